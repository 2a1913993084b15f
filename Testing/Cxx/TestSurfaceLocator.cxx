// SPDX-License-Identifier: BSD-3-Clause
// SurfaceLocator: closest points on the surface, searched and followed.

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/LocalThickness.h"
#include "dp/geometry/SurfaceLocator.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/track/AndersonAcceleration.h"
#include "dp/track/ClothEnergy.h"
#include "dp/track/CoverageTerm.h"
#include "dp/track/DeformationGraph.h"
#include "dp/track/DistanceTerm.h"
#include "dp/track/FrameData.h"
#include "dp/track/FrameQuality.h"
#include "dp/track/GraphRegistration.h"
#include "dp/track/InternalEnergyTerm.h"
#include "dp/track/Solvers.h"
#include "dp/track/TemporalTerm.h"
#include "dp/track/TracePreconditioner.h"
#include "dp/track/Tracker.h"

#include "NumericChecks.h"
#include "TrackingShapes.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <random>
#include <utility>

namespace
{

using dp::test::expectGradientMatches;
using dp::test::Frame;
using dp::test::jiggle;
using dp::test::Shape;
using dp::test::tube;

TEST(SurfaceLocator, FindsTheClosestPointsBruteForceFinds)
{
  const Shape s = tube(8, 10);
  const dp::TriangleMesh mesh(s.triangles, s.positions.size() / 3);
  dp::SurfaceLocator locator(mesh, s.positions.data());
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.6, 1.6);
  auto brute = [&](const std::vector<double>& x, const double p[3])
  {
    double best = HUGE_VAL;
    for (std::size_t t = 0; t < mesh.numberOfTriangles(); ++t)
    {
      double w[3], c[3];
      best = std::min(best, dp::closestPointOnTriangle(p, &x[3 * s.triangles[3 * t]],
                                                       &x[3 * s.triangles[3 * t + 1]],
                                                       &x[3 * s.triangles[3 * t + 2]], w, c));
    }
    return best;
  };
  for (int round = 0; round < 2; ++round)
  {
    // Round 1: the same tree refitted to a deformed shape.
    const std::vector<double> x = round == 0 ? s.positions : jiggle(s.positions, 0.05, 8);
    if (round == 1)
      locator.refit(x.data());
    for (int i = 0; i < 300; ++i)
    {
      const double p[3] = {0.4 * u(rng), 0.4 * u(rng), u(rng)};
      const double expected = brute(x, p);
      const dp::SurfaceLocator::Hit hit = locator.closest(p);
      ASSERT_GE(hit.triangle, 0);
      EXPECT_NEAR(hit.squaredDistance, expected, 1e-12);
      // The barycentric weights give the point, which lies at that distance.
      double d2 = 0, sum = 0;
      for (int k = 0; k < 3; ++k)
      {
        double q = 0;
        for (int c = 0; c < 3; ++c)
          q += hit.barycentric[c] * x[3 * s.triangles[3 * hit.triangle + c] + k];
        EXPECT_NEAR(q, hit.point[k], 1e-12);
        d2 += (q - p[k]) * (q - p[k]);
        sum += hit.barycentric[k];
      }
      EXPECT_NEAR(sum, 1.0, 1e-12);
      EXPECT_NEAR(d2, expected, 1e-12);
      // A hint (any triangle) does not change the answer; a bound below the distance finds none.
      EXPECT_EQ(locator.closest(p, HUGE_VAL, i % 50).triangle, hit.triangle);
      EXPECT_EQ(locator.closest(p, 0.99 * std::sqrt(expected)).triangle, -1);
    }
  }
}

TEST(SurfaceLocator, TreesOfEverySizeFindWhatBruteForceFinds)
{
  // Strips of 1 to 40 triangles, crumpled at random: trees of one leaf, and four-child nodes
  // with one to four children, leaves and inner nodes mixed. Every triangle as a hint.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int count = 1; count <= 40; ++count)
  {
    std::vector<double> positions;
    std::vector<std::int64_t> triangles;
    for (int i = 0; i < count + 2; ++i)
      positions.insert(positions.end(),
                       {0.3 * i + 0.1 * u(rng), 0.3 * (i % 2) + 0.1 * u(rng), 0.2 * u(rng)});
    for (int t = 0; t < count; ++t)
      triangles.insert(triangles.end(), {t, t + 1, t + 2});
    const dp::TriangleMesh mesh(triangles, positions.size() / 3);
    const dp::SurfaceLocator locator(mesh, positions.data());
    for (int i = 0; i < 20; ++i)
    {
      const double p[3] = {0.3 * count * 0.5 * (1 + u(rng)), u(rng), u(rng)};
      double best = HUGE_VAL;
      std::int64_t lowest = -1;
      for (int t = 0; t < count; ++t)
      {
        double w[3], c[3];
        const double d2 = dp::closestPointOnTriangle(p, &positions[3 * triangles[3 * t]],
                                                     &positions[3 * triangles[3 * t + 1]],
                                                     &positions[3 * triangles[3 * t + 2]], w, c);
        if (d2 < best)
        {
          best = d2;
          lowest = t;
        }
      }
      const dp::SurfaceLocator::Hit hit = locator.closest(p);
      ASSERT_EQ(hit.triangle, lowest) << count << " triangles";
      EXPECT_EQ(hit.squaredDistance, best);
      for (std::int64_t hint = 0; hint < count; ++hint)
        ASSERT_EQ(locator.closest(p, HUGE_VAL, hint).triangle, lowest)
            << count << " triangles, hint " << hint;
      EXPECT_EQ(locator.closest(p, 0.99 * std::sqrt(best), count / 2).triangle, -1);
    }
  }
}

