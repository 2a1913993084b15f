// SPDX-License-Identifier: BSD-3-Clause
// The header-only helpers of dp/support: the vector maths (Vec3) against their closed forms, the
// kd-tree (KdTree) against brute force, and the parallel loop (Parallel) visiting every index
// once with the same results on one thread as on all.
#include "dp/support/KdTree.h"
#include "dp/support/Parallel.h"
#include "dp/support/Vec3.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <utility>
#include <vector>

namespace
{

using dp::support::KdTree;
using dp::support::Vec3;

TEST(Vec3, OperatorsGiveTheirClosedForms)
{
  // Integer-valued vectors, so every result is exact.
  using dp::support::operator+;
  using dp::support::operator-;
  using dp::support::operator*;
  const Vec3 a{1, -2, 3}, b{4, 5, -6};
  EXPECT_EQ(a + b, (Vec3{5, 3, -3}));
  EXPECT_EQ(a - b, (Vec3{-3, -7, 9}));
  EXPECT_EQ(2.0 * a, (Vec3{2, -4, 6}));
  EXPECT_EQ(dp::support::dot(a, b), 4 - 10 - 18);
  EXPECT_EQ(dp::support::cross(Vec3{1, 0, 0}, Vec3{0, 1, 0}), (Vec3{0, 0, 1}));
  EXPECT_EQ(dp::support::cross(Vec3{0, 1, 0}, Vec3{1, 0, 0}), (Vec3{0, 0, -1}));
  EXPECT_EQ(dp::support::cross(a, b), (Vec3{-2 * -6 - 3 * 5, 3 * 4 - 1 * -6, 1 * 5 - -2 * 4}));
  EXPECT_EQ(dp::support::norm(Vec3{3, 4, 12}), 13.0);
}

TEST(Vec3, CrossIsOrthogonalWithLagrangesLength)
{
  // For random vectors: a x b is orthogonal to both, and |a x b|^2 = |a|^2 |b|^2 - (a.b)^2.
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int i = 0; i < 200; ++i)
  {
    const Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)};
    const Vec3 c = dp::support::cross(a, b);
    const double scale = dp::support::dot(a, a) * dp::support::dot(b, b);
    EXPECT_NEAR(dp::support::dot(c, a), 0, 1e-12 * std::sqrt(scale) * dp::support::norm(a));
    EXPECT_NEAR(dp::support::dot(c, b), 0, 1e-12 * std::sqrt(scale) * dp::support::norm(b));
    EXPECT_NEAR(dp::support::dot(c, c), scale - std::pow(dp::support::dot(a, b), 2), 1e-12 * scale);
  }
}

// Random points in the unit cube with some exact duplicates (ties for the searches).
std::vector<double> randomCloud(std::size_t count, unsigned seed)
{
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<double> points;
  for (std::size_t i = 0; i < count; ++i)
  {
    if (i % 50 == 49)
      points.insert(points.end(), {points[0], points[1], points[2]});
    else
      points.insert(points.end(), {u(rng), u(rng), u(rng)});
  }
  return points;
}

// The squared distance as the tree sums it (x, then y, then z).
double squaredDistance(const double* q, const double* p)
{
  return (q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) +
         (q[2] - p[2]) * (q[2] - p[2]);
}

TEST(KdTree, NearestPointsAreThoseBruteForceFinds)
{
  const std::vector<double> points = randomCloud(3000, 2);
  const std::size_t n = points.size() / 3;
  const KdTree tree(points.data(), n);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.2, 1.2);
  for (int i = 0; i < 200; ++i)
  {
    const double q[3] = {u(rng), u(rng), u(rng)};
    std::vector<double> all(n);
    for (std::size_t p = 0; p < n; ++p)
      all[p] = squaredDistance(q, &points[3 * p]);
    std::vector<double> sorted = all;
    std::sort(sorted.begin(), sorted.end());
    double d2 = -1;
    const std::uint32_t nearest = tree.nearest(q, &d2);
    ASSERT_LT(nearest, n);
    EXPECT_EQ(d2, sorted[0]);
    EXPECT_EQ(all[nearest], sorted[0]);
    // The k nearest: their distances are the k smallest, nearest first.
    const std::size_t k = 1 + static_cast<std::size_t>(i % 20);
    std::vector<std::uint32_t> indices(k);
    std::vector<double> distances(k);
    ASSERT_EQ(tree.nearest(q, k, indices.data(), distances.data()), k);
    for (std::size_t j = 0; j < k; ++j)
    {
      EXPECT_EQ(distances[j], sorted[j]) << j << " of " << k;
      EXPECT_EQ(all[indices[j]], distances[j]);
    }
    EXPECT_EQ(std::set<std::uint32_t>(indices.begin(), indices.end()).size(), k);
  }
}

