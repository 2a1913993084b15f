// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DepthRig.h
 * @brief A rig of N depth cameras around an animated mesh, seeing it as real sensors do, with
 *        the truth known: what `dynamicpoints-sample --rig N` writes.
 *
 * The cameras (one sensor model, DepthSensor.h) stand on a circle around the take's centre, at
 * the distance where the whole take fills the view; with six or more, in two rings (low and
 * high), as capture rigs are built. Each camera renders the frame (z-buffer), then makes a real
 * sensor's errors: no return beyond its grazing angle (and fewer on dark surfaces), mixed
 * pixels at silhouettes (depth between the surface and what is behind it: flying pixels),
 * axial and lateral noise that grow with distance and incidence, depth in the sensor's steps.
 * Each camera's points are taken to the world by where the rig *believes* the camera is, while
 * it saw from a pose off by a small rotation and translation: the cameras' surfaces stack into a
 * layer a few millimetres thick, as a calibrated rig's do. Normals come from the noisy depth
 * image's neighbours (as capture tools estimate them), colour from the material pattern
 * (materialColour()) shaded by the incidence and each camera's own gain per channel.
 *
 * Outputs: the fused cloud of a frame (every camera's points inside the capture volume, the
 * take's bounding box with a margin, optionally thinned), or one camera's depth image
 * triangulated into an open mesh as single-sensor capture tools export it (neighbouring pixels'
 * quads, none across a depth jump). Units: the take's; `subjectHeight` says how many metres the
 * subject's extent along `up` in frame 0 is, which sets the sensor's scale.
 *
 * Determinism: a frame's errors depend on (seed, frame, camera) alone.
 */
#pragma once

#include "dp/geometry/DepthSensor.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/io/PointCloud.h"

#include <cstdint>
#include <string>
#include <vector>

namespace dp
{

struct SequenceWriteOptions;

struct RigOptions
{
  std::size_t cameras = 4;
  std::string sensor = "kinect-v2";
  double subjectHeight = 1.7;      // metres: the subject's extent along `up` in frame 0
  std::string up = "y";            // x, y, z, -x, -y or -z
  double distance = 0;             // metres from the take's centre; 0: the take fills the view
  double azimuth = 0;              // degrees around `up`: camera 0's side of the subject
  double rotationError = 0.1;      // degrees: each camera's pose error, per axis (std. dev.)
  double translationError = 0.002; // metres, per axis (std. dev.)
  double colourGain = 0.05;        // each camera's gain per channel (std. dev. around 1)
  bool floor = false;              // a floor under the subject, seen where the volume reaches
  std::size_t points = 0;          // the fused cloud thinned to about this many (0: all)
  double meshJump = 0.05;          // metres: no depth-mesh triangle spans a larger depth step
  std::uint64_t seed = 1;
};

class DepthRig
{
public:
  /** The rig around `take` (its frames' bounding box, frame 0's extent for the scale). Throws
   *  std::invalid_argument for absurd options. */
  DepthRig(const AnimatedMesh& take, const RigOptions& options);

  /** Frame `frame` (its positions, the take's triangles) seen by every camera and fused: points
   *  in the take's units with normals and colours. */
  PointCloud fusedCloud(const std::vector<double>& positions, std::size_t frame) const;
  /** Camera `camera`'s depth image of the frame as an open triangle mesh. */
  PointCloud depthMesh(const std::vector<double>& positions, std::size_t camera,
                       std::size_t frame) const;

  std::size_t cameras() const { return Believed.size(); }
  const DepthSensorModel& sensor() const { return Sensor; }
  double metresPerUnit() const { return Scale; }
  /** The rig as JSON: sensor, scale, each camera's believed and true pose. */
  std::string description() const;

private:
  struct Capture; // one camera's points of one frame
  struct Surface  // what a pixel shows: the incidence's cosine, the material's colour
  {
    double cosine = 1;
    std::array<double, 3> albedo{};
  };
  void placeCameras(const double centre[3], double radius);
  void sceneOf(const std::vector<double>& positions, std::vector<double>& scene,
               std::vector<std::int64_t>& triangles) const;
  Surface surfaceAt(const DepthImage& image, std::size_t pixel, const std::vector<double>& scene,
                    const std::vector<std::int64_t>& triangles, const DepthCamera& camera,
                    const double ray[3]) const;
  double behindSilhouette(const DepthImage& image, int x, int y, double z) const;
  Capture capture(const std::vector<double>& positions, std::size_t camera,
                  std::size_t frame) const;
  static void estimateNormals(Capture& capture);
  PointCloud toWorld(Capture& capture, std::size_t camera) const;

  RigOptions Options;
  DepthSensorModel Sensor;
  std::vector<DepthCamera> Believed, Actual;
  std::vector<std::array<double, 3>> Gains;
  std::vector<std::int64_t> Triangles;
  std::vector<double> Rest; // frame 0, for the material's colour
  double RestDiagonal = 1, Scale = 1;
  double Up[3] = {0, 1, 0};
  double Box[6] = {0, 0, 0, 0, 0, 0}; // capture volume, take's units: min xyz, max xyz
  std::vector<double> FloorCorners;   // metres, 4 corners (empty: no floor)
  double FloorLevel = 0;              // metres along up
};

/** Every frame of `take` through the rig: `outDir/<prefix>NNNN.ply` the fused clouds, or with
 *  `depthMeshes` each camera's open mesh (one camera: in `outDir`; more: `outDir/camera_K/`,
 *  each with its points.series), plus `outDir/rig.json`, and the truth as `writing` asks.
 *  Returns the .series path (of camera 0 for depth meshes of several cameras). */
std::string writeRigSequence(const AnimatedMesh& take, const RigOptions& rig,
                             const std::string& outDir, const SequenceWriteOptions& writing,
                             bool depthMeshes);

} // namespace dp
