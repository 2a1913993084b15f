// SPDX-License-Identifier: BSD-3-Clause
// OutsideBand and interpolateHoles on grids built by hand: a spherical shell's band (the
// reconstruction's plane distances, in voxels) separates an inside from an outside, whose signs
// settle every value off the band and every border voxel, also under a cap of wrong signs; a
// sheet's band separates nothing and is open; holes take the harmonic interpolation (a linear
// field exactly) unless they meet one side only.
#include "dp/field/OutsideBand.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>
#include <vector>

namespace
{

using dp::support::OutsideBand;

constexpr float Background = 3;

double radius(const openvdb::Coord& v)
{
  return std::sqrt(double(v.x()) * v.x() + double(v.y()) * v.y() + double(v.z()) * v.z());
}

// The voxels of a shell of radius R (voxels) and half width 2, switched on.
openvdb::FloatGrid::Ptr shell(double R)
{
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(Background);
  auto acc = grid->getAccessor();
  const int n = static_cast<int>(R) + 4;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = -n; k <= n; ++k)
        if (std::abs(radius(openvdb::Coord(i, j, k)) - R) <= 2)
          acc.setValueOn(openvdb::Coord(i, j, k), 0.0f);
  return grid;
}

// Each active voxel's value, as the reconstruction evaluates the band once OutsideBand has made
// its cells whole: `value` of the voxel, clamped to the background.
void evaluate(openvdb::FloatGrid& grid, const std::function<double(const openvdb::Coord&)>& value)
{
  for (auto it = grid.beginValueOn(); it; ++it)
    it.setValue(static_cast<float>(
        std::clamp(value(it.getCoord()), -double(Background), double(Background))));
}

// Every active voxel next to an inactive one (the border of the band's cells, which the
// constructor made whole) has the sign of the side the inactive one is on.
void expectBorderAgreesWithSides(const openvdb::FloatGrid& grid, const OutsideBand& outside)
{
  auto acc = grid.getConstAccessor();
  std::size_t checked = 0;
  for (auto it = grid.cbeginValueOn(); it; ++it)
    for (int axis = 0; axis < 3; ++axis)
      for (int side = -1; side <= 1; side += 2)
      {
        openvdb::Coord u = it.getCoord();
        u[axis] += side;
        if (acc.isValueOn(u))
          continue;
        const int sign = outside.side(u);
        ASSERT_NE(sign, 0) << "an inactive voxel in the band at " << u;
        ASSERT_EQ(*it < 0, sign < 0) << "border voxel " << it.getCoord() << " holds " << *it;
        ++checked;
      }
  EXPECT_GT(checked, 1000u);
}

TEST(OutsideBand, AClosedShellHasAnInsideAndAnOutsideThatSettleEveryValueOffTheBand)
{
  for (const bool wrongCap : {false, true})
  {
    // The signed distance r - R, turned around on the cap z > 0.7 R when `wrongCap`.
    const double R = 10.5;
    openvdb::FloatGrid::Ptr grid = shell(R);
    OutsideBand outside(*grid);
    evaluate(*grid,
             [&](const openvdb::Coord& v)
             {
               const double d = radius(v) - R;
               return wrongCap && v.z() > 0.7 * R ? -d : d;
             });
    outside.findPieces(*grid);
    EXPECT_FALSE(outside.open()) << "wrong cap " << wrongCap;
    EXPECT_EQ(outside.side(openvdb::Coord(0, 0, 0)), -1);
    EXPECT_EQ(outside.side(openvdb::Coord(0, 3, -2)), -1);
    EXPECT_EQ(outside.side(openvdb::Coord(20, 0, 0)), 1);
    EXPECT_EQ(outside.side(openvdb::Coord(500, -500, 7)), 1); // beyond the cells: the outside
    EXPECT_EQ(outside.side(openvdb::Coord(0, 11, 0)), 0);     // in the band
    // The border voxels of both pieces, inside where they are inside the sphere.
    std::vector<std::pair<openvdb::Coord, bool>> border;
    outside.borderOfSettledPieces(border);
    std::size_t inner = 0;
    for (const auto& [voxel, inside] : border)
    {
      EXPECT_EQ(inside, radius(voxel) < R) << voxel;
      inner += inside;
    }
    EXPECT_GT(inner, 500u);
    EXPECT_GT(border.size() - inner, 500u);

    outside.settle(*grid, Background);
    auto acc = grid->getConstAccessor();
    EXPECT_EQ(acc.getValue(openvdb::Coord(0, 0, 0)), -Background);
    EXPECT_EQ(acc.getValue(openvdb::Coord(2, -4, 1)), -Background);
    EXPECT_EQ(acc.getValue(openvdb::Coord(30, 30, 30)), Background);
    EXPECT_EQ(grid->background(), Background);
    expectBorderAgreesWithSides(*grid, outside);
    // The band's own values away from its border are kept: the shell's middle, right or wrong.
    const float middle = acc.getValue(openvdb::Coord(11, 0, 0)); // r - R = 0.5
    EXPECT_FLOAT_EQ(middle, 0.5f);
  }
}

