// SPDX-License-Identifier: BSD-3-Clause
// Normal estimation: estimated normals against the surface's, orientation per separate part, the
// orientation tree and its mending against a reference.
#include "dp/geometry/NormalEstimation.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

namespace
{

struct Cloud
{
  std::vector<double> points;
  std::vector<float> normals;
};

Cloud tubeCloud(std::size_t n, std::size_t frame = 7)
{
  dp::BendingTube tube;
  dp::SamplerOptions o;
  o.pointsPerFrame = n;
  const dp::PointCloud pc = dp::sampleSurface(tube.positions(frame), tube.triangles(), o, frame);
  return {pc.points, pc.normals};
}

TEST(Normals, EstimatedNormalsMatchTheSurfaceAndPointOutward)
{
  const Cloud c = tubeCloud(20000, 0);
  const std::vector<float> estimated = dp::estimateNormals(c.points.data(), c.points.size() / 3);
  ASSERT_EQ(estimated.size(), c.normals.size());
  std::size_t aligned = 0, outward = 0;
  const std::size_t n = c.points.size() / 3;
  for (std::size_t i = 0; i < n; ++i)
  {
    const double dot = estimated[3 * i] * c.normals[3 * i] +
                       estimated[3 * i + 1] * c.normals[3 * i + 1] +
                       estimated[3 * i + 2] * c.normals[3 * i + 2];
    aligned += std::abs(dot) > 0.9;
    outward += dot > 0;
  }
  EXPECT_GT(static_cast<double>(aligned) / static_cast<double>(n), 0.95);
  EXPECT_GT(static_cast<double>(outward) / static_cast<double>(n), 0.95);
}

TEST(Normals, EachSeparatePartIsOrientedAndReportedOnItsOwn)
{
  // Two spheres far apart: two parts of the neighbour graph, each oriented outward from its own
  // largest-x point, and no part label shared between them (the tracker votes on the
  // orientation part by part).
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g;
  std::vector<double> points, outward;
  for (int i = 0; i < 4000; ++i)
  {
    double v[3] = {g(rng), g(rng), g(rng)};
    const double r = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    const double shift = i < 2000 ? 0.0 : 3.0;
    for (int c = 0; c < 3; ++c)
    {
      points.push_back(0.5 * v[c] / r + (c == 0 ? shift : 0.0));
      outward.push_back(v[c] / r);
    }
  }
  std::vector<std::uint32_t> parts;
  const std::vector<float> normals = dp::estimateNormals(points.data(), 4000, 16, &parts);
  ASSERT_EQ(parts.size(), 4000u);
  std::size_t right = 0;
  for (std::size_t i = 0; i < 4000; ++i)
    right += normals[3 * i] * outward[3 * i] + normals[3 * i + 1] * outward[3 * i + 1] +
                 normals[3 * i + 2] * outward[3 * i + 2] >
             0;
  EXPECT_GT(right, 3900u);
  std::vector<std::uint32_t> first(parts.begin(), parts.begin() + 2000);
  std::vector<std::uint32_t> second(parts.begin() + 2000, parts.end());
  std::sort(first.begin(), first.end());
  std::sort(second.begin(), second.end());
  std::vector<std::uint32_t> shared;
  std::set_intersection(first.begin(), first.end(), second.begin(), second.end(),
                        std::back_inserter(shared));
  EXPECT_TRUE(shared.empty());
}

// Points on a sphere of radius 0.5 about the origin, and their outward normals.
void spherePoints(std::size_t n, std::vector<double>& points, std::vector<double>& outward)
{
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  for (std::size_t i = 0; i < n; ++i)
  {
    double v[3] = {g(rng), g(rng), g(rng)};
    const double r = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int c = 0; c < 3; ++c)
    {
      points.push_back(0.5 * v[c] / r);
      outward.push_back(v[c] / r);
    }
  }
}

bool pointsOutward(const std::vector<float>& normals, const std::vector<double>& outward,
                   std::size_t i)
{
  return normals[3 * i] * outward[3 * i] + normals[3 * i + 1] * outward[3 * i + 1] +
             normals[3 * i + 2] * outward[3 * i + 2] >
         0;
}

// The points of the branch below `top`: the point and everything oriented from it.
std::vector<char> branchBelow(const dp::OrientationTree& tree, std::uint32_t top)
{
  std::vector<char> below(tree.parent.size(), 0);
  for (std::uint32_t p : tree.order)
    below[p] = p == top || (tree.parent[p] != p && below[tree.parent[p]]);
  return below;
}

TEST(Normals, TheOrientationTreeReachesEveryPointParentsFirst)
{
  std::vector<double> points, outward;
  spherePoints(3000, points, outward);
  for (std::size_t i = 1500; i < 3000; ++i)
    points[3 * i] += 3.0; // a second sphere, far away: a second tree
  dp::OrientationTree tree;
  dp::estimateNormals(points.data(), 3000, 16, nullptr, &tree);
  ASSERT_EQ(tree.parent.size(), 3000u);
  ASSERT_EQ(tree.order.size(), 3000u);
  std::vector<int> place(3000, -1);
  for (std::size_t k = 0; k < tree.order.size(); ++k)
  {
    ASSERT_EQ(place[tree.order[k]], -1) << "point " << tree.order[k] << " listed twice";
    place[tree.order[k]] = static_cast<int>(k);
  }
  std::size_t seeds = 0;
  for (std::uint32_t p = 0; p < 3000; ++p)
    if (tree.parent[p] == p)
      ++seeds;
    else
    {
      EXPECT_LT(place[tree.parent[p]], place[p]) << "point " << p << " before its parent";
      EXPECT_EQ(tree.parent[p] < 1500, p < 1500) << "an edge between the spheres";
    }
  EXPECT_EQ(seeds, 2u);
}

