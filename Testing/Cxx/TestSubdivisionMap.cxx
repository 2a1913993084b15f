// SPDX-License-Identifier: BSD-3-Clause
// SubdivisionMap: Loop subdivision as a fixed linear map from the base mesh to the fine mesh.
#include "FineMeshShapes.h"

#include "dp/geometry/SubdivisionMap.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <utility>

namespace
{

using dp::test::Mesh;

// Each directed edge of a closed, consistently oriented mesh appears once, and its reverse too.
void expectClosedAndOriented(const std::vector<std::int64_t>& triangles)
{
  std::map<std::pair<std::int64_t, std::int64_t>, int> directed;
  for (std::size_t t = 0; t < triangles.size(); t += 3)
    for (int k = 0; k < 3; ++k)
      ++directed[{triangles[t + k], triangles[t + (k + 1) % 3]}];
  for (const auto& [edge, count] : directed)
  {
    EXPECT_EQ(count, 1) << edge.first << "-" << edge.second;
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u) << edge.first << "-" << edge.second;
  }
}

TEST(SubdivisionMap, EachLevelSplitsEveryTriangleIntoFourAndKeepsTheMeshClosed)
{
  const Mesh ico = dp::test::icosahedron();
  const std::size_t expected[] = {12, 42, 162, 642};
  for (int levels = 0; levels <= 3; ++levels)
  {
    const dp::SubdivisionMap map(ico.triangles, 12, levels);
    EXPECT_EQ(map.levels(), levels);
    EXPECT_EQ(map.fineVertices(), expected[levels]);
    EXPECT_EQ(map.fineTriangles().size(), ico.triangles.size() << (2 * levels));
    EXPECT_EQ(map.parents().size(), expected[levels] - 12);
    for (int l = 0; l <= levels; ++l)
      EXPECT_EQ(map.verticesOf(l), expected[l]);
    expectClosedAndOriented(map.fineTriangles());
    // A vertex a split made lies on an edge of vertices made before it.
    for (std::size_t i = 0; i < map.parents().size(); ++i)
    {
      const auto& p = map.parents()[i];
      EXPECT_LT(p[0], p[1]);
      EXPECT_LT(static_cast<std::size_t>(p[1]), 12 + i);
    }
  }
}

