// SPDX-License-Identifier: BSD-3-Clause
// ClothRegions: the cloth's stiffness by region. A closed ball, thick everywhere, takes the
// thick parts' factors on every edge and hinge (the hinges' read through the bending energy); at
// the smoothstep's middle, half of them; a sheet, which encloses nothing, keeps its stiffness;
// where two balls face each other the crease's factor multiplies the thickness's; with both
// softenings off nothing is scaled.
#include "FineMeshShapes.h"
#include "NumericChecks.h"

#include "dp/geometry/TriangleMesh.h"
#include "dp/track/ClothEnergy.h"
#include "dp/track/ClothRegions.h"
#include "dp/track/TrackerOptions.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

namespace
{

// Icospheres of 642 vertices of `radius` around each centre, as one mesh.
dp::test::Mesh balls(const std::vector<std::array<double, 3>>& centres, double radius)
{
  dp::test::Mesh all;
  for (const auto& centre : centres)
  {
    const dp::test::Mesh m = dp::test::icosphere(3);
    const auto first = static_cast<std::int64_t>(all.vertices());
    for (std::size_t i = 0; i < m.positions.size(); ++i)
      all.positions.push_back(centre[i % 3] + radius * m.positions[i]);
    for (const std::int64_t v : m.triangles)
      all.triangles.push_back(first + v);
  }
  return all;
}

dp::ThicknessSoftening thickness(double stretch, double bend, double from = 0.4, double to = 0.7)
{
  dp::ThicknessSoftening t;
  t.stretch = stretch;
  t.bend = bend;
  t.from = from;
  t.to = to;
  return t;
}

dp::CreaseSoftening crease(double stretch, double width = 0.7)
{
  dp::CreaseSoftening c;
  c.stretch = stretch;
  c.width = width;
  return c;
}

TEST(ClothRegions, NothingIsScaledWithBothSofteningsOff)
{
  const dp::test::Mesh m = balls({{0, 0, 0}}, 0.3);
  const dp::TriangleMesh mesh(m.triangles, m.vertices());
  for (const dp::CreaseSoftening& c : {crease(1.0), crease(0.1, 0.0)})
  {
    dp::ClothEnergy cloth(mesh, m.positions.data(), dp::ClothParameters{});
    dp::softenByRegion(cloth, mesh, m.positions.data(), thickness(1, 1), c);
    EXPECT_TRUE(cloth.stretchScales().empty());
  }
}

TEST(ClothRegions, AThickBallTakesTheFactorsOnEveryEdgeAndHinge)
{
  // Every vertex of a ball is as thick as the ball (its inner radius about the thickness): the
  // smoothstep is 1, the stretch factor on every edge; the bending energy of any shape is the
  // bend factor times the unscaled one.
  const dp::test::Mesh m = balls({{0, 0, 0}}, 0.3);
  const dp::TriangleMesh mesh(m.triangles, m.vertices());
  const dp::ClothParameters bendOnly{0, 0, 1};
  dp::ClothEnergy plain(mesh, m.positions.data(), bendOnly),
      soft(mesh, m.positions.data(), bendOnly);
  dp::softenByRegion(soft, mesh, m.positions.data(), thickness(0.3, 0.5), crease(1.0));
  ASSERT_EQ(soft.stretchScales().size(), mesh.edges().size());
  for (const double scale : soft.stretchScales())
    EXPECT_NEAR(scale, 0.3, 1e-12);
  const std::vector<double> bent = dp::test::jiggle(m.positions, 0.01, 3);
  const double e = plain.value(bent.data());
  ASSERT_GT(e, 0);
  EXPECT_NEAR(soft.value(bent.data()), 0.5 * e, 1e-12 * e);

  // The thickness ratio (about 1) in the middle of [from, to]: the smoothstep's middle, half the
  // factor's change.
  dp::ClothEnergy half(mesh, m.positions.data(), bendOnly);
  dp::softenByRegion(half, mesh, m.positions.data(), thickness(0.3, 0.5, 0.5, 1.5), crease(1.0));
  for (const double scale : half.stretchScales())
    EXPECT_NEAR(scale, 1 + 0.5 * (0.3 - 1), 0.03);
}

TEST(ClothRegions, ASheetKeepsItsStiffness)
{
  // A sheet encloses no ball: it is no trunk, whatever the factors.
  const dp::test::Mesh sheet = dp::test::grid(12);
  const dp::TriangleMesh mesh(sheet.triangles, sheet.vertices());
  dp::ClothEnergy cloth(mesh, sheet.positions.data(), dp::ClothParameters{});
  dp::softenByRegion(cloth, mesh, sheet.positions.data(), thickness(0.3, 0.5), crease(1.0));
  ASSERT_EQ(cloth.stretchScales().size(), mesh.edges().size());
  for (const double scale : cloth.stretchScales())
    EXPECT_EQ(scale, 1.0);
}

TEST(ClothRegions, TheCreasesFactorMultipliesTheThicknesss)
{
  // Two balls of radius 0.3, 0.2 apart: the edges on the caps facing each other are in a crease
  // (the ball outside them is far smaller than the balls' thickness) and take both factors; those
  // on the far sides take the thickness's alone.
  const dp::test::Mesh m = balls({{0, 0, 0}, {0.8, 0, 0}}, 0.3);
  const dp::TriangleMesh mesh(m.triangles, m.vertices());
  dp::ClothEnergy cloth(mesh, m.positions.data(), dp::ClothParameters{});
  dp::softenByRegion(cloth, mesh, m.positions.data(), thickness(0.5, 1.0), crease(0.25));
  const std::vector<double>& scales = cloth.stretchScales();
  ASSERT_EQ(scales.size(), mesh.edges().size());
  std::size_t gap = 0, far = 0;
  for (std::size_t e = 0; e < scales.size(); ++e)
  {
    const auto [i, j] = mesh.edges()[e];
    const double x = 0.5 * (m.positions[3 * i] + m.positions[3 * j]);
    if (x > 0.25 && x < 0.55)
    {
      EXPECT_NEAR(scales[e], 0.5 * 0.25, 1e-12) << "edge " << e << " at x " << x;
      ++gap;
    }
    if (x < 0.0 || x > 0.8)
    {
      EXPECT_NEAR(scales[e], 0.5, 1e-12) << "edge " << e << " at x " << x;
      ++far;
    }
  }
  EXPECT_GT(gap, 20u);
  EXPECT_GT(far, 1000u);
}

} // namespace
