// SPDX-License-Identifier: BSD-3-Clause
// FrameData: the subsample, the normals and the order of a frame's points.

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

TEST(FrameData, SpreadsTheSubsampleEvenlyAndFlipsNormals)
{
  Frame f(tube().positions);
  const auto& spread = f.data->spread();
  EXPECT_GE(spread.size(), 450u); // about the 600 asked for
  EXPECT_LE(spread.size(), 900u);
  // Even: the kept points' nearest-neighbour distances are near the spacing an even spread
  // would have (random samples' would be far more scattered, down to almost 0).
  const double spacing = std::sqrt(f.mesh.totalArea(f.shape.positions.data()) / spread.size());
  std::vector<double> nearest(spread.size(), HUGE_VAL);
  for (std::size_t i = 0; i < spread.size(); ++i)
    for (std::size_t j = 0; j < spread.size(); ++j)
    {
      const double* a = f.data->point(spread[i]);
      const double* b = f.data->point(spread[j]);
      if (i != j)
        nearest[i] = std::min(nearest[i], std::sqrt((a[0] - b[0]) * (a[0] - b[0]) +
                                                    (a[1] - b[1]) * (a[1] - b[1]) +
                                                    (a[2] - b[2]) * (a[2] - b[2])));
    }
  std::sort(nearest.begin(), nearest.end());
  EXPECT_GT(nearest[nearest.size() / 2], 0.6 * spacing);
  EXPECT_GT(nearest[nearest.size() / 20], 0.25 * spacing);
  const float before = f.data->normal(5)[1];
  f.data->flipNormals();
  EXPECT_EQ(f.data->normal(5)[1], -before);
}

// Every term, at a shape off the data: gradient against finite differences, and the Gauss-Newton
// model's value and gradient equal to the term's own.

TEST(FrameData, KeepsEveryPointWithItsNormalInCurveOrder)
{
  const Shape shape = tube();
  dp::SamplerOptions o;
  o.pointsPerFrame = 3000;
  const dp::PointCloud c = dp::sampleSurface(shape.positions, shape.triangles, o, 0);
  dp::FrameDataOptions fo;
  fo.voxelSize = dp::boundingBoxDiagonal(shape.positions) / 60;
  const dp::FrameData data(c.points.data(), c.numberOfPoints(), c.normals.data(), fo);
  ASSERT_EQ(data.size(), c.numberOfPoints());
  // The same points, each with its own normal: matched by sorting both sides.
  auto rows = [](const double* p, const float* n, std::size_t count)
  {
    std::vector<std::array<double, 6>> r(count);
    for (std::size_t i = 0; i < count; ++i)
      r[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2], n[3 * i], n[3 * i + 1], n[3 * i + 2]};
    std::sort(r.begin(), r.end());
    return r;
  };
  EXPECT_EQ(rows(data.points(), data.normals(), data.size()),
            rows(c.points.data(), c.normals.data(), c.numberOfPoints()));
  // Near in memory, near in space: consecutive points are far closer than the sampler's
  // random order puts them.
  auto path = [](const double* p, std::size_t count)
  {
    double length = 0;
    for (std::size_t i = 1; i < count; ++i)
      length += std::sqrt((p[3 * i] - p[3 * i - 3]) * (p[3 * i] - p[3 * i - 3]) +
                          (p[3 * i + 1] - p[3 * i - 2]) * (p[3 * i + 1] - p[3 * i - 2]) +
                          (p[3 * i + 2] - p[3 * i - 1]) * (p[3 * i + 2] - p[3 * i - 1]));
    return length;
  };
  EXPECT_LT(path(data.points(), data.size()), 0.1 * path(c.points.data(), c.numberOfPoints()));
}

} // namespace
