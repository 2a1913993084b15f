// SPDX-License-Identifier: BSD-3-Clause
#include "dp/compress/Decomposition.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace dp
{
using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace compress
{
namespace
{
// Singular values under this share of the largest are noise of the Gram-matrix route.
constexpr double RankCut = 1e-8;
} // namespace

void Decomposition::factors(std::size_t k, MatrixXd& basis, MatrixXd& weights) const
{
  MatrixXd left, right; // C ~ left diag(sigma) right^T, both orthonormal
  if (gramOfColumns)
  {
    right = smallSide.leftCols(k);
    left = centred * right;
    for (std::size_t j = 0; j < k; ++j)
      left.col(j) /= sigma[j];
  }
  else
  {
    left = smallSide.leftCols(k);
    right = centred.transpose() * left;
    for (std::size_t j = 0; j < k; ++j)
      right.col(j) /= sigma[j];
  }
  if (layout == PcaLayout::Shapes)
  {
    basis = std::move(left);
    weights = right * sigma.head(k).asDiagonal();
  }
  else
  {
    basis = std::move(right);
    weights = left * sigma.head(k).asDiagonal();
  }
}

double Decomposition::truncationError(std::size_t k) const
{
  const double kept = sigma.head(k).squaredNorm();
  return std::sqrt(std::max(0.0, centredNorm2 - kept));
}

Decomposition decompose(const Eigen::Map<const MatrixXd>& A, PcaLayout layout)
{
  Decomposition d;
  d.layout = layout;
  d.frames = static_cast<std::size_t>(A.cols());
  d.vertices = static_cast<std::size_t>(A.rows()) / 3;
  if (layout == PcaLayout::Shapes)
  {
    d.mean = A.rowwise().mean();
    d.centred = A.colwise() - d.mean;
  }
  else
  {
    // B(i, 3t + c) = A(3i + c, t): row i is vertex i's trajectory.
    MatrixXd B(d.vertices, 3 * d.frames);
    for (std::size_t t = 0; t < d.frames; ++t)
      for (std::size_t i = 0; i < d.vertices; ++i)
        for (int c = 0; c < 3; ++c)
          B(i, 3 * t + c) = A(3 * i + c, t);
    d.mean = B.colwise().mean().transpose();
    B.rowwise() -= d.mean.transpose();
    d.centred = std::move(B);
  }
  d.centredNorm2 = d.centred.squaredNorm();
  d.gramOfColumns = d.centred.cols() <= d.centred.rows();
  const Eigen::Index side = d.gramOfColumns ? d.centred.cols() : d.centred.rows();
  MatrixXd gram = MatrixXd::Zero(side, side);
  if (d.gramOfColumns)
    gram.selfadjointView<Eigen::Lower>().rankUpdate(d.centred.transpose());
  else
    gram.selfadjointView<Eigen::Lower>().rankUpdate(d.centred);
  Eigen::SelfAdjointEigenSolver<MatrixXd> eigen(gram.selfadjointView<Eigen::Lower>());
  const VectorXd& values = eigen.eigenvalues(); // ascending
  const double largest = std::sqrt(std::max(0.0, values[side - 1]));
  std::size_t rank = 0;
  for (Eigen::Index j = side - 1; j >= 0; --j)
    if (std::sqrt(std::max(0.0, values[j])) > RankCut * largest && largest > 0)
      ++rank;
    else
      break;
  d.sigma.resize(rank);
  d.smallSide.resize(side, rank);
  for (std::size_t j = 0; j < rank; ++j)
  {
    d.sigma[j] = std::sqrt(values[side - 1 - j]);
    d.smallSide.col(j) = eigen.eigenvectors().col(side - 1 - j);
  }
  return d;
}

Errors errorsOf(const Eigen::Map<const MatrixXd>& A, const PcaModel& m)
{
  const MatrixXd approx = m.reconstruct();
  return {karniGotsmanError(A, approx), maxVertexError(A, approx)};
}

double measured(const Errors& e, PcaErrorMeasure measure, double diagonal)
{
  return measure == PcaErrorMeasure::KarniGotsman ? e.kg : e.max / diagonal;
}

} // namespace compress

// The model and the error measures (declared in PcaCompression.h).

double centroidSpread(const Eigen::Ref<const MatrixXd>& A)
{
  double spread = 0;
  for (Eigen::Index t = 0; t < A.cols(); ++t)
  {
    const auto frame = A.col(t).reshaped(3, A.rows() / 3);
    const Eigen::Vector3d centroid = frame.rowwise().mean();
    spread += (frame.colwise() - centroid).squaredNorm();
  }
  return std::sqrt(spread);
}

void PcaModel::frame(std::size_t t, double* positions) const
{
  if (t >= frames)
    throw std::out_of_range("frame " + std::to_string(t) + " of " + std::to_string(frames));
  Eigen::Map<VectorXd> out(positions, 3 * vertices);
  if (layout == PcaLayout::Shapes)
  {
    out = mean + basis * weights.row(t).transpose();
    return;
  }
  // X_i[t] = m[t] + sum_j c_ij Y_j[t].
  const Eigen::Index k = basis.cols();
  for (int c = 0; c < 3; ++c)
  {
    const Eigen::Index row = static_cast<Eigen::Index>(3 * t + c);
    const VectorXd coordinate = weights * basis.row(row).head(k).transpose();
    for (std::size_t i = 0; i < vertices; ++i)
      out[3 * i + c] = mean[row] + coordinate[i];
  }
}

MatrixXd PcaModel::reconstruct() const
{
  MatrixXd all(3 * vertices, frames);
  for (std::size_t t = 0; t < frames; ++t)
    frame(t, all.col(t).data());
  return all;
}

double karniGotsmanError(const Eigen::Ref<const MatrixXd>& original,
                         const Eigen::Ref<const MatrixXd>& approx)
{
  const double spread = centroidSpread(original);
  const double error = (original - approx).norm();
  return spread > 0 ? 100 * error / spread : (error > 0 ? 100 : 0);
}

double maxVertexError(const Eigen::Ref<const MatrixXd>& original,
                      const Eigen::Ref<const MatrixXd>& approx)
{
  double worst = 0;
  for (Eigen::Index t = 0; t < original.cols(); ++t)
    for (Eigen::Index i = 0; i + 2 < original.rows(); i += 3)
      worst = std::max(worst,
                       (original.col(t).segment<3>(i) - approx.col(t).segment<3>(i)).squaredNorm());
  return std::sqrt(worst);
}

} // namespace dp
