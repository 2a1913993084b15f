// SPDX-License-Identifier: BSD-3-Clause
// Depth sensors' published figures and a z-buffer rendering through one (DepthSensor.h).
#include "dp/geometry/DepthSensor.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace dp
{

namespace
{

constexpr double Pi = 3.141592653589793;

double radians(double degrees)
{
  return degrees * Pi / 180.0;
}

// The time-of-flight noise Fankhauser et al. (2015) measured on Kinect v2, in metres:
// 1.5 - 0.5 z + 0.3 z^2 mm, and 0.1 z^1.5 theta^2/(pi/2 - theta)^2 mm at incidence theta.
void fankhauserNoise(DepthSensorModel& s)
{
  s.c0 = 1.5e-3;
  s.c1 = -0.5e-3;
  s.c2 = 0.3e-3;
  s.angular = 0.1e-3;
  s.angularPower = 1.5;
  s.lateral = 0.5;
  s.mixedPixels = 0.3; // time of flight mixes what an edge pixel sees (flying pixels)
  s.darkDropout = 0.5;
}

// Active stereo (Intel): RMS = z^2 subpixel / (f B), subpixel 0.08; disparity in 1/32 pixel.
void stereoNoise(DepthSensorModel& s, double baseline)
{
  const double focalBaseline = s.focalPixels() * baseline;
  s.c2 = 0.08 / focalBaseline;
  s.lateral = 0.5;
  s.focalBaseline = focalBaseline;
  s.disparityStep = 1.0 / 32.0;
  s.mixedPixels = 0.1; // stereo loses most edge pixels instead
  s.darkDropout = 0.7; // dark and glossy surfaces give no texture to match
}

DepthSensorModel kinectV1()
{
  DepthSensorModel s;
  s.name = "kinect-v1";
  s.width = 640;
  s.height = 480;
  s.horizontalFov = 57;
  s.verticalFov = 43;
  s.nearRange = 0.8;
  s.farRange = 4.0;
  // Nguyen, Izadi & Lovell (2012): 0.0012 + 0.0019 (z - 0.4)^2, and
  // 0.0001 / sqrt(z) theta^2 / (pi/2 - theta)^2; lateral 0.8 + 0.035 theta / (pi/2 - theta) px.
  s.c0 = 0.0012 + 0.0019 * 0.16;
  s.c1 = -0.0019 * 0.8;
  s.c2 = 0.0019;
  s.angular = 0.0001;
  s.angularPower = -0.5;
  s.lateral = 0.8;
  s.lateralAngular = 0.035;
  s.focalBaseline = 580.0 * 0.075; // disparity in 1/8 pixel over a 7.5 cm baseline
  s.disparityStep = 1.0 / 8.0;
  s.mixedPixels = 0.1;
  s.darkDropout = 0.5;
  return s;
}

DepthSensorModel kinectV2()
{
  DepthSensorModel s;
  s.name = "kinect-v2";
  s.width = 512;
  s.height = 424;
  s.horizontalFov = 70.6;
  s.verticalFov = 60;
  s.nearRange = 0.5;
  s.farRange = 4.5;
  fankhauserNoise(s);
  return s;
}

DepthSensorModel azureKinect()
{
  DepthSensorModel s;
  s.name = "azure-kinect";
  s.width = 640; // narrow field of view, unbinned
  s.height = 576;
  s.horizontalFov = 75;
  s.verticalFov = 65;
  s.nearRange = 0.5;
  s.farRange = 3.86;
  fankhauserNoise(s);
  return s;
}

DepthSensorModel realSense(const std::string& name)
{
  DepthSensorModel s;
  s.name = name;
  s.nearRange = 0.3;
  s.farRange = 10;
  if (name == "d415")
  {
    s.width = 1280;
    s.height = 720;
    s.horizontalFov = 65;
    s.verticalFov = 40;
    stereoNoise(s, 0.055);
  }
  else
  {
    s.width = 848; // its best depth resolution
    s.height = 480;
    s.horizontalFov = 87;
    s.verticalFov = 58;
    stereoNoise(s, 0.050);
  }
  return s;
}

} // namespace

double DepthSensorModel::axialNoise(double z, double theta) const
{
  const double t = std::min(theta, radians(89.0));
  const double grazing = t * t / ((Pi / 2 - t) * (Pi / 2 - t));
  return std::max(0.0, c0 + c1 * z + c2 * z * z) + angular * std::pow(z, angularPower) * grazing;
}

double DepthSensorModel::lateralNoise(double theta) const
{
  const double t = std::min(theta, radians(89.0));
  return lateral + lateralAngular * t / (Pi / 2 - t);
}

double DepthSensorModel::quantised(double z) const
{
  if (disparityStep > 0 && focalBaseline > 0)
  {
    const double disparity = std::round(focalBaseline / z / disparityStep) * disparityStep;
    z = disparity > 0 ? focalBaseline / disparity : farRange;
  }
  return depthUnit > 0 ? std::round(z / depthUnit) * depthUnit : z;
}

double DepthSensorModel::focalPixels() const
{
  return 0.5 * width / std::tan(radians(horizontalFov) / 2);
}

std::vector<std::string> depthSensorNames()
{
  return {"kinect-v1", "kinect-v2", "azure-kinect", "d415", "d435"};
}

DepthSensorModel depthSensorModel(const std::string& name)
{
  if (name == "kinect-v1")
    return kinectV1();
  if (name == "kinect-v2")
    return kinectV2();
  if (name == "azure-kinect")
    return azureKinect();
  if (name == "d415" || name == "d435")
    return realSense(name);
  std::string known;
  for (const std::string& n : depthSensorNames())
    known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown depth sensor '" + name + "' (known: " + known + ")");
}

DepthCamera DepthCamera::lookingAt(const DepthSensorModel& sensor, const double eye[3],
                                   const double target[3], const double up[3])
{
  // Columns of the rotation: the camera's x (right), y (down) and z (forward) in the world.
  double forward[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
  const auto normalise = [](double v[3])
  {
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(n > 0))
      throw std::invalid_argument("a camera's eye, target and up must span a frame");
    for (int i = 0; i < 3; ++i)
      v[i] /= n;
  };
  normalise(forward);
  double right[3] = {forward[1] * up[2] - forward[2] * up[1],
                     forward[2] * up[0] - forward[0] * up[2],
                     forward[0] * up[1] - forward[1] * up[0]};
  normalise(right);
  const double down[3] = {forward[1] * right[2] - forward[2] * right[1],
                          forward[2] * right[0] - forward[0] * right[2],
                          forward[0] * right[1] - forward[1] * right[0]};
  DepthCamera c;
  for (int i = 0; i < 3; ++i)
  {
    c.rotation[3 * i + 0] = right[i];
    c.rotation[3 * i + 1] = down[i];
    c.rotation[3 * i + 2] = forward[i];
    c.translation[i] = eye[i];
  }
  c.width = sensor.width;
  c.height = sensor.height;
  c.fx = sensor.focalPixels();
  c.fy = 0.5 * sensor.height / std::tan(radians(sensor.verticalFov) / 2);
  c.cx = 0.5 * sensor.width;
  c.cy = 0.5 * sensor.height;
  return c;
}

void DepthCamera::toCamera(const double world[3], double camera[3]) const
{
  const double d[3] = {world[0] - translation[0], world[1] - translation[1],
                       world[2] - translation[2]};
  for (int j = 0; j < 3; ++j)
    camera[j] = rotation[j] * d[0] + rotation[3 + j] * d[1] + rotation[6 + j] * d[2];
}

void DepthCamera::toWorld(const double camera[3], double world[3]) const
{
  for (int i = 0; i < 3; ++i)
    world[i] = rotation[3 * i] * camera[0] + rotation[3 * i + 1] * camera[1] +
               rotation[3 * i + 2] * camera[2] + translation[i];
}

namespace
{

// A triangle projected: pixel coordinates and camera depths of its corners.
struct Projected
{
  double u[3], v[3], z[3];
};

// Draws one triangle into the image: at each pixel centre inside it, the perspective-correct
// depth, kept where nearer than what is there.
void rasterise(const Projected& p, std::int32_t id, DepthImage& image)
{
  const double area = (p.u[1] - p.u[0]) * (p.v[2] - p.v[0]) - (p.u[2] - p.u[0]) * (p.v[1] - p.v[0]);
  if (!(std::abs(area) > 1e-12))
    return;
  const int x0 = std::max(0, static_cast<int>(std::floor(std::min({p.u[0], p.u[1], p.u[2]}))));
  const int x1 =
      std::min(image.width - 1, static_cast<int>(std::ceil(std::max({p.u[0], p.u[1], p.u[2]}))));
  const int y0 = std::max(0, static_cast<int>(std::floor(std::min({p.v[0], p.v[1], p.v[2]}))));
  const int y1 =
      std::min(image.height - 1, static_cast<int>(std::ceil(std::max({p.v[0], p.v[1], p.v[2]}))));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x)
    {
      const double px = x + 0.5, py = y + 0.5;
      double w[3];
      for (int k = 0; k < 3; ++k)
      {
        const int a = (k + 1) % 3, b = (k + 2) % 3;
        w[k] = ((p.u[b] - p.u[a]) * (py - p.v[a]) - (p.v[b] - p.v[a]) * (px - p.u[a])) / area;
      }
      if (w[0] < 0 || w[1] < 0 || w[2] < 0)
        continue;
      const double inverse = w[0] / p.z[0] + w[1] / p.z[1] + w[2] / p.z[2];
      const double z = 1.0 / inverse;
      const std::size_t i = static_cast<std::size_t>(y) * image.width + x;
      if (image.depth[i] != 0 && image.depth[i] <= z)
        continue;
      image.depth[i] = static_cast<float>(z);
      image.triangle[i] = id;
      image.barycentric[i] = {static_cast<float>(w[0] / p.z[0] * z),
                              static_cast<float>(w[1] / p.z[1] * z)};
    }
}

} // namespace

