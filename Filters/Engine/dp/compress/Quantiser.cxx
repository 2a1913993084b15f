// SPDX-License-Identifier: BSD-3-Clause
#include "dp/compress/Quantiser.h"

#include <algorithm>
#include <cmath>

namespace dp::compress
{
using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace
{

std::vector<std::int64_t> quantiseValues(const double* v, std::size_t n, double step,
                                         double* dequantised)
{
  std::vector<std::int64_t> q(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    q[i] = static_cast<std::int64_t>(std::llround(v[i] / step));
    dequantised[i] = static_cast<double>(q[i]) * step;
  }
  return q;
}

} // namespace

QuantisedPca quantise(const Decomposition& d, const MatrixXd& basis, const MatrixXd& weights,
                      double step)
{
  QuantisedPca q;
  PcaModel& m = q.model;
  m.layout = d.layout;
  m.vertices = d.vertices;
  m.frames = d.frames;
  const std::size_t k = static_cast<std::size_t>(basis.cols());
  q.step = step;
  q.meanStep = step / std::sqrt(static_cast<double>(d.meanRepeats()));
  m.mean.resize(d.mean.size());
  q.meanIntegers = quantiseValues(d.mean.data(), d.mean.size(), q.meanStep, m.mean.data());
  m.basis.resize(basis.rows(), basis.cols());
  m.weights.resize(weights.rows(), weights.cols());
  q.basisSteps.resize(k);
  q.basisIntegers.resize(basis.size());
  for (std::size_t j = 0; j < k; ++j)
  {
    q.basisSteps[j] = step / d.sigma[j];
    const auto ints =
        quantiseValues(basis.col(j).data(), basis.rows(), q.basisSteps[j], m.basis.col(j).data());
    std::copy(ints.begin(), ints.end(), q.basisIntegers.begin() + j * basis.rows());
  }
  q.weightIntegers = quantiseValues(weights.data(), weights.size(), step, m.weights.data());
  return q;
}

double estimatedError2(const MatrixXd& basis, const MatrixXd& weights, const VectorXd& mean,
                       const PcaModel& q, double residual2)
{
  const Eigen::Index k = basis.cols();
  MatrixXd P(basis.rows(), 1 + 2 * k), Q(weights.rows(), 1 + 2 * k);
  P.col(0) = q.mean - mean;
  P.middleCols(1, k) = q.basis - basis;
  P.rightCols(k) = basis;
  Q.col(0).setOnes();
  Q.middleCols(1, k) = q.weights;
  Q.rightCols(k) = q.weights - weights;
  MatrixXd gp = MatrixXd::Zero(1 + 2 * k, 1 + 2 * k), gq = gp;
  gp.selfadjointView<Eigen::Lower>().rankUpdate(P.transpose());
  gq.selfadjointView<Eigen::Lower>().rankUpdate(Q.transpose());
  const MatrixXd fp = gp.selfadjointView<Eigen::Lower>(), fq = gq.selfadjointView<Eigen::Lower>();
  return fp.cwiseProduct(fq).sum() + residual2;
}

} // namespace dp::compress
