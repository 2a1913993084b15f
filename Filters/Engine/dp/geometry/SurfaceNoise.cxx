// SPDX-License-Identifier: BSD-3-Clause
// A cloud's noise measured in itself (SurfaceNoise.h).
#include "dp/geometry/SurfaceNoise.h"

#include "dp/support/KdTree.h"
#include "dp/support/Parallel.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace dp
{

namespace
{

constexpr std::size_t SampleSize = 2000;
constexpr double Pi = 3.141592653589793;
// A stray point: its k-th neighbour this many times as far as usual, or this many thicknesses
// (and a spacing) off its neighbours' plane.
constexpr double IsolatedReach = 3, OffLayer = 4;

double median(std::vector<double> values)
{
  if (values.empty())
    return 0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// Around one sample: the RMS distance of its neighbours from their plane, the spacing they
// would have on one surface, the k-th neighbour's distance, the sample's distance from the
// plane and to its nearest other point.
struct Neighbourhood
{
  double residual = -1, spacing = 0, reach = 0, offPlane = 0, nearest = 0;
};

Neighbourhood around(const double* points, const double* x, const std::uint32_t* ids,
                     const double* d2, std::size_t found)
{
  Neighbourhood n;
  if (found < 4 || !(d2[found - 1] > 0))
    return n;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t j = 0; j < found; ++j)
    mean += Eigen::Map<const Eigen::Vector3d>(points + 3 * ids[j]);
  mean /= static_cast<double>(found);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::size_t j = 0; j < found; ++j)
  {
    const Eigen::Vector3d d = Eigen::Map<const Eigen::Vector3d>(points + 3 * ids[j]) - mean;
    covariance += d * d.transpose();
  }
  covariance /= static_cast<double>(found);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  n.residual = std::sqrt(std::max(0.0, solver.eigenvalues()[0]));
  n.spacing = std::sqrt(Pi * d2[found - 1] / static_cast<double>(found));
  n.reach = std::sqrt(d2[found - 1]);
  n.offPlane =
      std::abs(solver.eigenvectors().col(0).dot(Eigen::Map<const Eigen::Vector3d>(x) - mean));
  for (std::size_t j = 0; j < found && n.nearest == 0; ++j)
    n.nearest = std::sqrt(d2[j]);
  return n;
}

// Isolated (its k-th neighbour far beyond the usual reach) or off the layer.
bool isStray(const Neighbourhood& n, const NoiseAtSamples& judged)
{
  const double layer = OffLayer * judged.noise.thickness + judged.noise.surfaceSpacing;
  return n.residual >= 0 && (n.reach > IsolatedReach * judged.usualReach || n.offPlane > layer);
}

} // namespace

NoiseAtSamples measureNoiseAt(const double* points, const std::vector<std::uint32_t>& samples,
                              const NearestPoints& nearest, std::size_t neighbours)
{
  std::vector<Neighbourhood> at(samples.size());
  forEachIndex(samples.size(),
               [&](std::size_t s)
               {
                 std::vector<std::uint32_t> ids(neighbours);
                 std::vector<double> d2(neighbours);
                 const double* x = points + 3 * static_cast<std::size_t>(samples[s]);
                 const std::size_t found = nearest(x, neighbours, ids.data(), d2.data());
                 at[s] = around(points, x, ids.data(), d2.data(), found);
               });
  std::vector<double> residuals, spacings, reaches, nearestOther;
  for (const Neighbourhood& n : at)
    if (n.residual >= 0)
    {
      residuals.push_back(n.residual);
      spacings.push_back(n.spacing);
      reaches.push_back(n.reach);
      if (n.nearest > 0)
        nearestOther.push_back(n.nearest);
    }
  NoiseAtSamples out;
  out.noise.thickness = median(residuals);
  out.noise.surfaceSpacing = median(spacings);
  out.noise.pointSpacing = median(nearestOther);
  out.usualReach = median(reaches);
  out.stray.resize(samples.size());
  for (std::size_t s = 0; s < at.size(); ++s)
    out.stray[s] = isStray(at[s], out);
  return out;
}

bool isStrayPoint(const double* points, const double* x, const NearestPoints& nearest,
                  const NoiseAtSamples& judged, std::size_t neighbours)
{
  std::vector<std::uint32_t> ids(neighbours);
  std::vector<double> d2(neighbours);
  const std::size_t found = nearest(x, neighbours, ids.data(), d2.data());
  return isStray(around(points, x, ids.data(), d2.data(), found), judged);
}

SurfaceNoise measureSurfaceNoise(const double* points, std::size_t count, std::size_t neighbours)
{
  if (count < 8)
    throw std::invalid_argument("the noise of a surface needs at least 8 points, not " +
                                std::to_string(count));
  const support::KdTree tree(points, count);
  std::vector<std::uint32_t> samples;
  for (std::size_t i = 0; i < count; i += std::max<std::size_t>(1, count / SampleSize))
    samples.push_back(static_cast<std::uint32_t>(i));
  const SurfaceNoise noise = measureNoiseAt(
                                 points, samples,
                                 [&](const double* x, std::size_t k, std::uint32_t* ids, double* d2)
                                 { return tree.nearest(x, k, ids, d2); },
                                 std::clamp<std::size_t>(neighbours, 4, count))
                                 .noise;
  if (!(noise.pointSpacing > 0))
    throw std::invalid_argument("the noise of a surface: all its points coincide");
  return noise;
}

std::vector<std::uint32_t> pointsOnTheSurface(const double* points, std::size_t count)
{
  std::vector<std::uint32_t> all(count);
  for (std::size_t i = 0; i < count; ++i)
    all[i] = static_cast<std::uint32_t>(i);
  if (count <= StrayNeighbours)
    return all;
  const support::KdTree tree(points, count);
  const NoiseAtSamples n = measureNoiseAt(points, all,
                                          [&](const double* x, std::size_t k, std::uint32_t* ids,
                                              double* d2) { return tree.nearest(x, k, ids, d2); });
  std::vector<std::uint32_t> kept;
  for (std::size_t i = 0; i < count; ++i)
    if (!n.stray[i])
      kept.push_back(static_cast<std::uint32_t>(i));
  return kept;
}

} // namespace dp
