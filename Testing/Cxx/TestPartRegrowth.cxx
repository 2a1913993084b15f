// SPDX-License-Identifier: BSD-3-Clause
// PartRegrowth: the lost part of a mesh moved onto the points it left.

#include "dp/track/PartRegrowth.h"

#include "TrackingShapes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace
{

using dp::test::Frame;
using dp::test::Shape;
using dp::test::tube;

// The RMS distance between the vertices `which` of a and b.
double rmsOver(const std::vector<double>& a, const std::vector<double>& b,
               const std::vector<std::size_t>& which)
{
  double sum = 0;
  for (std::size_t v : which)
    for (int k = 0; k < 3; ++k)
      sum += (a[3 * v + k] - b[3 * v + k]) * (a[3 * v + k] - b[3 * v + k]);
  return std::sqrt(sum / static_cast<double>(which.size()));
}

TEST(PartRegrowth, MovesALimbThatTurnedAboutItsJointOntoItsPoints)
{
  // A tube whose upper 60 % turned by 1.5 rad about a joint at 40 % of its height: the mesh still
  // stands straight, far from the turned part's points. The lost part is moved onto them (within
  // a fifth of how far it was: measured 0.076 of 0.50); the rest of the mesh stays.
  const Shape rest = tube(30, 12);
  const std::size_t nv = rest.positions.size() / 3;
  double low = 1e300, high = -1e300, cx = 0;
  for (std::size_t v = 0; v < nv; ++v)
  {
    low = std::min(low, rest.positions[3 * v + 2]);
    high = std::max(high, rest.positions[3 * v + 2]);
    cx += rest.positions[3 * v] / static_cast<double>(nv);
  }
  const double joint = low + 0.4 * (high - low), angle = 1.5;
  std::vector<double> truth = rest.positions;
  std::vector<std::size_t> turned, still;
  for (std::size_t v = 0; v < nv; ++v)
  {
    const double u = rest.positions[3 * v] - cx, w = rest.positions[3 * v + 2] - joint;
    if (w <= 0)
    {
      if (w < -0.2 * (high - low)) // well below the joint
        still.push_back(v);
      continue;
    }
    turned.push_back(v);
    truth[3 * v] = cx + std::cos(angle) * u + std::sin(angle) * w;
    truth[3 * v + 2] = joint - std::sin(angle) * u + std::cos(angle) * w;
  }
  const Frame frame(truth, false, rest);
  const double reach = 3 * frame.voxel;
  const std::vector<double> moved =
      dp::regrowLostPart(*frame.data, frame.mesh, rest.positions, reach);
  ASSERT_EQ(moved.size(), rest.positions.size());
  const double before = rmsOver(rest.positions, truth, turned);
  const double after = rmsOver(moved, truth, turned);
  // A start for the coarse level, not a fit: the lost vertices and the unexplained points are
  // not the same stretch of the limb (the part near the joint is neither), so it lands near.
  EXPECT_GT(before, 8 * reach);
  EXPECT_LT(after, 0.2 * before) << "before " << before << ", after " << after;
  EXPECT_EQ(rmsOver(moved, rest.positions, still), 0.0) << "the part the data see moved";

  // Nothing lost: nothing to move.
  const Frame same(rest.positions, false, rest);
  EXPECT_TRUE(dp::regrowLostPart(*same.data, same.mesh, rest.positions, reach).empty());
}

} // namespace