TEST(SubdivisionMap, IsLinearAndReproducesAffineMotionExactly)
{
  const Mesh ico = dp::test::icosphere(1);
  const dp::SubdivisionMap map(ico.triangles, ico.vertices(), 3);
  std::vector<double> a = ico.positions, b(a.size()), sum(a.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    b[i] = std::sin(0.7 * static_cast<double>(i));
  for (std::size_t i = 0; i < a.size(); ++i)
    sum[i] = 2 * a[i] - 3 * b[i];
  const std::size_t n = 3 * map.fineVertices();
  std::vector<double> fa(n), fb(n), fsum(n);
  map.apply(a.data(), fa.data());
  map.apply(b.data(), fb.data());
  map.apply(sum.data(), fsum.data());
  for (std::size_t i = 0; i < n; ++i)
    EXPECT_NEAR(fsum[i], 2 * fa[i] - 3 * fb[i], 1e-12);
  // A rotation and translation of the base moves the fine mesh the same way.
  const double c = std::cos(0.3), s = std::sin(0.3);
  std::vector<double> moved(a.size()), fmoved(n);
  for (std::size_t i = 0; i < a.size(); i += 3)
  {
    moved[i] = c * a[i] - s * a[i + 1] + 5;
    moved[i + 1] = s * a[i] + c * a[i + 1] - 2;
    moved[i + 2] = a[i + 2] + 0.5;
  }
  map.apply(moved.data(), fmoved.data());
  for (std::size_t i = 0; i < n; i += 3)
  {
    EXPECT_NEAR(fmoved[i], c * fa[i] - s * fa[i + 1] + 5, 1e-12);
    EXPECT_NEAR(fmoved[i + 1], s * fa[i] + c * fa[i + 1] - 2, 1e-12);
    EXPECT_NEAR(fmoved[i + 2], fa[i + 2] + 0.5, 1e-12);
  }
}

TEST(SubdivisionMap, APlaneStaysExactlyInItsPlaneAndInsideItsBoundary)
{
  const Mesh square = dp::test::grid(6);
  const dp::SubdivisionMap map(square.triangles, square.vertices(), 3);
  std::vector<double> fine(3 * map.fineVertices());
  map.apply(square.positions.data(), fine.data());
  std::size_t onSide = 0;
  for (std::size_t i = 0; i < map.fineVertices(); ++i)
  {
    const double* x = &fine[3 * i];
    EXPECT_EQ(x[2], 0.0);
    EXPECT_GE(x[0], 0.0);
    EXPECT_LE(x[0], 1.0);
    EXPECT_GE(x[1], 0.0);
    EXPECT_LE(x[1], 1.0);
    // A straight side of the boundary stays straight (away from the corners, which the
    // boundary's curve rounds): its points are on it exactly.
    if (x[1] < 1e-3 && x[0] > 0.2 && x[0] < 0.8)
    {
      EXPECT_EQ(x[1], 0.0);
      ++onSide;
    }
  }
  EXPECT_EQ(onSide, 29u); // 48 segments along the side, those with 0.2 < x < 0.8
}

TEST(SubdivisionMap, ASphereStaysWithinAFractionOfItsRadius)
{
  // Loop's surface is approximating: it shrinks a convex shape by a little.
  const Mesh sphere = dp::test::icosphere(3); // 642 vertices
  const dp::SubdivisionMap map(sphere.triangles, sphere.vertices(), 2);
  std::vector<double> fine(3 * map.fineVertices());
  map.apply(sphere.positions.data(), fine.data());
  double smallest = 1, largest = 0;
  for (std::size_t i = 0; i < map.fineVertices(); ++i)
  {
    const double r = std::sqrt(fine[3 * i] * fine[3 * i] + fine[3 * i + 1] * fine[3 * i + 1] +
                               fine[3 * i + 2] * fine[3 * i + 2]);
    smallest = std::min(smallest, r);
    largest = std::max(largest, r);
  }
  EXPECT_LE(largest, 1.0 + 1e-12);
  EXPECT_GT(smallest, 0.99);
}

TEST(SubdivisionMap, BoundariesAndEdgesOfThreeTrianglesAreSharp)
{
  // Three triangles on one edge (a fin), and a lone triangle: every count as for any mesh, the
  // sharp edge's new vertex at its midpoint.
  const std::vector<std::int64_t> triangles = {0, 1, 2, 1, 0, 3, 0, 1, 4, 5, 6, 7};
  const std::vector<double> x = {0,   0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0,
                                 0.5, 0, 1, 3, 0, 0, 4,   0, 0, 3,   1,  0};
  const dp::SubdivisionMap map(triangles, 8, 1);
  EXPECT_EQ(map.fineTriangles().size(), 4 * triangles.size());
  std::vector<double> fine(3 * map.fineVertices());
  map.apply(x.data(), fine.data());
  for (std::size_t i = 0; i < map.parents().size(); ++i)
  {
    const auto& p = map.parents()[i];
    if (p[0] == 0 && p[1] == 1)
    {
      for (int c = 0; c < 3; ++c)
        EXPECT_DOUBLE_EQ(fine[3 * (8 + i) + c], 0.5 * (x[c] + x[3 + c]));
    }
  }
  // The lone triangle (its edges all on the boundary) stays in its plane.
  for (int v = 5; v <= 7; ++v)
    EXPECT_EQ(fine[3 * v + 2], 0.0);
}

TEST(SubdivisionMap, TheSameBitsOnOneThreadAsOnAll)
{
  const Mesh sphere = dp::test::icosphere(3);
  const dp::SubdivisionMap map(sphere.triangles, sphere.vertices(), 2);
  std::vector<double> all(3 * map.fineVertices()), one(all.size());
  map.apply(sphere.positions.data(), all.data());
  {
    const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    map.apply(sphere.positions.data(), one.data());
  }
  EXPECT_EQ(all, one);
}

TEST(SubdivisionMap, RefusesBadMeshesAndLevels)
{
  const Mesh ico = dp::test::icosahedron();
  EXPECT_THROW(dp::SubdivisionMap(ico.triangles, 12, -1), std::invalid_argument);
  EXPECT_THROW(dp::SubdivisionMap(ico.triangles, 12, dp::MaximumDetailLevels + 1),
               std::invalid_argument);
  EXPECT_THROW(dp::SubdivisionMap(ico.triangles, 11, 1), std::invalid_argument);
  EXPECT_THROW(dp::SubdivisionMap({0, 1, 1}, 3, 1), std::invalid_argument);
  EXPECT_THROW(dp::SubdivisionMap({0, 1}, 3, 1), std::invalid_argument);
  EXPECT_THROW(dp::SubdivisionMap({0, -1, 2}, 3, 1), std::invalid_argument);
}

} // namespace
