// SPDX-License-Identifier: BSD-3-Clause
// The dense distance image against brute-force nearest points: exact within the band, a close
// upper bound beyond it, points outside the image, the same bits on one thread and on all, and
// bad arguments refused with the problem named.
#include "dp/field/DistanceImage.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{

// Points on a sphere of radius 0.5 around the origin.
std::vector<double> spherePoints(std::size_t n, unsigned seed)
{
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  std::vector<double> out;
  for (std::size_t i = 0; i < n; ++i)
  {
    double p[3] = {g(rng), g(rng), g(rng)};
    const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (double c : p)
      out.push_back(0.5 * c / r);
  }
  return out;
}

dp::ImageGrid cube(int size, double half)
{
  dp::ImageGrid grid;
  grid.dimensions = {size, size, size};
  grid.origin = {-half, -half, -half};
  const double h = 2 * half / (size - 1);
  grid.spacing = {h, h, h};
  return grid;
}

std::array<double, 3> voxelCentre(const dp::ImageGrid& grid, std::size_t v)
{
  const std::size_t nx = static_cast<std::size_t>(grid.dimensions[0]);
  const std::size_t ny = static_cast<std::size_t>(grid.dimensions[1]);
  return {grid.origin[0] + static_cast<double>(v % nx) * grid.spacing[0],
          grid.origin[1] + static_cast<double>((v / nx) % ny) * grid.spacing[1],
          grid.origin[2] + static_cast<double>(v / (nx * ny)) * grid.spacing[2]};
}

double distance(const std::array<double, 3>& x, const double* p)
{
  return std::sqrt((x[0] - p[0]) * (x[0] - p[0]) + (x[1] - p[1]) * (x[1] - p[1]) +
                   (x[2] - p[2]) * (x[2] - p[2]));
}

// The brute-force nearest distance of every voxel.
std::vector<double> exactDistances(const std::vector<double>& points, const dp::ImageGrid& grid)
{
  std::vector<double> out(grid.voxelCount());
  for (std::size_t v = 0; v < out.size(); ++v)
  {
    const auto x = voxelCentre(grid, v);
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t p = 0; p < points.size(); p += 3)
      best = std::min(best, distance(x, &points[p]));
    out[v] = best;
  }
  return out;
}

TEST(DistanceImage, ExactInTheBandAndACloseUpperBoundBeyond)
{
  const std::vector<double> points = spherePoints(2000, 1);
  const dp::ImageGrid grid = cube(33, 0.6);
  const double voxel = grid.spacing[0], band = 2.5 * voxel;
  const dp::DistanceImage image = dp::computeDistanceImage(points.data(), 2000, grid, band);
  const std::vector<double> exact = exactDistances(points, grid);
  std::size_t inBand = 0, beyond = 0;
  double worst = 0, sum2 = 0;
  for (std::size_t v = 0; v < exact.size(); ++v)
  {
    const auto x = voxelCentre(grid, v);
    // The reported distance is the distance to the reported point.
    ASSERT_NEAR(image.distance[v], distance(x, &points[3 * image.nearest[v]]), 1e-6);
    if (exact[v] <= band * (1 - 1e-9))
    {
      ++inBand;
      ASSERT_EQ(image.exact[v], 1) << "voxel " << v;
      ASSERT_NEAR(image.distance[v], exact[v], 1e-6) << "voxel " << v;
    }
    else
    {
      ++beyond;
      EXPECT_EQ(image.exact[v], 0) << "voxel " << v;
      const double error = image.distance[v] - exact[v];
      ASSERT_GE(error, -1e-6) << "voxel " << v; // a real point: never nearer than the nearest
      worst = std::max(worst, error);
      sum2 += error * error;
    }
  }
  EXPECT_GT(inBand, 3000u);
  EXPECT_GT(beyond, 20000u);
  EXPECT_EQ(image.bandVoxels, inBand);
  EXPECT_LT(worst, 1.0 * voxel);
  EXPECT_LT(std::sqrt(sum2 / static_cast<double>(beyond)), 0.15 * voxel);
}

TEST(DistanceImage, FindsPointsOutsideTheImage)
{
  // Two points inside and one far outside to the right: voxels on the right face are nearer to
  // the outside point than to any seed in the image.
  const std::vector<double> points = {-0.5, 0, 0, -0.4, 0.1, 0, 1.5, 0, 0};
  const dp::ImageGrid grid = cube(21, 1.0);
  const dp::DistanceImage image = dp::computeDistanceImage(points.data(), 3, grid, 0.1);
  const std::vector<double> exact = exactDistances(points, grid);
  for (std::size_t v = 0; v < exact.size(); ++v)
    ASSERT_NEAR(image.distance[v], exact[v], 1e-6) << "voxel " << v;
  const std::size_t rightCentre = 20 + 21 * (10 + 21 * 10);
  EXPECT_EQ(image.nearest[rightCentre], 2);
}

