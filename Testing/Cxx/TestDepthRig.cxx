// SPDX-License-Identifier: BSD-3-Clause
// The simulated depth sensors (DepthSensor.h) and rig (DepthRig.h): each error they make
// measured against the parameter that sets it, on planes and spheres whose truth is exact.
#include "dp/geometry/DepthRig.h"
#include "dp/geometry/DepthSensor.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <utility>

namespace
{

constexpr double Pi = 3.141592653589793;

// A mesh that holds still: the same positions every frame.
class StillMesh : public dp::AnimatedMesh
{
public:
  StillMesh(std::vector<double> positions, std::vector<std::int64_t> triangles, std::size_t frames)
      : Positions(std::move(positions)), Triangles(std::move(triangles)), Frames(frames)
  {
  }
  std::size_t numberOfFrames() const override { return Frames; }
  std::size_t numberOfVertices() const override { return Positions.size() / 3; }
  const std::vector<std::int64_t>& triangles() const override { return Triangles; }
  std::vector<double> positions(std::size_t) const override { return Positions; }

private:
  std::vector<double> Positions;
  std::vector<std::int64_t> Triangles;
  std::size_t Frames;
};

// A square of side `side` centred at the origin, normal `normal` (unit, across y), its edges
// along y and along normal x y: a grid of n x n cells.
StillMesh square(double side, const double normal[3], int n = 20)
{
  const double up[3] = {0, 1, 0};
  const double across[3] = {up[1] * normal[2] - up[2] * normal[1],
                            up[2] * normal[0] - up[0] * normal[2],
                            up[0] * normal[1] - up[1] * normal[0]};
  std::vector<double> p;
  std::vector<std::int64_t> t;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
    {
      const double a = side * (static_cast<double>(i) / n - 0.5);
      const double b = side * (static_cast<double>(j) / n - 0.5);
      for (int d = 0; d < 3; ++d)
        p.push_back(a * across[d] + b * up[d]);
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
    {
      const std::int64_t v = j * (n + 1) + i;
      t.insert(t.end(), {v, v + 1, v + n + 2, v, v + n + 2, v + n + 1});
    }
  return StillMesh(p, t, 2);
}

// A sphere of `radius` at the origin (latitude-longitude grid).
StillMesh sphere(double radius, std::size_t frames = 2)
{
  const int rings = 40, segments = 80;
  std::vector<double> p;
  std::vector<std::int64_t> t;
  for (int r = 0; r <= rings; ++r)
    for (int s = 0; s < segments; ++s)
    {
      const double theta = Pi * r / rings, phi = 2 * Pi * s / segments;
      p.insert(p.end(), {radius * std::sin(theta) * std::cos(phi), radius * std::cos(theta),
                         radius * std::sin(theta) * std::sin(phi)});
    }
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s)
    {
      const std::int64_t a = r * segments + s, b = r * segments + (s + 1) % segments;
      t.insert(t.end(), {a, a + segments, b, b, a + segments, b + segments});
    }
  return StillMesh(p, t, frames);
}

// A rig of exact cameras (no pose error) at `distance` metres; the take in metres.
dp::RigOptions exactRig(std::size_t cameras, const std::string& sensor, double distance,
                        double height)
{
  dp::RigOptions o;
  o.cameras = cameras;
  o.sensor = sensor;
  o.distance = distance;
  o.subjectHeight = height;
  o.rotationError = 0;
  o.translationError = 0;
  return o;
}

std::array<double, 3> cameraPosition(const dp::DepthRig& rig, std::size_t k)
{
  const auto json = nlohmann::json::parse(rig.description());
  const auto t = json["cameras"][k]["believed"]["translation"];
  return {t[0].get<double>(), t[1].get<double>(), t[2].get<double>()};
}

double distanceTo(const double* p, const std::array<double, 3>& c)
{
  return std::sqrt((p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1]) +
                   (p[2] - c[2]) * (p[2] - c[2]));
}

} // namespace

