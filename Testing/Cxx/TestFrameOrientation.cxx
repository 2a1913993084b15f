// SPDX-License-Identifier: BSD-3-Clause
// FrameOrientation: a frame's normals turned to face the way the tracked shape does. Points of
// spheres, whose outward direction is known in closed form: given normals all inward are turned,
// outward ones kept bit for bit; estimated normals come out outward part by part; a part the
// shape does not reach keeps its orientation.
#include "FineMeshShapes.h"

#include "dp/geometry/TriangleMesh.h"
#include "dp/track/FrameData.h"
#include "dp/track/FrameOrientation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

namespace
{

struct Sphere
{
  double centre[3];
  double radius;
};

// `count` points on each sphere with their outward unit normals (or inward when `inward`).
void sample(const std::vector<Sphere>& spheres, std::size_t count, bool inward,
            std::vector<double>& points, std::vector<float>& normals)
{
  std::mt19937_64 rng(6);
  std::normal_distribution<double> g(0, 1);
  for (const Sphere& s : spheres)
    for (std::size_t i = 0; i < count; ++i)
    {
      double d[3] = {g(rng), g(rng), g(rng)};
      const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      for (int k = 0; k < 3; ++k)
      {
        points.push_back(s.centre[k] + s.radius * d[k] / length);
        normals.push_back(static_cast<float>((inward ? -1 : 1) * d[k] / length));
      }
    }
}

// The icospheres of 642 vertices on the spheres, as one mesh.
dp::test::Mesh meshOf(const std::vector<Sphere>& spheres)
{
  dp::test::Mesh all;
  for (const Sphere& s : spheres)
  {
    const dp::test::Mesh m = dp::test::icosphere(3);
    const auto first = static_cast<std::int64_t>(all.vertices());
    for (std::size_t i = 0; i < m.positions.size(); ++i)
      all.positions.push_back(s.centre[i % 3] + s.radius * m.positions[i]);
    for (const std::int64_t v : m.triangles)
      all.triangles.push_back(first + v);
  }
  return all;
}

std::unique_ptr<dp::FrameData> frameOf(const std::vector<double>& points, const float* normals)
{
  dp::FrameDataOptions o;
  o.voxelSize = 0.02;
  o.surfaceArea = 2.0;
  o.spreadCount = 800;
  return std::make_unique<dp::FrameData>(points.data(), points.size() / 3, normals, o);
}

// Per point of the frame: +1 when its normal points out of the sphere it lies on, else -1.
std::vector<int> facing(const dp::FrameData& frame, const std::vector<Sphere>& spheres)
{
  std::vector<int> out;
  for (std::size_t i = 0; i < frame.size(); ++i)
  {
    const double* p = frame.point(i);
    const Sphere* on = &spheres[0];
    for (const Sphere& s : spheres)
      if (std::abs(std::hypot(p[0] - s.centre[0], p[1] - s.centre[1], p[2] - s.centre[2]) -
                   s.radius) < 1e-9)
        on = &s;
    double along = 0;
    for (int k = 0; k < 3; ++k)
      along += frame.normal(i)[k] * (p[k] - on->centre[k]);
    out.push_back(along > 0 ? 1 : -1);
  }
  return out;
}

TEST(FrameOrientation, GivenNormalsFacingInAreTurnedOutAndOutwardOnesKept)
{
  const std::vector<Sphere> ball = {{{0, 0, 0}, 0.5}};
  const dp::test::Mesh mesh = meshOf(ball);
  const dp::TriangleMesh triangles(mesh.triangles, mesh.vertices());
  for (const bool inward : {true, false})
  {
    std::vector<double> points;
    std::vector<float> normals;
    sample(ball, 3000, inward, points, normals);
    const std::unique_ptr<dp::FrameData> frame = frameOf(points, normals.data());
    const std::vector<float> before(frame->normals(), frame->normals() + 3 * frame->size());
    dp::orientToShape(*frame, triangles, mesh.positions, 0.02);
    EXPECT_EQ(facing(*frame, ball), std::vector<int>(frame->size(), 1)) << "inward " << inward;
    if (!inward)
    {
      EXPECT_EQ(std::vector<float>(frame->normals(), frame->normals() + 3 * frame->size()), before);
    }
  }
}

TEST(FrameOrientation, EstimatedNormalsFaceOutPartByPart)
{
  // Two balls apart: two parts of the estimated orientation, the first made to face in.
  const std::vector<Sphere> balls = {{{-1, 0, 0}, 0.4}, {{1, 0.2, 0}, 0.3}};
  std::vector<double> points;
  std::vector<float> normals;
  sample(balls, 3000, false, points, normals);
  const std::unique_ptr<dp::FrameData> frame = frameOf(points, nullptr);
  ASSERT_GE(frame->numberOfParts(), 2u);
  std::vector<int> before = facing(*frame, balls);
  long firstPart = 0;
  for (std::size_t i = 0; i < frame->size(); ++i)
    if (frame->part(i) == frame->part(0))
      firstPart += before[i];
  if (firstPart > 0)
    frame->flipNormals(frame->part(0));
  before = facing(*frame, balls);
  EXPECT_NE(before, std::vector<int>(frame->size(), 1));
  const dp::test::Mesh mesh = meshOf(balls);
  const dp::TriangleMesh triangles(mesh.triangles, mesh.vertices());
  dp::orientToShape(*frame, triangles, mesh.positions, 0.02);
  EXPECT_EQ(facing(*frame, balls), std::vector<int>(frame->size(), 1));
}

TEST(FrameOrientation, GivenNormalsTurnAsOneAndAnUnreachedPartKeepsItsOwn)
{
  // Both balls' normals given inward; the shape covers the first ball only: the first ball's
  // normals turn out, the second's (no surface near them) stay as given.
  const std::vector<Sphere> balls = {{{-1, 0, 0}, 0.4}, {{1, 0.2, 0}, 0.3}};
  std::vector<double> points;
  std::vector<float> normals;
  sample(balls, 3000, true, points, normals);
  const std::unique_ptr<dp::FrameData> frame = frameOf(points, normals.data());
  const dp::test::Mesh mesh = meshOf({balls[0]});
  const dp::TriangleMesh triangles(mesh.triangles, mesh.vertices());
  dp::orientToShape(*frame, triangles, mesh.positions, 0.02);
  // Normals given are one part: the first ball's votes turn them all. Estimated normals are
  // parts of their own: only the reached one turns.
  EXPECT_EQ(facing(*frame, balls), std::vector<int>(frame->size(), 1));

  const std::unique_ptr<dp::FrameData> estimated = frameOf(points, nullptr);
  ASSERT_GE(estimated->numberOfParts(), 2u);
  // Each part made to face in.
  std::vector<int> f = facing(*estimated, balls);
  std::vector<long> sum(estimated->numberOfParts(), 0);
  for (std::size_t i = 0; i < estimated->size(); ++i)
    sum[estimated->part(i)] += f[i];
  for (std::uint32_t part = 0; part < sum.size(); ++part)
    if (sum[part] > 0)
      estimated->flipNormals(part);
  f = facing(*estimated, balls);
  dp::orientToShape(*estimated, triangles, mesh.positions, 0.02);
  const std::vector<int> after = facing(*estimated, balls);
  std::size_t first = 0, second = 0;
  for (std::size_t i = 0; i < estimated->size(); ++i)
  {
    const bool onFirst = estimated->point(i)[0] < 0;
    if (onFirst)
    {
      EXPECT_EQ(after[i], 1) << "point " << i;
      ++first;
    }
    else
    {
      EXPECT_EQ(after[i], f[i]) << "point " << i;
      EXPECT_EQ(after[i], -1) << "point " << i;
      ++second;
    }
  }
  EXPECT_GT(first, 0u);
  EXPECT_GT(second, 0u);
}

} // namespace
