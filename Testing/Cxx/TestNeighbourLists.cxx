// SPDX-License-Identifier: BSD-3-Clause
// nearestNeighbourLists against brute force on clouds that take each of its paths: a surface
// (the grid, first radius), uneven density (larger radii), far outliers (the kd-tree), repeated
// points, flat and tiny clouds; and the same lists on one thread as on two.
#include "dp/geometry/NeighbourLists.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>

namespace
{
// The k nearest of every point by sorting all distances, ties to the lower index.
std::vector<std::uint32_t> bruteForce(const std::vector<double>& points, std::size_t k)
{
  const std::size_t n = points.size() / 3;
  k = std::min(k, n);
  std::vector<std::uint32_t> ids;
  std::vector<std::pair<double, std::uint32_t>> all(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    for (std::size_t j = 0; j < n; ++j)
    {
      double d2 = 0;
      for (int a = 0; a < 3; ++a)
        d2 += std::pow(points[3 * i + a] - points[3 * j + a], 2);
      all[j] = {d2, static_cast<std::uint32_t>(j)};
    }
    std::partial_sort(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(k), all.end());
    for (std::size_t j = 0; j < k; ++j)
      ids.push_back(all[j].second);
  }
  return ids;
}

void expectBruteForce(const std::vector<double>& points, std::size_t k, const char* what)
{
  const dp::NeighbourLists lists = dp::nearestNeighbourLists(points.data(), points.size() / 3, k);
  const std::size_t kept = std::min(k, points.size() / 3);
  EXPECT_EQ(lists.k, kept) << what;
  EXPECT_EQ(lists.degree, std::vector<std::size_t>(points.size() / 3, kept)) << what;
  const std::vector<std::uint32_t> expected = bruteForce(points, k);
  // The lists are sets (in no particular order): compared sorted, point by point.
  std::size_t wrong = 0;
  for (std::size_t i = 0; i + kept <= expected.size() && kept > 0; i += kept)
  {
    std::vector<std::uint32_t> found(lists.ids.begin() + i, lists.ids.begin() + i + kept),
        truth(expected.begin() + i, expected.begin() + i + kept);
    std::sort(found.begin(), found.end());
    std::sort(truth.begin(), truth.end());
    wrong += found != truth;
  }
  EXPECT_EQ(wrong, 0u) << what << ": points whose neighbours differ from brute force";
}

// Points on a sphere of radius 1, denser around its north pole when `uneven`.
std::vector<double> sphere(std::size_t n, bool uneven, unsigned seed)
{
  std::mt19937 random(seed);
  std::normal_distribution<double> normal;
  std::vector<double> points;
  for (std::size_t i = 0; i < n; ++i)
  {
    double p[3] = {normal(random), normal(random), normal(random)};
    if (uneven && i % 2 == 0)
      p[2] = std::abs(p[2]) * 8 + 1;
    const double length = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (double c : p)
      points.push_back(c / length);
  }
  return points;
}
} // namespace

TEST(NeighbourLists, SurfacesFindWhatBruteForceFinds)
{
  expectBruteForce(sphere(3000, false, 1), 16, "even sphere");
  expectBruteForce(sphere(3000, true, 2), 16, "uneven sphere");
  expectBruteForce(sphere(2000, false, 3), 5, "k = 5");
}

TEST(NeighbourLists, OutliersRepeatsAndFlatCloudsFindWhatBruteForceFinds)
{
  std::vector<double> outliers = sphere(2000, false, 4);
  for (double far : {40.0, -300.0, 1e4})
    outliers.insert(outliers.end(), {far, 0.5 * far, 1.0});
  expectBruteForce(outliers, 16, "sphere and far outliers");
  // A few points inside the sphere: the grid suits the sphere, their neighbours are beyond the
  // grid's largest radius (the kd-tree answers for them).
  std::vector<double> inside = sphere(3000, false, 8);
  inside.insert(inside.end(), {0, 0, 0, 0.1, 0, 0, 0, -0.1, 0.05, -0.1, 0.1, 0, 0, 0, 0.1});
  expectBruteForce(inside, 16, "sphere and points inside");

  // Every point four times (distance ties), and a cloud of one repeated point.
  std::vector<double> repeated;
  const std::vector<double> base = sphere(500, false, 5);
  for (int copy = 0; copy < 4; ++copy)
    repeated.insert(repeated.end(), base.begin(), base.end());
  expectBruteForce(repeated, 16, "repeated points");
  expectBruteForce(std::vector<double>(3 * 50, 0.25), 16, "one point fifty times");

  std::vector<double> flat;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j)
      flat.insert(flat.end(), {0.01 * i, 0.013 * j + 0.001 * (i % 3), 2.0});
  expectBruteForce(flat, 16, "a flat grid (ties)");

  for (std::size_t n : {1, 2, 15, 16, 17})
    expectBruteForce(std::vector<double>(sphere(n, false, 6)), 16, "a tiny cloud");
  EXPECT_TRUE(dp::nearestNeighbourLists(nullptr, 0, 16).ids.empty());
}

TEST(NeighbourLists, ANaNOrInfinitePointNeitherCrashesNorJoinsTheOthersLists)
{
  // Callers check coordinates first (FrameData); here the lists only must stay in bounds.
  for (const double bad : {std::nan(""), HUGE_VAL})
  {
    std::vector<double> points = sphere(500, false, 10);
    points[3 * 7 + 1] = bad;
    const dp::NeighbourLists lists = dp::nearestNeighbourLists(points.data(), 500, 16);
    for (std::size_t i = 0; i < 500; ++i)
    {
      ASSERT_LE(lists.degree[i], 16u);
      for (std::size_t j = 0; j < lists.degree[i]; ++j)
      {
        ASSERT_LT(lists.ids[16 * i + j], 500u);
        if (i != 7)
        {
          EXPECT_NE(lists.ids[16 * i + j], 7u) << "point " << i << ", coordinate " << bad;
        }
      }
    }
  }
}

TEST(NeighbourLists, OneThreadGivesWhatTwoGive)
{
  const std::vector<double> points = sphere(20000, true, 7);
  const dp::NeighbourLists two = dp::nearestNeighbourLists(points.data(), 20000, 16);
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const dp::NeighbourLists single = dp::nearestNeighbourLists(points.data(), 20000, 16);
  EXPECT_EQ(single.ids, two.ids);
}