// The published figures the models carry, at 2 m facing the sensor (the tables in
// Documentation/Formats.md): Kinect v1 6.1 mm (Nguyen et al.), Kinect v2 1.7 mm (Fankhauser et
// al.), D435 14.3 mm at 848 pixels (Intel's formula, subpixel 0.08).
TEST(DepthSensor, ModelsGiveThePublishedNoise)
{
  EXPECT_NEAR(dp::depthSensorModel("kinect-v1").axialNoise(2, 0), 6.1e-3, 0.1e-3);
  EXPECT_NEAR(dp::depthSensorModel("kinect-v2").axialNoise(2, 0), 1.7e-3, 0.05e-3);
  EXPECT_NEAR(dp::depthSensorModel("d435").axialNoise(2, 0), 14.3e-3, 0.3e-3);
  EXPECT_NEAR(dp::depthSensorModel("d415").axialNoise(2, 0), 5.8e-3, 0.2e-3);
  // Noise grows with distance and toward grazing incidence.
  for (const std::string& name : dp::depthSensorNames())
  {
    const dp::DepthSensorModel s = dp::depthSensorModel(name);
    EXPECT_LT(s.axialNoise(1.5, 0), s.axialNoise(3, 0)) << name;
    EXPECT_LE(s.axialNoise(2, 0.2), s.axialNoise(2, 1.3)) << name;
  }
  try
  {
    dp::depthSensorModel("kinect-v9");
    ADD_FAILURE();
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("kinect-v9"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("azure-kinect"), std::string::npos);
  }
}

// A plane facing a camera: the depths' spread across it is the model's noise at that distance
// and incidence, with the depth unit's rounding (variance step^2 / 12), within 10 %.
TEST(DepthRig, TheNoiseOnAPlaneIsTheModelsAtItsDistance)
{
  const double normal[3] = {0, 0, 1};
  for (const auto& [sensor, distance] :
       {std::pair{std::string("kinect-v2"), 1.5}, {"kinect-v2", 3.0}, {"d415", 2.0}})
  {
    const StillMesh plane = square(4, normal);
    const dp::DepthRig rig(plane, exactRig(1, sensor, distance, 4));
    const dp::PointCloud cloud = rig.fusedCloud(plane.positions(0), 0);
    const auto eye = cameraPosition(rig, 0);
    double sum2 = 0, expected2 = 0;
    std::size_t n = 0;
    for (std::size_t p = 0; p < cloud.numberOfPoints(); ++p)
    {
      const double* x = &cloud.points[3 * p];
      if (std::abs(x[0]) > 0.15 || std::abs(x[1] - eye[1]) > 0.15)
        continue; // the patch straight ahead
      const double range = distanceTo(x, eye), cosine = std::min(1.0, (eye[2] - x[2]) / range);
      const double z = range * cosine; // depth along the camera's axis (it looks along -z)
      const dp::DepthSensorModel& s = rig.sensor();
      const double sigma = s.axialNoise(z, std::acos(cosine));
      const double disparityStep =
          s.focalBaseline > 0 ? z * z / s.focalBaseline * s.disparityStep : 0;
      // Along the ray, seen across the plane.
      sum2 += x[2] * x[2];
      expected2 +=
          (sigma * sigma + (s.depthUnit * s.depthUnit + disparityStep * disparityStep) / 12) *
          cosine * cosine;
      ++n;
    }
    ASSERT_GT(n, 500u) << sensor;
    const double measured = std::sqrt(sum2 / n), expected = std::sqrt(expected2 / n);
    EXPECT_NEAR(measured / expected, 1.0, 0.1)
        << sensor << " at " << distance << " m: " << measured * 1e3 << " mm, model "
        << expected * 1e3 << " mm";
  }
}

