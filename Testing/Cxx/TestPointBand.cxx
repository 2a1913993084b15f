// SPDX-License-Identifier: BSD-3-Clause
// PointBand: the sparse band the field's grids start from. Each point goes to the voxel whose
// centre is nearest (brute force over the voxels around it), the seeds are those voxels, the
// dilation is the Chebyshev ball of brute force, and the bound on the band's size is never
// below the band (and exact for an aligned cube of seeds).
#include "dp/field/PointBand.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <vector>

namespace
{

using Voxel = std::tuple<int, int, int>;

Voxel voxelTuple(const openvdb::Coord& c)
{
  return {c.x(), c.y(), c.z()};
}

std::set<Voxel> activeVoxels(const openvdb::FloatTree& tree)
{
  std::set<Voxel> out;
  for (auto it = tree.cbeginValueOn(); it; ++it)
  {
    EXPECT_TRUE(it.isVoxelValue()) << "a tile in the band";
    out.insert(voxelTuple(it.getCoord()));
  }
  return out;
}

// Every voxel within `reach` (Chebyshev) of a seed, by brute force.
std::set<Voxel> chebyshevBall(const std::set<Voxel>& seeds, int reach)
{
  std::set<Voxel> out;
  for (const auto& [x, y, z] : seeds)
    for (int i = -reach; i <= reach; ++i)
      for (int j = -reach; j <= reach; ++j)
        for (int k = -reach; k <= reach; ++k)
          out.insert({x + i, y + j, z + k});
  return out;
}

TEST(PointBand, EachPointGoesToTheVoxelWhoseCentreIsNearest)
{
  const double voxel = 0.37;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-5, 5);
  for (int i = 0; i < 2000; ++i)
  {
    const double p[3] = {u(rng), u(rng), u(rng)};
    double best = HUGE_VAL;
    openvdb::Coord nearest;
    const openvdb::Coord below(static_cast<int>(std::floor(p[0] / voxel)),
                               static_cast<int>(std::floor(p[1] / voxel)),
                               static_cast<int>(std::floor(p[2] / voxel)));
    for (int a = -1; a <= 2; ++a)
      for (int b = -1; b <= 2; ++b)
        for (int c = -1; c <= 2; ++c)
        {
          const openvdb::Coord v = below.offsetBy(a, b, c);
          const double d2 = std::pow(p[0] - v.x() * voxel, 2) + std::pow(p[1] - v.y() * voxel, 2) +
                            std::pow(p[2] - v.z() * voxel, 2);
          if (d2 < best)
          {
            best = d2;
            nearest = v;
          }
        }
    ASSERT_EQ(dp::support::voxelOf(p, voxel), nearest) << p[0] << " " << p[1] << " " << p[2];
  }
  // Half way between two centres, the upper one: the same on both sides of 0.
  const double half[3] = {0.125, -0.125, -0.375};
  EXPECT_EQ(dp::support::voxelOf(half, 0.25), openvdb::Coord(1, 0, -1));
}

TEST(PointBand, TheSeedsAreThePointsVoxelsAndTheDilationTheirChebyshevBall)
{
  const double voxel = 0.1;
  std::mt19937_64 rng(2);
  std::normal_distribution<double> g(0, 0.6);
  std::vector<double> points;
  for (int i = 0; i < 300; ++i)
    points.insert(points.end(), {g(rng), g(rng), g(rng)});
  points.insert(points.end(), {points[0], points[1], points[2]}); // a voxel seeded twice
  std::set<Voxel> expected;
  for (std::size_t i = 0; i < points.size() / 3; ++i)
    expected.insert(voxelTuple(dp::support::voxelOf(&points[3 * i], voxel)));

  for (int reach = 0; reach <= 3; ++reach)
  {
    openvdb::FloatTree tree(0.0f);
    dp::support::seedPointVoxels(tree, points.data(), points.size() / 3, voxel, 2.5f);
    ASSERT_EQ(activeVoxels(tree), expected);
    for (auto it = tree.cbeginValueOn(); it; ++it)
      ASSERT_EQ(*it, 2.5f);
    const double bound = dp::support::bandVoxelBound(tree, reach);
    dp::support::dilateBand(tree, reach);
    const std::set<Voxel> band = activeVoxels(tree);
    EXPECT_EQ(band, chebyshevBall(expected, reach)) << "reach " << reach;
    EXPECT_GE(bound, static_cast<double>(band.size())) << "reach " << reach;
    if (reach == 0)
    {
      EXPECT_EQ(bound, static_cast<double>(expected.size()));
    }
    // The bound counts whole blocks around the seeds' blocks: at most 27 per seed.
    EXPECT_LE(bound, 27.0 * static_cast<double>(expected.size()) * std::pow(std::max(reach, 1), 3));
  }
}

TEST(PointBand, TheBoundOfAnAlignedCubeOfSeedsIsExact)
{
  // Every voxel of [0, 20)^3 seeded, reach 2: blocks 0..9 per axis and one more each side make
  // 12^3 blocks of 2^3 voxels, the band itself [-2, 22)^3: 24^3 voxels both.
  openvdb::FloatTree tree(0.0f);
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j)
      for (int k = 0; k < 20; ++k)
        tree.setValueOn(openvdb::Coord(i, j, k), 1.0f);
  EXPECT_EQ(dp::support::bandVoxelBound(tree, 2), 24.0 * 24 * 24);
  dp::support::dilateBand(tree, 2);
  EXPECT_EQ(tree.activeVoxelCount(), 24u * 24 * 24);
  // A reach of 0 dilates nothing.
  dp::support::dilateBand(tree, 0);
  EXPECT_EQ(tree.activeVoxelCount(), 24u * 24 * 24);
}

} // namespace
