// SPDX-License-Identifier: BSD-3-Clause
// DeformationGraph: the coarse level's nodes and their blending.

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

TEST(DeformationGraph, MovesRigidlyFitsRigidMotionsAndContinuesThem)
{
  const Shape s = tube(16, 12);
  const dp::TriangleMesh mesh(s.triangles, s.positions.size() / 3);
  const dp::DeformationGraph graph(mesh, s.positions.data(), 30, 4);
  EXPECT_EQ(graph.numberOfNodes(), 30u);
  std::vector<double> x(s.positions.size());
  graph.deform(graph.identity(), x.data());
  for (std::size_t i = 0; i < x.size(); ++i)
    ASSERT_NEAR(x[i], s.positions[i], 1e-12);
  for (std::size_t v = 0; v < mesh.numberOfVertices(); ++v)
  {
    double total = 0;
    for (auto i = graph.influencesBegin(v); i != graph.influencesEnd(v); ++i)
      total += i->weight;
    ASSERT_NEAR(total, 1.0, 1e-12) << v;
  }
  // One rigid motion for all nodes moves the mesh rigidly; fit() recovers it from the shape.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).matrix();
  const Eigen::Vector3d t(0.3, -0.1, 0.2);
  dp::DeformationGraph::State rigid = graph.identity();
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
  {
    const Eigen::Vector3d g(graph.nodePosition(j));
    rigid.rotation[j] = R;
    rigid.translation[j] = R * g + t - g;
  }
  graph.deform(rigid, x.data());
  for (std::size_t v = 0; v < mesh.numberOfVertices(); ++v)
    ASSERT_LT((Eigen::Vector3d(&x[3 * v]) - (R * Eigen::Vector3d(&s.positions[3 * v]) + t)).norm(),
              1e-12);
  const dp::DeformationGraph::State fitted = graph.fit(x.data());
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
  {
    EXPECT_LT((fitted.rotation[j] - R).norm(), 1e-9) << j;
    EXPECT_LT((fitted.translation[j] - rigid.translation[j]).norm(), 1e-9) << j;
  }
  // A constant turn, continued: identity -> R -> R^2.
  dp::DeformationGraph::State half = graph.identity();
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
    half.rotation[j] = R;
  const dp::DeformationGraph::State next = dp::extrapolate(graph.identity(), half, graph, 1.0);
  EXPECT_LT((next.rotation[0] - R * R).norm(), 1e-12);
  // A rigid motion continued is the same motion once more, x -> R (R x + t) + t, for a turn about
  // a point far from the nodes too (a leg about its hip): not only the rotation continues.
  const dp::DeformationGraph::State twice = dp::extrapolate(graph.identity(), rigid, graph, 1.0);
  graph.deform(twice, x.data());
  for (std::size_t v = 0; v < mesh.numberOfVertices(); ++v)
  {
    const Eigen::Vector3d p(&s.positions[3 * v]);
    ASSERT_LT((Eigen::Vector3d(&x[3 * v]) - (R * (R * p + t) + t)).norm(), 1e-12) << v;
  }
}