// A sphere's estimated normals with one branch of the orientation tree turned inward (what a
// wrong step across a sharp edge does), and votes from the true surface on every 5th point.
struct TurnedBranch
{
  std::vector<double> points, outward;
  std::vector<float> normals;
  dp::OrientationTree tree;
  std::vector<std::uint32_t> parts;
  std::vector<char> below;
  std::size_t branchSize = 0;

  TurnedBranch()
  {
    spherePoints(4000, points, outward);
    normals = dp::estimateNormals(points.data(), 4000, 16, &parts, &tree);
    for (std::size_t i = 0; i < 4000; ++i) // all outward to start with (nearly all are)
      if (!pointsOutward(normals, outward, i))
        for (int c = 0; c < 3; ++c)
          normals[3 * i + c] = -normals[3 * i + c];
    std::fill(parts.begin(), parts.end(), 0u); // one part: only the branch is wrong
    // A branch of 300 to 1500 points, late in the order (a deep one).
    for (auto it = tree.order.rbegin(); it != tree.order.rend() && branchSize == 0; ++it)
    {
      below = branchBelow(tree, *it);
      const auto size = static_cast<std::size_t>(std::count(below.begin(), below.end(), 1));
      if (size >= 300 && size <= 1500)
        branchSize = size;
    }
  }
  void turn(bool inside)
  {
    for (std::size_t i = 0; i < 4000; ++i)
      if ((below[i] != 0) == inside)
        for (int c = 0; c < 3; ++c)
          normals[3 * i + c] = -normals[3 * i + c];
  }
  std::vector<std::int8_t> votes() const
  {
    std::vector<std::int8_t> v(4000, dp::NotAsked);
    for (std::size_t i = 0; i < 4000; i += 5)
      v[i] = pointsOutward(normals, outward, i) ? 1 : -1;
    return v;
  }
  std::size_t outwardCount() const
  {
    std::size_t n = 0;
    for (std::size_t i = 0; i < 4000; ++i)
      n += pointsOutward(normals, outward, i);
    return n;
  }
};

TEST(Normals, MendTurnsTheBranchAReferenceDisagreesWith)
{
  TurnedBranch b;
  ASSERT_GT(b.branchSize, 0u);
  std::vector<std::int8_t> votes = b.votes();
  EXPECT_EQ(dp::mendOrientation(b.tree, b.parts, votes, b.normals.data()), 0u)
      << "nothing to mend when all agree";

  b.turn(true);
  ASSERT_EQ(b.outwardCount(), 4000 - b.branchSize);
  // Where exactly the cut falls between the last vote for and the first against is not known
  // from the votes: a few unasked points either side of it may go either way.
  constexpr std::size_t Slack = 20;
  votes = b.votes();
  std::size_t turned = dp::mendOrientation(b.tree, b.parts, votes, b.normals.data());
  EXPECT_NEAR(static_cast<double>(turned), static_cast<double>(b.branchSize), Slack);
  EXPECT_GE(b.outwardCount(), 4000 - Slack);
  for (std::size_t i = 0; i < 4000; i += 5)
  {
    EXPECT_EQ(votes[i], 1) << "the votes are turned with the normals";
    EXPECT_TRUE(pointsOutward(b.normals, b.outward, i)) << "asked point " << i;
  }

  // The rest of the part wrong and the branch right (the seed's side turned): the rest turns.
  TurnedBranch c;
  c.turn(false);
  votes = c.votes();
  turned = dp::mendOrientation(c.tree, c.parts, votes, c.normals.data());
  EXPECT_NEAR(static_cast<double>(turned), static_cast<double>(4000 - c.branchSize), Slack);
  EXPECT_GE(c.outwardCount(), 4000 - Slack);
}

TEST(Normals, MendLeavesWhatTheReferenceBarelyMeets)
{
  TurnedBranch b;
  ASSERT_GT(b.branchSize, 0u);
  b.turn(true);
  // The reference silent on most of the branch's points (it is elsewhere): no cut.
  std::vector<std::int8_t> votes = b.votes();
  std::size_t kept = 0;
  for (std::size_t i = 0; i < 4000; i += 5)
    if (b.below[i] && kept++ % 3 != 0)
      votes[i] = 0;
  EXPECT_EQ(dp::mendOrientation(b.tree, b.parts, votes, b.normals.data()), 0u);
  // Votes that are noise (a coin each): no side is clear, no cut either.
  std::mt19937 coin(7);
  for (std::size_t i = 0; i < 4000; i += 5)
    votes[i] = coin() % 2 == 0 ? 1 : -1;
  EXPECT_EQ(dp::mendOrientation(b.tree, b.parts, votes, b.normals.data()), 0u);
  // Too few votes to tell.
  dp::MendOptions strict;
  strict.minimumVotes = b.branchSize; // more than the branch's asked points
  votes = b.votes();
  EXPECT_EQ(dp::mendOrientation(b.tree, b.parts, votes, b.normals.data(), strict), 0u);
  EXPECT_EQ(b.outwardCount(), 4000 - b.branchSize);
}

} // namespace