TEST(KdTree, WithinFindsEveryPointUpToTheRadiusInclusive)
{
  // The radius is set to a point's own squared distance at times: that point must be found.
  const std::vector<double> points = randomCloud(2000, 4);
  const std::size_t n = points.size() / 3;
  const KdTree tree(points.data(), n);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<std::pair<std::uint32_t, double>> found;
  for (int i = 0; i < 100; ++i)
  {
    const double q[3] = {u(rng), u(rng), u(rng)};
    const std::size_t on = static_cast<std::size_t>(u(rng) * static_cast<double>(n));
    const double radius2 = i % 2 == 0 ? squaredDistance(q, &points[3 * on]) : 0.01 * u(rng);
    tree.within(q, radius2, found);
    std::set<std::uint32_t> expected;
    for (std::size_t p = 0; p < n; ++p)
      if (squaredDistance(q, &points[3 * p]) <= radius2)
        expected.insert(static_cast<std::uint32_t>(p));
    std::set<std::uint32_t> got;
    for (const auto& [index, d2] : found)
    {
      EXPECT_TRUE(got.insert(index).second) << "found twice: " << index;
      EXPECT_EQ(d2, squaredDistance(q, &points[3 * index]));
    }
    EXPECT_EQ(got, expected) << "query " << i << ", radius^2 " << radius2;
  }
  EXPECT_GT(tree.memoryBytes(), 0u);
}

TEST(KdTree, ASinglePointIsFoundFromAnywhere)
{
  const double point[3] = {0.5, -1, 2};
  const KdTree tree(point, 1);
  const double q[3] = {10, 10, 10};
  double d2 = 0;
  EXPECT_EQ(tree.nearest(q, &d2), 0u);
  EXPECT_EQ(d2, squaredDistance(q, point));
  std::uint32_t index[4];
  double distances[4];
  EXPECT_EQ(tree.nearest(q, 4, index, distances), 1u); // fewer than asked when there are fewer
}

// f(i) for every i: a value that depends on i alone.
double valueOf(std::size_t i)
{
  return std::sin(0.001 * static_cast<double>(i)) * std::sqrt(static_cast<double>(i) + 1);
}

TEST(Parallel, EveryIndexIsVisitedOnceForAnyCount)
{
  // Counts around the block size (128), none, and many blocks.
  for (std::size_t count : {0, 1, 127, 128, 129, 255, 256, 1000, 20000})
  {
    std::vector<std::atomic<int>> visits(count);
    for (auto& v : visits)
      v = 0;
    dp::forEachIndex(count, [&](std::size_t i) { ++visits[i]; });
    for (std::size_t i = 0; i < count; ++i)
      ASSERT_EQ(visits[i].load(), 1) << "index " << i << " of " << count;
  }
}

TEST(Parallel, OneThreadGivesTheSameBitsAsAll)
{
  // Each index writes its own entry: the results equal a plain loop's, bit for bit, on one
  // thread and on all.
  const std::size_t count = 50000;
  std::vector<double> serial(count);
  for (std::size_t i = 0; i < count; ++i)
    serial[i] = valueOf(i);
  std::vector<double> all(count, 0.0), one(count, 0.0);
  dp::forEachIndex(count, [&](std::size_t i) { all[i] = valueOf(i); });
  {
    const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    dp::forEachIndex(count, [&](std::size_t i) { one[i] = valueOf(i); });
  }
  EXPECT_EQ(all, serial);
  EXPECT_EQ(one, serial);
}

} // namespace
