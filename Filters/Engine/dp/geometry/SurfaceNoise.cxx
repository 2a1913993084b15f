// SPDX-License-Identifier: BSD-3-Clause
// A cloud's noise measured in itself (SurfaceNoise.h).
#include "dp/geometry/SurfaceNoise.h"

#include "dp/detail/KdTree.h"
#include "dp/detail/Parallel.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace dp
{

namespace
{

constexpr std::size_t SampleSize = 2000;
constexpr double Pi = 3.141592653589793;

double median(std::vector<double>& values)
{
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// The distance of `x` from the least-squares plane of the points `ids`.
double distanceFromPlane(const double* points, const std::uint32_t* ids, std::size_t found,
                         const double* x)
{
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
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  return std::abs(solver.eigenvectors().col(0).dot(Eigen::Map<const Eigen::Vector3d>(x) - mean));
}

} // namespace

SurfaceNoise measureSurfaceNoise(const double* points, std::size_t count, std::size_t neighbours)
{
  if (count < 8)
    throw std::invalid_argument("the noise of a surface needs at least 8 points, not " +
                                std::to_string(count));
  const std::size_t k = std::clamp<std::size_t>(neighbours, 4, count);
  const detail::KdTree tree(points, count);
  const std::size_t stride = std::max<std::size_t>(1, count / SampleSize);
  std::vector<double> residuals, spacings, nearest;
  std::vector<std::uint32_t> ids(k);
  std::vector<double> d2(k);
  for (std::size_t i = 0; i < count; i += stride)
  {
    const std::size_t found = tree.nearest(points + 3 * i, k, ids.data(), d2.data());
    if (found < 4 || !(d2[found - 1] > 0))
      continue;
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
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance, Eigen::EigenvaluesOnly);
    residuals.push_back(std::sqrt(std::max(0.0, solver.eigenvalues()[0])));
    spacings.push_back(std::sqrt(Pi * d2[found - 1] / static_cast<double>(found)));
    for (std::size_t j = 1; j < found; ++j)
      if (d2[j] > 0)
      {
        nearest.push_back(std::sqrt(d2[j]));
        break;
      }
  }
  if (residuals.empty() || nearest.empty())
    throw std::invalid_argument("the noise of a surface: all its points coincide");
  SurfaceNoise noise;
  noise.thickness = median(residuals);
  noise.surfaceSpacing = median(spacings);
  noise.pointSpacing = median(nearest);
  return noise;
}

std::vector<std::uint32_t> pointsOnTheSurface(const double* points, std::size_t count,
                                              const SurfaceNoise& noise)
{
  constexpr std::size_t K = 16;
  std::vector<std::uint32_t> kept;
  if (count <= K)
  {
    for (std::size_t i = 0; i < count; ++i)
      kept.push_back(static_cast<std::uint32_t>(i));
    return kept;
  }
  const detail::KdTree tree(points, count);
  std::vector<double> reach(count), offPlane(count);
  forEachIndex(count,
               [&](std::size_t i)
               {
                 std::uint32_t ids[K];
                 double d2[K];
                 const std::size_t found = tree.nearest(points + 3 * i, K, ids, d2);
                 reach[i] = std::sqrt(d2[found - 1]);
                 offPlane[i] = distanceFromPlane(points, ids, found, points + 3 * i);
               });
  std::vector<double> sorted = reach;
  const double usual = median(sorted);
  const double layer = 4 * noise.thickness + noise.surfaceSpacing;
  for (std::size_t i = 0; i < count; ++i)
    if (reach[i] <= 3 * usual && offPlane[i] <= layer)
      kept.push_back(static_cast<std::uint32_t>(i));
  return kept;
}

} // namespace dp
