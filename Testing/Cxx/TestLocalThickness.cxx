// SPDX-License-Identifier: BSD-3-Clause
// LocalThickness: inner and outer medial radii, and the softening the tracker derives from them.

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

// A closed lat-long sphere of `radius` around `centre` (rings x segments quads, fans at the poles),
// appended to `shape`; `inward` turns its faces inward.
void addSphere(Shape& shape, const double centre[3], double radius, bool inward = false)
{
  const std::int64_t rings = 12, segments = 24;
  const auto first = static_cast<std::int64_t>(shape.positions.size() / 3);
  const auto put = [&](double polar, double azimuth)
  {
    shape.positions.insert(shape.positions.end(),
                           {centre[0] + radius * std::sin(polar) * std::cos(azimuth),
                            centre[1] + radius * std::sin(polar) * std::sin(azimuth),
                            centre[2] + radius * std::cos(polar)});
  };
  put(0, 0);
  for (std::int64_t r = 1; r < rings; ++r)
    for (std::int64_t s = 0; s < segments; ++s)
      put(M_PI * static_cast<double>(r) / rings, 2 * M_PI * static_cast<double>(s) / segments);
  put(M_PI, 0);
  const std::int64_t south = first + 1 + (rings - 1) * segments;
  const auto ring = [&](std::int64_t r, std::int64_t s)
  { return first + 1 + (r - 1) * segments + s % segments; };
  const auto face = [&](std::int64_t a, std::int64_t b, std::int64_t c)
  {
    if (inward)
      std::swap(b, c);
    shape.triangles.insert(shape.triangles.end(), {a, b, c});
  };
  for (std::int64_t s = 0; s < segments; ++s)
  {
    face(first, ring(1, s), ring(1, s + 1));
    face(south, ring(rings - 1, s + 1), ring(rings - 1, s));
    for (std::int64_t r = 1; r + 1 < rings; ++r)
    {
      face(ring(r, s), ring(r + 1, s), ring(r + 1, s + 1));
      face(ring(r, s), ring(r + 1, s + 1), ring(r, s + 1));
    }
  }
}

TEST(LocalThickness, FindsEachPartsRadiusWhicheverWayItsFacesTurn)
{
  // A thin part and a thick one far apart: each vertex's inner ball is its own sphere (within
  // 10 %: area-weighted normals on a lat-long mesh lean a few degrees).
  for (const bool inward : {false, true})
  {
    Shape shape;
    const double thin[3] = {0, 0, 0}, thick[3] = {2, 0, 0};
    addSphere(shape, thin, 0.1, inward);
    const std::size_t thinVertices = shape.positions.size() / 3;
    addSphere(shape, thick, 0.4, inward);
    const dp::TriangleMesh mesh(shape.triangles, shape.positions.size() / 3);
    const std::vector<double> radius = dp::medialRadii(mesh, shape.positions.data(), 1.0);
    ASSERT_EQ(radius.size(), mesh.numberOfVertices());
    for (std::size_t v = 0; v < radius.size(); ++v)
      EXPECT_NEAR(radius[v], v < thinVertices ? 0.1 : 0.4, v < thinVertices ? 0.01 : 0.04)
          << "vertex " << v << (inward ? " (faces turned inward)" : "");
  }
}

TEST(LocalThickness, OutsideBallsMeasureTheGapInFrontOfEachVertex)
{
  // Two spheres of radius 0.3, 0.2 apart: the ball outside the first sphere at its point facing
  // the second fits the gap (radius 0.1); on its far side nothing faces it (the cap).
  Shape shape;
  const double a[3] = {0, 0, 0}, b[3] = {0.8, 0, 0};
  addSphere(shape, a, 0.3);
  const std::size_t first = shape.positions.size() / 3;
  addSphere(shape, b, 0.3);
  const dp::TriangleMesh mesh(shape.triangles, shape.positions.size() / 3);
  const std::vector<double> outer =
      dp::medialRadii(mesh, shape.positions.data(), 1.0, 0, dp::MedialSide::Outside);
  std::size_t facing = 0, away = 0;
  for (std::size_t v = 0; v < first; ++v)
  {
    if (shape.positions[3 * v] > shape.positions[3 * facing])
      facing = v;
    if (shape.positions[3 * v] < shape.positions[3 * away])
      away = v;
  }
  EXPECT_NEAR(outer[facing], 0.1, 0.01);
  EXPECT_DOUBLE_EQ(outer[away], 1.0);
  // Inside, the same vertices measure the sphere.
  const std::vector<double> inner = dp::medialRadii(mesh, shape.positions.data(), 1.0, 0);
  EXPECT_NEAR(inner[facing], 0.3, 0.03);
}

