// SPDX-License-Identifier: BSD-3-Clause
// FrameSurface: where a line along a fine vertex's normal meets a frame's data. A plane, given as
// a mesh or as points, is met where the line's closed form says; a sphere's mesh where brute
// force intersects the line with its triangles; the normal test, the reach, the rim of a mesh
// and the spread of points refuse what they should; the orientation turns to agree with a mesh.
#include "FineMeshShapes.h"

#include "dp/detail/FrameSurface.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace
{

using dp::test::Mesh;

// A unit vector at `tilt` radians from +z, turned by `azimuth` about it.
std::vector<double> tilted(double tilt, double azimuth)
{
  return {std::sin(tilt) * std::cos(azimuth), std::sin(tilt) * std::sin(azimuth), std::cos(tilt)};
}

TEST(FrameSurface, AFlatMeshIsMetWhereTheLineCrossesItsPlane)
{
  // The unit square at z = 0 (faces up): from (x, y, h) along n the line meets it at s = -h / nz,
  // to the steps' tolerance (a thousandth of the reach).
  const Mesh plane = dp::test::grid(10);
  const dp::FrameSurface surface = dp::FrameSurface::ofMesh(plane.surface());
  EXPECT_EQ(surface.size(), plane.vertices());
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 200; ++i)
  {
    const double p[3] = {0.3 + 0.4 * u(rng), 0.3 + 0.4 * u(rng), 0.2 * u(rng) - 0.1};
    const std::vector<double> n = tilted(0.7 * u(rng), 6.3 * u(rng));
    const dp::FrameSurface::Crossing c = surface.cross(p, n.data(), 0.3, 0.5, 0.02);
    ASSERT_TRUE(c.found) << "point " << i;
    EXPECT_NEAR(c.distance, -p[2] / n[2], 1e-3 * 0.3);
    EXPECT_EQ(c.weight, 1.0);
  }
  // Along -z the surface faces away: refused by a normal test of 60 degrees, met without one.
  const double p[3] = {0.5, 0.5, 0.05}, down[3] = {0, 0, -1};
  EXPECT_FALSE(surface.cross(p, down, 0.3, 0.5, 0.02).found);
  const dp::FrameSurface::Crossing any = surface.cross(p, down, 0.3, -1, 0.02);
  ASSERT_TRUE(any.found);
  EXPECT_NEAR(any.distance, 0.05, 1e-12);
  // Farther than the reach; past the mesh's rim (on its plane, not on it); far from it.
  const double up[3] = {0, 0, 1};
  EXPECT_FALSE(surface.cross(p, up, 0.04, 0.5, 0.02).found);
  const double beyondRim[3] = {1.05, 0.5, 0.01};
  EXPECT_FALSE(surface.cross(beyondRim, up, 0.3, 0.5, 0.02).found);
  const double far[3] = {3, 0.5, 0.01};
  EXPECT_FALSE(surface.cross(far, up, 0.3, 0.5, 0.02).found);
}

// Where the line p + s n meets triangle (a, b, c), if it does (Moller-Trumbore).
bool lineMeetsTriangle(const double* p, const double* n, const double* a, const double* b,
                       const double* c, double& s)
{
  double e1[3], e2[3], q[3], t[3], r[3];
  for (int k = 0; k < 3; ++k)
  {
    e1[k] = b[k] - a[k];
    e2[k] = c[k] - a[k];
    t[k] = p[k] - a[k];
  }
  const auto cross = [](const double* x, const double* y, double* out)
  {
    out[0] = x[1] * y[2] - x[2] * y[1];
    out[1] = x[2] * y[0] - x[0] * y[2];
    out[2] = x[0] * y[1] - x[1] * y[0];
  };
  const auto dot = [](const double* x, const double* y)
  { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; };
  cross(n, e2, q);
  const double det = dot(e1, q);
  if (std::abs(det) < 1e-15)
    return false;
  const double beta = dot(t, q) / det;
  cross(t, e1, r);
  const double gamma = dot(n, r) / det;
  s = dot(e2, r) / det;
  return beta >= 0 && gamma >= 0 && beta + gamma <= 1;
}