DepthImage renderDepth(const DepthCamera& camera, const std::vector<double>& positions,
                       const std::vector<std::int64_t>& triangles)
{
  DepthImage image;
  image.width = camera.width;
  image.height = camera.height;
  const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
  image.depth.assign(pixels, 0.0f);
  image.triangle.assign(pixels, -1);
  image.barycentric.assign(pixels, {0.0f, 0.0f});
  std::vector<double> local(positions.size());
  for (std::size_t v = 0; v + 2 < positions.size(); v += 3)
    camera.toCamera(&positions[v], &local[v]);
  const std::size_t vertices = positions.size() / 3;
  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3)
  {
    Projected p;
    bool visible = true;
    for (int k = 0; k < 3 && visible; ++k)
    {
      const auto v = static_cast<std::size_t>(triangles[t + k]);
      if (triangles[t + k] < 0 || v >= vertices)
        throw std::invalid_argument("a triangle's vertex index is out of range");
      const double* c = &local[3 * v];
      visible = c[2] > 0.01;
      p.z[k] = c[2];
      p.u[k] = camera.fx * c[0] / c[2] + camera.cx;
      p.v[k] = camera.fy * c[1] / c[2] + camera.cy;
    }
    if (visible)
      rasterise(p, static_cast<std::int32_t>(t / 3), image);
  }
  return image;
}

} // namespace dp