TEST(LocalThickness, TheTrackerSoftensTheStretchWhereTwoPartsFaceEachOther)
{
  // A template of two spheres 0.2 apart (a crease between parts, as where an arm touches the
  // body): the edges facing the other sphere get the crease's factor, those on the far sides
  // keep the full stiffness; with the factor 1 nothing is scaled.
  Shape shape;
  const double a[3] = {0, 0, 0}, b[3] = {0.8, 0, 0};
  addSphere(shape, a, 0.3);
  addSphere(shape, b, 0.3);
  const dp::TriangleMesh mesh(shape.triangles, shape.positions.size() / 3);
  dp::TrackerOptions options;
  options.softening.stretch = 1.0; // the creases' factor alone
  options.creases.stretch = 0.25;
  const dp::Tracker tracker(mesh, shape.positions, options);
  const std::vector<double>& scales = tracker.clothEnergy().stretchScales();
  ASSERT_EQ(scales.size(), mesh.edges().size());
  std::size_t facing = 0, soft = 0;
  for (std::size_t e = 0; e < scales.size(); ++e)
  {
    const auto [i, j] = mesh.edges()[e];
    const double x = 0.5 * (shape.positions[3 * i] + shape.positions[3 * j]);
    const bool inGap = x > 0.25 && x < 0.55; // both ends on the spheres' facing caps
    facing += inGap;
    soft += scales[e] == 0.25;
    if (inGap)
    {
      EXPECT_DOUBLE_EQ(scales[e], 0.25) << "edge " << e << " at x " << x;
    }
    if (x < 0.0 || x > 0.8)
    {
      EXPECT_DOUBLE_EQ(scales[e], 1.0) << "edge " << e << " at x " << x;
    }
  }
  EXPECT_GT(facing, 0u);
  EXPECT_LT(soft, scales.size() / 2);
  options.creases.stretch = 1.0;
  const dp::Tracker stiff(mesh, shape.positions, options);
  EXPECT_TRUE(stiff.clothEnergy().stretchScales().empty());
}

TEST(LocalThickness, OnlyWhatEnclosesABallIsSoftenedAsThick)
{
  // A ball (closed, thick everywhere) gets the thick parts' factor on every edge; a flat sheet
  // (its balls meet nothing) keeps the full stiffness: it is no trunk.
  dp::TrackerOptions options;
  options.softening.stretch = 0.3;
  options.creases.stretch = 1.0; // the thick parts' factor alone
  Shape ball;
  const double centre[3] = {0, 0, 0};
  addSphere(ball, centre, 0.3);
  const dp::TriangleMesh ballMesh(ball.triangles, ball.positions.size() / 3);
  const dp::Tracker round(ballMesh, ball.positions, options);
  ASSERT_EQ(round.clothEnergy().stretchScales().size(), ballMesh.edges().size());
  for (const double scale : round.clothEnergy().stretchScales())
    EXPECT_NEAR(scale, 0.3, 1e-9);

  Shape sheet;
  const int cells = 12;
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i)
      sheet.positions.insert(sheet.positions.end(), {0.1 * i, 0.1 * j, 0.0});
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i)
    {
      const std::int64_t v = j * (cells + 1) + i;
      sheet.triangles.insert(sheet.triangles.end(),
                             {v, v + 1, v + cells + 2, v, v + cells + 2, v + cells + 1});
    }
  const dp::TriangleMesh sheetMesh(sheet.triangles, sheet.positions.size() / 3);
  const dp::Tracker flat(sheetMesh, sheet.positions, options);
  for (const double scale : flat.clothEnergy().stretchScales())
    EXPECT_EQ(scale, 1.0);
}

TEST(LocalThickness, AnOpenTubesRadiusIsItsOwn)
{
  // The bending tube (radius 0.1 here) closed by nothing: balls stop at the tube's own far
  // side, so the radius is the tube's; the cap `largest` bounds balls that meet nothing.
  const Shape shape = tube();
  const dp::TriangleMesh mesh(shape.triangles, shape.positions.size() / 3);
  const std::vector<double> radius = dp::medialRadii(mesh, shape.positions.data(), 5.0, 0);
  std::vector<double> sorted = radius;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2];
  double tubeRadius = 0;
  const std::size_t n = mesh.numberOfVertices();
  for (std::size_t v = 0; v < n; ++v)
    tubeRadius += std::hypot(shape.positions[3 * v], shape.positions[3 * v + 1]) / n;
  EXPECT_NEAR(median, tubeRadius, 0.05 * tubeRadius);
  EXPECT_LE(sorted.back(), 5.0);
}

} // namespace