// Kinect v1 reports disparity in eighths of a pixel: at 2.5 m its depths come in steps of
// z^2 / (f b) / 8, about 18 mm, far coarser than the millimetre it writes them in.
TEST(DepthRig, AStructuredLightSensorsDepthsComeInDisparitySteps)
{
  const double normal[3] = {0, 0, 1};
  const StillMesh plane = square(4, normal);
  const dp::DepthRig rig(plane, exactRig(1, "kinect-v1", 2.5, 4));
  const dp::PointCloud cloud = rig.fusedCloud(plane.positions(0), 0);
  const auto eye = cameraPosition(rig, 0);
  const double length = std::sqrt(eye[0] * eye[0] + eye[1] * eye[1] + eye[2] * eye[2]);
  std::set<long> steps; // depths along the camera's axis (toward the origin), in 0.1 mm
  for (std::size_t p = 0; p < cloud.numberOfPoints(); ++p)
  {
    const double* x = &cloud.points[3 * p];
    const double depth =
        -((x[0] - eye[0]) * eye[0] + (x[1] - eye[1]) * eye[1] + (x[2] - eye[2]) * eye[2]) / length;
    steps.insert(std::lround(1e4 * depth));
  }
  ASSERT_GT(steps.size(), 5u);
  // Between neighbouring depths reported near 2.5 m, at least most of a disparity step.
  const dp::DepthSensorModel& s = rig.sensor();
  const double step = 2.5 * 2.5 / s.focalBaseline * s.disparityStep;
  EXPECT_NEAR(step, 0.018, 0.001);
  std::vector<long> sorted(steps.begin(), steps.end());
  std::size_t near = 0, fine = 0;
  for (std::size_t i = 1; i < sorted.size(); ++i)
    if (std::abs(sorted[i] * 1e-4 - 2.5) < 0.1)
    {
      ++near;
      fine += (sorted[i] - sorted[i - 1]) * 1e-4 < 0.5 * step;
    }
  EXPECT_GT(near, 2u);
  EXPECT_EQ(fine, 0u) << "depths closer than half a disparity step near 2.5 m";
}

// Beyond the sensor's grazing limit the surface returns nothing (but the flying pixels of its
// outline); well inside it, the surface is seen.
TEST(DepthRig, NothingReturnsAtGrazingIncidence)
{
  std::map<double, std::size_t> points;
  for (double degrees : {86.0, 40.0})
  {
    const double a = degrees * Pi / 180;
    const double normal[3] = {std::sin(a), 0, std::cos(a)};
    const StillMesh plane = square(1, normal);
    const dp::DepthRig rig(plane, exactRig(1, "kinect-v2", 1.5, 1));
    points[degrees] = rig.fusedCloud(plane.positions(0), 0).numberOfPoints();
  }
  EXPECT_GT(points[40.0], 5000u);
  EXPECT_LT(points[86.0], points[40.0] / 100);
}

// Time of flight mixes a silhouette pixel's surface with what lies behind: a ball in front of
// a wall gives flying pixels between the two, a small share of the cloud.
TEST(DepthRig, SilhouettesGiveFlyingPixelsBetweenASurfaceAndWhatIsBehind)
{
  const double normal[3] = {0, 0, 1};
  const StillMesh wall = square(1.5, normal);
  const StillMesh ball = sphere(0.2);
  std::vector<double> p = wall.positions(0);
  std::vector<std::int64_t> t = wall.triangles();
  const auto offset = static_cast<std::int64_t>(p.size() / 3);
  const std::vector<double> b = ball.positions(0);
  for (std::size_t i = 0; i < b.size(); ++i)
    p.push_back(b[i] + (i % 3 == 2 ? 0.5 : 0.0));
  for (std::int64_t v : ball.triangles())
    t.push_back(v + offset);
  const StillMesh scene(p, t, 2);
  const dp::DepthRig rig(scene, exactRig(1, "kinect-v2", 2.0, 1.5));
  const dp::PointCloud cloud = rig.fusedCloud(scene.positions(0), 0);
  std::size_t flying = 0;
  for (std::size_t i = 0; i < cloud.numberOfPoints(); ++i)
  {
    const double* x = &cloud.points[3 * i];
    const double toBall =
        std::abs(std::sqrt(x[0] * x[0] + x[1] * x[1] + (x[2] - 0.5) * (x[2] - 0.5)) - 0.2);
    flying += toBall > 0.02 && std::abs(x[2]) > 0.02;
  }
  const double share = static_cast<double>(flying) / cloud.numberOfPoints();
  EXPECT_GT(flying, 20u);
  EXPECT_LT(share, 0.02);
}

// Each camera's pose error moves its whole view: the fused surfaces stack into a layer. Exact
// cameras leave the noise alone.
TEST(DepthRig, PoseErrorsStackTheCamerasSurfacesIntoALayer)
{
  const StillMesh ball = sphere(0.3);
  const auto radialRms = [&](double rotation, double translation)
  {
    dp::RigOptions o = exactRig(4, "kinect-v2", 2.0, 0.6);
    o.rotationError = rotation;
    o.translationError = translation;
    const dp::DepthRig rig(ball, o);
    const dp::PointCloud cloud = rig.fusedCloud(ball.positions(0), 0);
    std::vector<double> r;
    for (std::size_t p = 0; p < cloud.numberOfPoints(); ++p)
    {
      const double* x = &cloud.points[3 * p];
      r.push_back(std::abs(std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) - 0.3));
    }
    std::sort(r.begin(), r.end()); // the median: flying pixels left out
    return r[r.size() / 2];
  };
  const double exact = radialRms(0, 0), layered = radialRms(0.3, 0.005);
  EXPECT_LT(exact, 0.0025);
  EXPECT_GT(layered, 2 * exact) << exact << " " << layered;
}