TEST(DistanceImage, SameBitsOnOneThreadAndOnAll)
{
  std::vector<double> points = spherePoints(5000, 2);
  // Duplicates: ties go to the lower index whatever the order the threads visit them in.
  points.insert(points.end(), points.begin(), points.begin() + 3000);
  const dp::ImageGrid grid = cube(40, 0.7);
  const dp::DistanceImage all =
      dp::computeDistanceImage(points.data(), points.size() / 3, grid, 0.05);
  dp::DistanceImage one;
  {
    tbb::global_control oneThread(tbb::global_control::max_allowed_parallelism, 1);
    one = dp::computeDistanceImage(points.data(), points.size() / 3, grid, 0.05);
  }
  EXPECT_EQ(all.distance, one.distance);
  EXPECT_EQ(all.nearest, one.nearest);
  EXPECT_EQ(all.exact, one.exact);
  for (std::int64_t p : all.nearest)
    ASSERT_LT(p, 5000); // a duplicate never wins over its original
}

TEST(DistanceImage, ExactOnAStretchedGridInAnyPointOrderAndIntoTheCallersArrays)
{
  // A grid whose axes differ (the band reaches a different number of rows along each), points
  // partly beyond it, once in their order and once reversed.
  const std::vector<double> points = spherePoints(3000, 4);
  dp::ImageGrid grid;
  grid.dimensions = {37, 23, 17};
  grid.origin = {-0.55, -0.45, -0.4};
  grid.spacing = {0.03, 0.045, 0.05};
  const double band = 0.11;
  const dp::DistanceImage image = dp::computeDistanceImage(points.data(), 3000, grid, band);
  const std::vector<double> exact = exactDistances(points, grid);
  std::size_t inBand = 0;
  for (std::size_t v = 0; v < exact.size(); ++v)
  {
    ASSERT_EQ(image.exact[v], exact[v] <= band ? 1 : 0) << "voxel " << v;
    if (exact[v] <= band)
    {
      ++inBand;
      ASSERT_NEAR(image.distance[v], exact[v], 1e-6) << "voxel " << v;
    }
    ASSERT_GE(image.distance[v], exact[v] - 1e-6) << "voxel " << v;
  }
  EXPECT_EQ(image.bandVoxels, inBand);
  EXPECT_GT(inBand, exact.size() / 10);

  std::vector<double> reversed;
  for (std::size_t p = 3000; p-- > 0;)
    reversed.insert(reversed.end(), &points[3 * p], &points[3 * p + 3]);
  std::vector<float> distance(grid.voxelCount());
  std::vector<std::uint32_t> nearest(grid.voxelCount());
  std::vector<std::uint8_t> flags(grid.voxelCount());
  std::vector<float> gradient(3 * grid.voxelCount(), -7.0f);
  const dp::DistanceImageBand result = dp::computeDistanceImage(
      reversed.data(), 3000, grid, band,
      {grid.voxelCount(), distance.data(), nearest.data(), flags.data(), gradient.data()});
  EXPECT_EQ(result.bandVoxels, image.bandVoxels);
  EXPECT_EQ(distance, image.distance);
  EXPECT_EQ(flags, image.exact);
  for (std::size_t v = 0; v < nearest.size(); ++v)
  {
    for (int c = 0; c < 3; ++c) // the same point (no duplicates: indices map one to one)
      ASSERT_EQ(reversed[3 * nearest[v] + c], points[3 * image.nearest[v] + c]) << "voxel " << v;
    // The gradient: the unit vector from the nearest point to the voxel's centre (in single
    // precision: coordinates rounded by 6e-8 make an error of about that over the distance).
    const auto x = voxelCentre(grid, v);
    const double* p = &reversed[3 * nearest[v]];
    for (int c = 0; c < 3; ++c)
      ASSERT_NEAR(gradient[3 * v + c], (x[c] - p[c]) / distance[v], 1e-6 + 2e-7 / distance[v])
          << "voxel " << v;
  }

  EXPECT_THROW(dp::computeDistanceImage(
                   points.data(), 3000, grid, band,
                   {grid.voxelCount() - 1, distance.data(), nearest.data(), flags.data()}),
               std::invalid_argument);
}

TEST(DistanceImage, RefusesBadArgumentsNamingTheProblem)
{
  const std::vector<double> points = spherePoints(10, 3);
  const dp::ImageGrid grid = cube(8, 1.0);
  auto message = [&](const double* p, std::size_t n, const dp::ImageGrid& g, double band)
  {
    try
    {
      dp::computeDistanceImage(p, n, g, band);
    }
    catch (const std::invalid_argument& e)
    {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(points.data(), 0, grid, 0.1).find("no points"), std::string::npos);
  EXPECT_NE(message(points.data(), 10, grid, -1).find("band width"), std::string::npos);
  EXPECT_NE(message(points.data(), 10, grid, std::nan("")).find("band width"), std::string::npos);
  dp::ImageGrid flat = grid;
  flat.dimensions[1] = 0;
  EXPECT_NE(message(points.data(), 10, flat, 0.1).find("dimension 1"), std::string::npos);
  dp::ImageGrid zero = grid;
  zero.spacing[2] = 0;
  EXPECT_NE(message(points.data(), 10, zero, 0.1).find("spacing"), std::string::npos);
  std::vector<double> bad = points;
  bad[3 * 4 + 1] = std::numeric_limits<double>::infinity();
  EXPECT_NE(message(bad.data(), 10, grid, 0.1).find("point 4"), std::string::npos);
}

} // namespace