TEST(FrameSurface, ASphereMeshIsMetWhereBruteForceIntersectsTheLine)
{
  // Points within 0.05 of the unit icosphere (642 vertices), lines tilted up to 20 degrees from
  // the outward radius: the nearest crossing of a triangle facing the line's way.
  const Mesh sphere = dp::test::icosphere(3);
  const dp::FrameSurface surface = dp::FrameSurface::ofMesh(sphere.surface());
  std::mt19937_64 rng(2);
  std::normal_distribution<double> g(0, 1);
  std::uniform_real_distribution<double> u(0, 1);
  const double reach = 0.2;
  for (int i = 0; i < 200; ++i)
  {
    double d[3] = {g(rng), g(rng), g(rng)};
    const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const double jitter[3] = {g(rng), g(rng), g(rng)};
    const double jl =
        std::sqrt(jitter[0] * jitter[0] + jitter[1] * jitter[1] + jitter[2] * jitter[2]);
    const double tilt = 0.36 * u(rng); // up to about 20 degrees
    double n[3];
    for (int k = 0; k < 3; ++k)
      n[k] = d[k] / length + tilt * jitter[k] / jl;
    const double nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (double& v : n)
      v /= nl;
    const double r = 0.95 + 0.1 * u(rng);
    const double p[3] = {r * d[0] / length, r * d[1] / length, r * d[2] / length};
    double expected = HUGE_VAL;
    const auto& tri = sphere.triangles;
    for (std::size_t t = 0; t < tri.size(); t += 3)
    {
      const double* a = &sphere.positions[3 * tri[t]];
      const double* b = &sphere.positions[3 * tri[t + 1]];
      const double* c = &sphere.positions[3 * tri[t + 2]];
      double s = 0;
      // Facing the line's way: the outward normal of a triangle near p has a positive n.
      const double facing =
          (a[0] + b[0] + c[0]) * n[0] + (a[1] + b[1] + c[1]) * n[1] + (a[2] + b[2] + c[2]) * n[2];
      if (facing > 0 && lineMeetsTriangle(p, n, a, b, c, s) && std::abs(s) < std::abs(expected))
        expected = s;
    }
    ASSERT_LT(std::abs(expected), reach);
    const dp::FrameSurface::Crossing c = surface.cross(p, n, reach, 0.5, 0.02);
    ASSERT_TRUE(c.found) << "point " << i;
    EXPECT_NEAR(c.distance, expected, 5e-4) << "point " << i;
  }
}

// The unit square at z = 0 as n x n points with normals up.
std::vector<double> planePoints(int n)
{
  std::vector<double> points;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      points.insert(points.end(), {(i + 0.5) / n, (j + 0.5) / n, 0.0});
  return points;
}