// A single sensor's depth image as an open mesh: manifold, a boundary, no triangle across a
// depth jump, every vertex used.
TEST(DepthRig, ADepthMeshIsOpenManifoldAndSpansNoJump)
{
  const StillMesh ball = sphere(0.3);
  dp::RigOptions o = exactRig(1, "azure-kinect", 1.5, 0.6);
  o.meshJump = 0.03;
  const dp::DepthRig rig(ball, o);
  const dp::PointCloud mesh = rig.depthMesh(ball.positions(0), 0, 0);
  ASSERT_GT(mesh.numberOfFaces(), 1000u);
  std::map<std::pair<std::int64_t, std::int64_t>, int> edges;
  std::vector<char> used(mesh.numberOfPoints(), 0);
  const auto eye = cameraPosition(rig, 0);
  double longest = 0;
  for (std::size_t f = 0; f < mesh.numberOfFaces(); ++f)
  {
    ASSERT_EQ(mesh.faceOffsets[f + 1] - mesh.faceOffsets[f], 3);
    const std::int64_t* v = &mesh.faceConnectivity[static_cast<std::size_t>(mesh.faceOffsets[f])];
    for (int k = 0; k < 3; ++k)
    {
      const std::int64_t a = v[k], b = v[(k + 1) % 3];
      ++edges[{std::min(a, b), std::max(a, b)}];
      used[static_cast<std::size_t>(a)] = 1;
      const double da = distanceTo(&mesh.points[3 * a], eye);
      const double db = distanceTo(&mesh.points[3 * b], eye);
      longest = std::max(longest, std::abs(da - db));
    }
  }
  std::size_t boundary = 0;
  for (const auto& [edge, count] : edges)
  {
    EXPECT_LE(count, 2);
    boundary += count == 1;
  }
  EXPECT_GT(boundary, 100u);
  EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0);
  EXPECT_LT(longest, 0.03 + 0.01); // the jump, and the lateral noise along the ray
}

// A frame's errors depend on the seed and the frame alone; the take's units scale the cloud
// and nothing else (the same take in centimetres gives the same cloud times 100).
TEST(DepthRig, TheSameSeedGivesTheSameCloudInAnyUnit)
{
  const StillMesh ball = sphere(0.3, 5);
  const dp::RigOptions o = exactRig(3, "kinect-v2", 2.0, 0.6);
  const dp::PointCloud a = dp::DepthRig(ball, o).fusedCloud(ball.positions(3), 3);
  const dp::PointCloud b = dp::DepthRig(ball, o).fusedCloud(ball.positions(3), 3);
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.colors, b.colors);
  EXPECT_NE(a.points, dp::DepthRig(ball, o).fusedCloud(ball.positions(4), 4).points);
  std::vector<double> centimetres = ball.positions(0);
  for (double& v : centimetres)
    v *= 100;
  const StillMesh scaled(centimetres, ball.triangles(), 5);
  const dp::PointCloud c = dp::DepthRig(scaled, o).fusedCloud(scaled.positions(3), 3);
  ASSERT_EQ(c.points.size(), a.points.size());
  for (std::size_t i = 0; i < a.points.size(); ++i)
    ASSERT_NEAR(c.points[i], 100 * a.points[i], 1e-9 * 100) << i;
  EXPECT_EQ(c.colors, a.colors);
}

TEST(DepthRig, AbsurdOptionsAreRefused)
{
  const StillMesh ball = sphere(0.3);
  dp::RigOptions o;
  o.cameras = 0;
  EXPECT_THROW(dp::DepthRig(ball, o), std::invalid_argument);
  o = dp::RigOptions{};
  o.up = "w";
  EXPECT_THROW(dp::DepthRig(ball, o), std::invalid_argument);
  o = dp::RigOptions{};
  o.subjectHeight = -1;
  EXPECT_THROW(dp::DepthRig(ball, o), std::invalid_argument);
}
