// SPDX-License-Identifier: BSD-3-Clause
// FrameQuality: tears, departed mesh and holes.

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

TEST(FrameQuality, ATearIsTheLargestStiffEdgeGrowthInMeanEdgeLengths)
{
  // A unit square of two triangles: four sides of 1 and a diagonal of sqrt(2).
  const dp::TriangleMesh mesh({0, 1, 2, 1, 3, 2}, 4);
  const std::vector<double> rest{0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  const double mean = (4 + std::sqrt(2.0)) / 5;
  EXPECT_DOUBLE_EQ(dp::largestEdgeGrowth(mesh, rest, rest, {}), 0.0);
  // Shrinking tears nothing.
  std::vector<double> shrunk = rest;
  for (double& c : shrunk)
    c *= 0.5;
  EXPECT_DOUBLE_EQ(dp::largestEdgeGrowth(mesh, rest, shrunk, {}), 0.0);
  // Vertex 3 pulled 3 away: edge 1-3 grows by 3, edge 3-2 by sqrt(10) - 1.
  std::vector<double> pulled = rest;
  pulled[3 * 3 + 1] = 4;
  EXPECT_NEAR(dp::largestEdgeGrowth(mesh, rest, pulled, {}), 3 / mean, 1e-12);
  // An edge made soft to stretch counts by its stiffness: edge 1-3 at 0.1 leaves edge 3-2.
  std::vector<double> scales;
  for (const auto& e : mesh.edges())
    scales.push_back(std::min(e[0], e[1]) == 1 && std::max(e[0], e[1]) == 3 ? 0.1 : 1.0);
  EXPECT_NEAR(dp::largestEdgeGrowth(mesh, rest, pulled, scales), (std::sqrt(10.0) - 1) / mean,
              1e-12);
}

TEST(FrameQuality, MeshTakenOffItsDataDepartsMeshOverAHoleDoesNot)
{
  const Shape shape = tube(20, 12);
  const std::size_t nv = shape.positions.size() / 3;
  const dp::TriangleMesh mesh(shape.triangles, nv);
  const std::vector<double> mass(nv, 1.0 / static_cast<double>(nv));
  dp::SamplerOptions o;
  o.pointsPerFrame = 6000;
  const dp::PointCloud c = dp::sampleSurface(shape.positions, shape.triangles, o, 0);
  dp::FrameDataOptions fo;
  fo.voxelSize = dp::boundingBoxDiagonal(shape.positions) / 60;
  const double reach = 3 * fo.voxelSize;
  // The top of the tube (its highest tenth) is where a hole is, or what is pulled off.
  double top = -1e300, bottom = 1e300;
  for (std::size_t v = 0; v < nv; ++v)
  {
    top = std::max(top, shape.positions[3 * v + 2]);
    bottom = std::min(bottom, shape.positions[3 * v + 2]);
  }
  const double cut = top - 0.1 * (top - bottom);
  double topMass = 0;
  std::vector<double> pulled = shape.positions;
  for (std::size_t v = 0; v < nv; ++v)
    if (shape.positions[3 * v + 2] > cut)
    {
      pulled[3 * v] += 10 * reach;
      topMass += mass[v];
    }
  ASSERT_GT(topMass, 0.05);
  const dp::FrameData all(c.points.data(), c.numberOfPoints(), c.normals.data(), fo);
  dp::FrameQuality q =
      dp::assessFrame(all, mesh, pulled.data(), mass, reach, shape.positions.data());
  EXPECT_NEAR(q.departed, topMass, 1e-12);
  EXPECT_NEAR(q.unsupported, topMass, 1e-12);
  // Without a start nothing departs.
  EXPECT_EQ(dp::assessFrame(all, mesh, pulled.data(), mass, reach).departed, 0.0);
  // A hole in the data over the top: the mesh there lacks data where it started too.
  std::vector<double> kept;
  std::vector<float> keptNormals;
  for (std::size_t i = 0; i < c.numberOfPoints(); ++i)
    if (c.points[3 * i + 2] < cut - 2 * reach)
    {
      kept.insert(kept.end(), &c.points[3 * i], &c.points[3 * i] + 3);
      keptNormals.insert(keptNormals.end(), &c.normals[3 * i], &c.normals[3 * i] + 3);
    }
  const dp::FrameData holed(kept.data(), kept.size() / 3, keptNormals.data(), fo);
  q = dp::assessFrame(holed, mesh, shape.positions.data(), mass, reach, shape.positions.data());
  EXPECT_GT(q.unsupported, 0.5 * topMass);
  EXPECT_EQ(q.departed, 0.0);
}

} // namespace
