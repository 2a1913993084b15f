// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DepthSensor.h
 * @brief A depth camera as real sensors are: its published resolution, field of view and range,
 *        the depth noise that grows with distance and with the incidence angle, the steps its
 *        depth comes in, and no return at grazing angles; and a z-buffer rendering of a
 *        triangle mesh through it (what the camera would see, before any of those errors).
 *
 * The sensors (depthSensorModel(); Documentation/Formats.md, *Simulated depth sensors*, cites
 * each figure): Kinect v1 (structured light; noise after Nguyen, Izadi & Lovell 2012), Kinect v2
 * (time of flight; Fankhauser et al. 2015), Azure Kinect in its narrow unbinned mode (Microsoft's
 * hardware specification for the stream; its noise given as a bound only, so Kinect v2's measured
 * model, the same principle), RealSense D415 and D435 (active stereo; Intel's RMS formula,
 * subpixel 0.08). Axial noise, in metres, of depth z (metres) at incidence theta (radians):
 *
 *   sigma(z, theta) = c0 + c1 z + c2 z^2 + angular z^angularPower theta^2 / (pi/2 - theta)^2
 *
 * lateral noise, in pixels: lateral + lateralAngular theta / (pi/2 - theta). Depth is reported
 * in steps of depthUnit; a triangulating sensor's (structured light, stereo) as a disparity
 * focalBaseline / z in steps of disparityStep pixels, so its steps grow as z^2.
 *
 * Limits: no multipath, no motion blur, no sunlight; the grazing limit, the share of mixed
 * pixels and the dark-surface dropouts are practitioners' figures, not measured ones (none is
 * published).
 */
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace dp
{

struct DepthSensorModel
{
  std::string name;
  int width = 0, height = 0;
  double horizontalFov = 0, verticalFov = 0; // degrees
  double nearRange = 0, farRange = 0;        // metres
  double c0 = 0, c1 = 0, c2 = 0, angular = 0, angularPower = 0;
  double lateral = 0, lateralAngular = 0;
  double depthUnit = 0.001, focalBaseline = 0, disparityStep = 0;
  double grazingLimit = 75; // degrees of incidence beyond which nothing returns
  double mixedPixels = 0;   // share of silhouette pixels mixing the surface with what is behind
  double darkDropout = 0;   // share of returns lost on a black surface (fewer on brighter ones)

  /** sigma(z, theta) in metres. */
  double axialNoise(double z, double theta) const;
  /** Lateral noise in pixels at incidence theta. */
  double lateralNoise(double theta) const;
  /** z as the sensor reports it: on its disparity steps, then in its depth unit. */
  double quantised(double z) const;
  /** The focal length in pixels, from the width and the horizontal field of view. */
  double focalPixels() const;
};

/** kinect-v1, kinect-v2, azure-kinect, d415 or d435; std::invalid_argument naming the choices
 *  for another name. */
DepthSensorModel depthSensorModel(const std::string& name);
std::vector<std::string> depthSensorNames();

/** A pinhole camera: camera to world x = rotation p + translation (rotation row-major); it looks
 *  along its +z with its image's y down. */
struct DepthCamera
{
  std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::array<double, 3> translation{0, 0, 0};
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;

  /** A camera of the sensor's intrinsics at `eye` looking at `target`, `up` its image's up. */
  static DepthCamera lookingAt(const DepthSensorModel& sensor, const double eye[3],
                               const double target[3], const double up[3]);
  /** World to camera. */
  void toCamera(const double world[3], double camera[3]) const;
  /** Camera to world. */
  void toWorld(const double camera[3], double world[3]) const;
};

/** What a camera sees at each pixel (row-major): the depth along its axis (0: nothing), the
 *  nearest triangle, and that triangle's barycentric coordinates of the point (the first two;
 *  perspective-correct). */
struct DepthImage
{
  int width = 0, height = 0;
  std::vector<float> depth;
  std::vector<std::int32_t> triangle;
  std::vector<std::array<float, 2>> barycentric;
};

/** Renders the triangles (x y z per vertex in the world) through the camera with a z-buffer;
 *  triangles reaching behind the camera's near plane (1 cm) are left out. */
DepthImage renderDepth(const DepthCamera& camera, const std::vector<double>& positions,
                       const std::vector<std::int64_t>& triangles);

} // namespace dp