TEST(DeformationGraph, BlendsAlongTheSurfaceNotAcrossGaps)
{
  // A U of two long strips joined at the bottom, their tops 1/20 of their length apart: close in
  // space, far along the surface. No vertex of one arm's top blends a node of the other arm.
  const int rows = 40, columns = 4;
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;
  // The strip runs up one arm (x = 0), across the bottom and up the other (x = 0.05).
  const int length = 2 * rows + 2;
  for (int i = 0; i < length; ++i)
    for (int j = 0; j < columns; ++j)
    {
      double x, y;
      if (i < rows)
      {
        x = 0;
        y = 1.0 - static_cast<double>(i) / rows;
      }
      else if (i < rows + 2)
      {
        x = 0.025 * (i - rows + 0.5);
        y = -0.01;
      }
      else
      {
        x = 0.05;
        y = static_cast<double>(i - rows - 2) / rows;
      }
      positions.insert(positions.end(), {x, y, 0.02 * j});
    }
  for (int i = 0; i + 1 < length; ++i)
    for (int j = 0; j + 1 < columns; ++j)
    {
      const std::int64_t a = i * columns + j, b = a + 1, c = a + columns, d = c + 1;
      triangles.insert(triangles.end(), {a, c, b, b, c, d});
    }
  const dp::TriangleMesh mesh(triangles, positions.size() / 3);
  const dp::DeformationGraph graph(mesh, positions.data(), 40, 4);
  for (std::size_t v = 0; v < mesh.numberOfVertices(); ++v)
  {
    if (positions[3 * v + 1] < 0.5)
      continue; // the tops only
    const bool left = positions[3 * v] < 0.025;
    for (auto i = graph.influencesBegin(v); i != graph.influencesEnd(v); ++i)
    {
      const double* g = graph.nodePosition(static_cast<std::size_t>(i->node));
      EXPECT_EQ(g[0] < 0.025, left) << "vertex " << v << " blends a node of the other arm";
    }
  }
}

// Appends a flat strip of rows x columns vertices (spacing 0.025) whose first vertex is at
// (x, y, 0).
void appendStrip(double x, double y, int rows, int columns, std::vector<double>& positions,
                 std::vector<std::int64_t>& triangles)
{
  const auto first = static_cast<std::int64_t>(positions.size() / 3);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < columns; ++j)
      positions.insert(positions.end(), {x + 0.025 * j, y + 0.025 * i, 0.0});
  for (int i = 0; i + 1 < rows; ++i)
    for (int j = 0; j + 1 < columns; ++j)
    {
      const std::int64_t a = first + i * columns + j, b = a + 1, c = a + columns, d = c + 1;
      triangles.insert(triangles.end(), {a, c, b, b, c, d});
    }
}

TEST(DeformationGraph, LinksASmallPieceToTheNearestPartButKeepsLargePartsApart)
{
  // Two large strips far apart (two bodies) and a small one beside the first (a hand a depth
  // mesh broke off): the small piece's nodes are joined to the first strip by one edge, to its
  // nearest node; the large strips stay two parts.
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;
  appendStrip(0, 0, 40, 4, positions, triangles);    // first body
  appendStrip(5, 0, 40, 4, positions, triangles);    // second body, 5 m away
  appendStrip(0.2, 0.5, 4, 4, positions, triangles); // the small piece, 0.1 m off the first
  const std::size_t firstEnd = 160, secondEnd = 320;
  const dp::TriangleMesh mesh(triangles, positions.size() / 3);
  const dp::DeformationGraph graph(mesh, positions.data(), 60, 4);
  const auto pieceOf = [&](std::size_t node)
  {
    const auto v = static_cast<std::size_t>(graph.nodeVertex(node));
    return v < firstEnd ? 0 : v < secondEnd ? 1 : 2;
  };
  std::vector<std::array<std::int64_t, 2>> across;
  for (const auto& e : graph.edges())
    if (pieceOf(static_cast<std::size_t>(e[0])) != pieceOf(static_cast<std::size_t>(e[1])))
      across.push_back(e);
  ASSERT_EQ(across.size(), 1u) << "one link, from the small piece to the first body";
  const std::size_t a = static_cast<std::size_t>(across[0][0]),
                    b = static_cast<std::size_t>(across[0][1]);
  EXPECT_EQ(pieceOf(a) + pieceOf(b), 2) << "the small piece (2) linked to the first body (0)";
  // The link is the nearest pair of nodes between the two pieces.
  const auto distance = [&](std::size_t j, std::size_t k)
  {
    const double* p = graph.nodePosition(j);
    const double* q = graph.nodePosition(k);
    return std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]);
  };
  double nearest = HUGE_VAL;
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
    for (std::size_t k = 0; k < graph.numberOfNodes(); ++k)
      if (pieceOf(j) == 0 && pieceOf(k) == 2)
        nearest = std::min(nearest, distance(j, k));
  EXPECT_DOUBLE_EQ(distance(a, b), nearest);
}

} // namespace