TEST(OutsideBand, AnOpenSheetSeparatesNothingAndKeepsItsValues)
{
  // A square sheet: its band |z| <= 2 holds z + 1/4. The space around it is one piece whose
  // border is half positive, half negative: open data, whose border settle leaves alone.
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(Background);
  auto acc = grid->getAccessor();
  for (int i = -15; i <= 15; ++i)
    for (int j = -15; j <= 15; ++j)
      for (int k = -2; k <= 2; ++k)
        acc.setValueOn(openvdb::Coord(i, j, k), 0.0f);
  OutsideBand outside(*grid);
  evaluate(*grid, [](const openvdb::Coord& v) { return v.z() + 0.25; });
  outside.findPieces(*grid);
  EXPECT_TRUE(outside.open());
  std::vector<std::pair<openvdb::Coord, bool>> border;
  outside.borderOfSettledPieces(border);
  EXPECT_TRUE(border.empty());
  outside.settle(*grid, Background);
  EXPECT_EQ(acc.getValue(openvdb::Coord(3, 4, -2)), -1.75f);
  EXPECT_EQ(acc.getValue(openvdb::Coord(3, 4, 2)), 2.25f);
  EXPECT_EQ(acc.getValue(openvdb::Coord(3, 4, -1)), -0.75f);
}

// A box [0, 15]^3 of band voxels holding f, with the voxels of `holes` unknown.
openvdb::FloatGrid::Ptr boxWithHoles(const std::function<float(int, int, int)>& f,
                                     const std::vector<openvdb::Coord>& holes)
{
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(Background);
  auto acc = grid->getAccessor();
  for (int i = 0; i <= 15; ++i)
    for (int j = 0; j <= 15; ++j)
      for (int k = 0; k <= 15; ++k)
        acc.setValueOn(openvdb::Coord(i, j, k), f(i, j, k));
  for (const openvdb::Coord& h : holes)
    acc.setValueOn(h, dp::support::UnknownHoleValue);
  return grid;
}

std::vector<openvdb::Coord> block(int x0, int x1, int y0, int y1, int z0, int z1)
{
  std::vector<openvdb::Coord> out;
  for (int i = x0; i <= x1; ++i)
    for (int j = y0; j <= y1; ++j)
      for (int k = z0; k <= z1; ++k)
        out.emplace_back(i, j, k);
  return out;
}

float linear(int i, int j, int k)
{
  return 0.1f * i - 0.2f * j + 0.3f * k - 0.5f;
}

TEST(OutsideBand, AHoleInsideTheBandTakesTheHarmonicInterpolation)
{
  // A linear field is harmonic: the interpolation across a hole is that field itself.
  const std::vector<openvdb::Coord> holes = block(4, 10, 5, 9, 3, 11);
  openvdb::FloatGrid::Ptr grid = boxWithHoles(linear, holes);
  dp::support::interpolateHoles(*grid, holes, Background);
  auto acc = grid->getConstAccessor();
  for (const openvdb::Coord& h : holes)
    EXPECT_NEAR(acc.getValue(h), linear(h.x(), h.y(), h.z()), 1e-4) << h;
  EXPECT_EQ(acc.getValue(openvdb::Coord(3, 5, 3)), linear(3, 5, 3)); // the band is kept
  // No holes: nothing changes (a hole's voxel keeps its unknown value).
  openvdb::FloatGrid::Ptr untouched = boxWithHoles(linear, holes);
  dp::support::interpolateHoles(*untouched, {}, Background);
  EXPECT_EQ(untouched->getConstAccessor().getValue(holes[0]), dp::support::UnknownHoleValue);
}

TEST(OutsideBand, AHoleThatMeetsOneSideOnlyTakesThatSide)
{
  // A hole at the box's face meets the outside (the background, positive) there. Where the band
  // around it is positive too (a hollow of the outside), it is outside: the background. Where the
  // band is negative, it is a real hole between the sides: a membrane from one to the other.
  const std::vector<openvdb::Coord> holes = block(0, 2, 5, 9, 5, 9);
  for (const float band : {1.0f, -1.0f})
  {
    openvdb::FloatGrid::Ptr grid = boxWithHoles([band](int, int, int) { return band; }, holes);
    dp::support::interpolateHoles(*grid, holes, Background);
    auto acc = grid->getConstAccessor();
    for (const openvdb::Coord& h : holes)
    {
      const float v = acc.getValue(h);
      if (band > 0)
      {
        EXPECT_EQ(v, Background) << h;
      }
      else
      {
        EXPECT_GT(v, -1.0f) << h;
        EXPECT_LT(v, Background) << h;
      }
    }
    if (band < 0)
    {
      // The membrane rises toward the outside: larger at the face than deeper in.
      EXPECT_GT(acc.getValue(openvdb::Coord(0, 7, 7)), acc.getValue(openvdb::Coord(2, 7, 7)));
    }
  }
}

} // namespace