TEST(SurfaceLocator, ATieGoesToTheLowestTriangleWhateverTheHint)
{
  // A flat grid of 12 x 12 squares, two triangles each: a point above an inner vertex is
  // equally near its six triangles (their closest point is the vertex itself).
  const int n = 12;
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      positions.insert(positions.end(), {double(i), double(j), 0.0});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
    {
      const std::int64_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      triangles.insert(triangles.end(), {a, b, d, a, d, c});
    }
  const dp::TriangleMesh mesh(triangles, positions.size() / 3);
  const dp::SurfaceLocator locator(mesh, positions.data());
  for (const auto& [i, j] : {std::pair{3, 4}, std::pair{7, 7}, std::pair{10, 2}})
  {
    const std::int64_t vertex = j * (n + 1) + i;
    std::int64_t lowest = -1;
    for (std::size_t t = 0; t < mesh.numberOfTriangles() && lowest < 0; ++t)
      for (int c = 0; c < 3; ++c)
        if (triangles[3 * t + c] == vertex)
          lowest = static_cast<std::int64_t>(t);
    const double p[3] = {double(i), double(j), 0.5};
    EXPECT_EQ(locator.closest(p).triangle, lowest);
    for (std::int64_t hint = 0; hint < static_cast<std::int64_t>(mesh.numberOfTriangles()); ++hint)
      ASSERT_EQ(locator.closest(p, HUGE_VAL, hint).triangle, lowest) << "hint " << hint;
  }
}

TEST(SurfaceLocator, FollowingASmallMoveReachesTheClosestPoint)
{
  // Points just outside a tube (a convex surface there: its only local minimum of the distance
  // is the closest point), each followed from the closest triangle of a point up to 0.1 away
  // (a step's move, a few triangles): the walk ends where brute force does.
  const Shape s = tube(8, 10);
  const dp::TriangleMesh mesh(s.triangles, s.positions.size() / 3);
  const dp::SurfaceLocator locator(mesh, s.positions.data());
  std::vector<double> normals(s.positions.size());
  mesh.vertexNormals(s.positions.data(), normals.data());
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int moved = 0;
  for (int i = 0; i < 300; ++i)
  {
    // A point of a random triangle, 0.02 off the surface, away from the tube's axis.
    const std::size_t t = static_cast<std::size_t>(u(rng) * mesh.numberOfTriangles());
    double a = u(rng), b = u(rng);
    if (a + b > 1)
    {
      a = 1 - a;
      b = 1 - b;
    }
    const double w[3] = {1 - a - b, a, b};
    double p[3] = {0, 0, 0}, n[3] = {0, 0, 0};
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k)
      {
        p[k] += w[c] * s.positions[3 * s.triangles[3 * t + c] + k];
        n[k] += w[c] * normals[3 * s.triangles[3 * t + c] + k];
      }
    const double outward = n[0] * p[0] + n[1] * p[1] >= 0 ? 1.0 : -1.0;
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; ++k)
      p[k] += 0.02 * outward * n[k] / length;
    double q[3];
    for (int k = 0; k < 3; ++k)
      q[k] = p[k] + 0.1 * (2 * u(rng) - 1) / std::sqrt(3.0);
    const std::int64_t from = locator.closest(q).triangle;
    const dp::SurfaceLocator::Hit exact = locator.closest(p);
    const dp::SurfaceLocator::Hit hit = locator.follow(p, from);
    ASSERT_GE(hit.triangle, 0);
    EXPECT_NEAR(hit.squaredDistance, exact.squaredDistance, 1e-12) << "point " << i;
    moved += from != exact.triangle;
    // Its weights give its point; a bound below its distance finds none.
    for (int k = 0; k < 3; ++k)
    {
      double x = 0;
      for (int c = 0; c < 3; ++c)
        x += hit.barycentric[c] * s.positions[3 * s.triangles[3 * hit.triangle + c] + k];
      EXPECT_NEAR(x, hit.point[k], 1e-12);
    }
    EXPECT_EQ(locator.follow(p, from, 0.99 * std::sqrt(exact.squaredDistance)).triangle, -1);
  }
  EXPECT_GT(moved, 100) << "most walks start away from the answer";
}

TEST(SurfaceLocator, FollowingStaysOnItsPartOfTheSurface)
{
  // Two parallel sheets, 0.3 apart; a point 0.1 below the upper one. Followed from the lower
  // sheet, the walk finds the lower sheet's closest point (0.2 away): it is local, unlike the
  // search.
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;
  const int n = 6;
  for (int sheet = 0; sheet < 2; ++sheet)
  {
    const auto base = static_cast<std::int64_t>(positions.size() / 3);
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
        positions.insert(positions.end(), {0.1 * i, 0.1 * j, 0.3 * sheet});
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
      {
        const std::int64_t a = base + j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
        triangles.insert(triangles.end(), {a, b, d, a, d, c});
      }
  }
  const dp::TriangleMesh mesh(triangles, positions.size() / 3);
  const dp::SurfaceLocator locator(mesh, positions.data());
  const double p[3] = {0.33, 0.27, 0.2};
  const dp::SurfaceLocator::Hit search = locator.closest(p);
  EXPECT_NEAR(search.squaredDistance, 0.01, 1e-12);
  EXPECT_GE(search.triangle, 2 * n * n) << "the upper sheet";
  const dp::SurfaceLocator::Hit walk = locator.follow(p, 0); // a corner triangle of the lower one
  EXPECT_NEAR(walk.squaredDistance, 0.04, 1e-12);
  EXPECT_LT(walk.triangle, 2 * n * n) << "the lower sheet";
  EXPECT_NEAR(walk.point[0], 0.33, 1e-12);
  EXPECT_NEAR(walk.point[1], 0.27, 1e-12);
  EXPECT_EQ(locator.follow(p, 0, 0.15).triangle, -1);
}

} // namespace