TEST(FrameSurface, PointsAreMetOnTheirTangentPlanesAveragedNearTheLine)
{
  // Points of a plane with their normals: every tangent plane gives the same crossing, so their
  // average is the plane's, with the full weight where enough points lie near the line.
  const std::vector<double> points = planePoints(50);
  const std::size_t count = points.size() / 3;
  const std::vector<float> up = [&]
  {
    std::vector<float> normals;
    for (std::size_t i = 0; i < count; ++i)
      normals.insert(normals.end(), {0.0f, 0.0f, 1.0f});
    return normals;
  }();
  const dp::FrameSurface oriented = dp::FrameSurface::ofPoints(points.data(), count, up.data());
  EXPECT_EQ(oriented.size(), count);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 100; ++i)
  {
    const double p[3] = {0.3 + 0.4 * u(rng), 0.3 + 0.4 * u(rng), 0.2 * u(rng) - 0.1};
    const std::vector<double> n = tilted(0.5 * u(rng), 6.3 * u(rng));
    const dp::FrameSurface::Crossing c = oriented.cross(p, n.data(), 0.3, 0.5, 0.03);
    ASSERT_TRUE(c.found) << "point " << i;
    EXPECT_NEAR(c.distance, -p[2] / n[2], 1e-12);
    EXPECT_EQ(c.weight, 1.0);
  }
  // Looking down, the oriented points face away; estimated normals have no orientation, so the
  // test reads the lines and the plane is met.
  const double p[3] = {0.51, 0.49, 0.05}, down[3] = {0, 0, -1};
  EXPECT_FALSE(oriented.cross(p, down, 0.3, 0.5, 0.03).found);
  const dp::FrameSurface estimated = dp::FrameSurface::ofPoints(points.data(), count, nullptr);
  const dp::FrameSurface::Crossing c = estimated.cross(p, down, 0.3, 0.5, 0.03);
  ASSERT_TRUE(c.found);
  EXPECT_NEAR(c.distance, 0.05, 1e-9);
  // A line between points, far from each compared with the width, meets nothing; a line that
  // meets the plane farther than the reach neither.
  const double between[3] = {0.5, 0.5, 0.01}, up3[3] = {0, 0, 1};
  EXPECT_FALSE(oriented.cross(between, up3, 0.3, 0.5, 1e-4).found);
  EXPECT_FALSE(oriented.cross(p, up3, 0.04, 0.5, 0.03).found);
  // Few points near the line (a sparse corner): found with less than the full weight.
  const double corner[3] = {-0.02, -0.02, 0.01};
  const dp::FrameSurface::Crossing sparse = oriented.cross(corner, up3, 0.3, 0.5, 0.02);
  ASSERT_TRUE(sparse.found);
  EXPECT_LT(sparse.weight, 1.0);
  EXPECT_GT(sparse.weight, 0.0);
}

TEST(FrameSurface, AnInwardDataTurnsToAgreeWithTheMeshItIsSeenFrom)
{
  // The tracked mesh, just above the plane, faces down: the data (facing up) face the other way
  // and turn; asked again, they agree. Estimated normals have no orientation to turn.
  const Mesh plane = dp::test::grid(10);
  dp::FrameSurface surface = dp::FrameSurface::ofMesh(plane.surface());
  std::vector<double> positions, normals;
  for (int i = 0; i < 100; ++i)
  {
    positions.insert(positions.end(), {0.05 + 0.009 * i, 0.5, 0.02});
    normals.insert(normals.end(), {0, 0, -1});
  }
  const double p[3] = {0.5, 0.5, 0.05}, down[3] = {0, 0, -1};
  EXPECT_FALSE(surface.cross(p, down, 0.3, 0.5, 0.02).found);
  EXPECT_TRUE(surface.orientAgainst(positions.data(), normals.data(), 100, 0.1));
  const dp::FrameSurface::Crossing c = surface.cross(p, down, 0.3, 0.5, 0.02);
  ASSERT_TRUE(c.found);
  EXPECT_NEAR(c.distance, 0.05, 1e-12);
  EXPECT_FALSE(surface.orientAgainst(positions.data(), normals.data(), 100, 0.1));
  // Out of reach, nothing votes and nothing turns.
  for (std::size_t i = 2; i < positions.size(); i += 3)
    positions[i] = 1.0;
  for (double& n : normals)
    n = -n;
  EXPECT_FALSE(surface.orientAgainst(positions.data(), normals.data(), 100, 0.1));

  const std::vector<double> points = planePoints(20);
  dp::FrameSurface estimated =
      dp::FrameSurface::ofPoints(points.data(), points.size() / 3, nullptr);
  for (std::size_t i = 2; i < positions.size(); i += 3)
    positions[i] = 0.02;
  for (double& n : normals)
    n = -n;
  EXPECT_FALSE(estimated.orientAgainst(positions.data(), normals.data(), 100, 0.1));
}

} // namespace
