// SPDX-License-Identifier: BSD-3-Clause
// Quantiser: a PCA model rounded for coding. Every number comes back within half of its own step
// (weights at q, basis vector j at q / sigma_j, the mean at q / sqrt(its repeats)) as its integer
// times that step; the error estimate is the reconstruction's error exactly when every component
// is kept, and within the Cauchy-Schwarz bound of its omitted term when some are not.
#include "dp/compress/Decomposition.h"
#include "dp/compress/Quantiser.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace
{

using Eigen::MatrixXd;

// 3 nv x nt positions: a mean shape and a motion whose components decay.
MatrixXd animation(std::size_t nv, std::size_t nt, unsigned seed)
{
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  MatrixXd A(3 * nv, nt);
  for (Eigen::Index i = 0; i < A.rows(); ++i)
    for (Eigen::Index t = 0; t < A.cols(); ++t)
      A(i, t) = 2 * std::sin(0.1 * static_cast<double>(i)) +
                std::pow(0.6, static_cast<double>(t % 7)) * g(rng);
  return A;
}

// Each value of `values` is `integers[i]` steps, and within half a step of `original`.
void expectWithinHalfAStep(const double* original, const double* values,
                           const std::int64_t* integers, std::size_t count, double step,
                           const char* what)
{
  for (std::size_t i = 0; i < count; ++i)
  {
    ASSERT_EQ(values[i], static_cast<double>(integers[i]) * step) << what << " " << i;
    // Half a step, and the rounding of a value far larger than its step.
    ASSERT_LE(std::abs(values[i] - original[i]), 0.5 * step + 1e-15 * std::abs(original[i]))
        << what << " " << i;
  }
}

class Quantiser : public ::testing::TestWithParam<dp::PcaLayout>
{
};

TEST_P(Quantiser, EveryNumberComesBackWithinHalfItsStep)
{
  const MatrixXd A = animation(50, 14, 1);
  const Eigen::Map<const MatrixXd> map(A.data(), A.rows(), A.cols());
  const dp::compress::Decomposition d = dp::compress::decompose(map, GetParam());
  MatrixXd basis, weights;
  const std::size_t k = 5;
  d.factors(k, basis, weights);
  for (const double step : {1e-4, 0.01, 0.3})
  {
    const dp::QuantisedPca q = dp::compress::quantise(d, basis, weights, step);
    const dp::PcaModel& m = q.model;
    EXPECT_EQ(m.layout, GetParam());
    EXPECT_EQ(m.vertices, 50u);
    EXPECT_EQ(m.frames, 14u);
    EXPECT_EQ(q.step, step);
    EXPECT_EQ(q.meanStep, step / std::sqrt(static_cast<double>(d.meanRepeats())));
    ASSERT_EQ(q.basisSteps.size(), k);
    ASSERT_EQ(q.meanIntegers.size(), static_cast<std::size_t>(d.mean.size()));
    ASSERT_EQ(q.basisIntegers.size(), static_cast<std::size_t>(basis.size()));
    ASSERT_EQ(q.weightIntegers.size(), static_cast<std::size_t>(weights.size()));
    expectWithinHalfAStep(d.mean.data(), m.mean.data(), q.meanIntegers.data(),
                          q.meanIntegers.size(), q.meanStep, "mean");
    for (std::size_t j = 0; j < k; ++j)
    {
      EXPECT_EQ(q.basisSteps[j], step / d.sigma[j]);
      expectWithinHalfAStep(basis.col(j).data(), m.basis.col(j).data(),
                            q.basisIntegers.data() + j * basis.rows(), basis.rows(),
                            q.basisSteps[j], "basis");
    }
    expectWithinHalfAStep(weights.data(), m.weights.data(), q.weightIntegers.data(),
                          q.weightIntegers.size(), step, "weights");
  }
}

TEST_P(Quantiser, TheErrorEstimateIsTheReconstructionsUpToTheTermItLeavesOut)
{
  // With X' - X = D - R (D the quantisation's part, R the truncation's), the estimate is
  // ||D||^2 + ||R||^2 and the error ||D - R||^2: equal when every component is kept (R = 0),
  // else apart by 2 <D, R> at most 2 ||D|| ||R||.
  const MatrixXd A = animation(50, 14, 2);
  const Eigen::Map<const MatrixXd> map(A.data(), A.rows(), A.cols());
  const dp::compress::Decomposition d = dp::compress::decompose(map, GetParam());
  const auto rank = static_cast<std::size_t>(d.sigma.size());
  for (const std::size_t k : {rank, std::size_t{3}})
    for (const double step : {1e-3, 0.05})
    {
      MatrixXd basis, weights;
      d.factors(k, basis, weights);
      const dp::QuantisedPca q = dp::compress::quantise(d, basis, weights, step);
      const double residual2 = std::pow(d.truncationError(k), 2);
      const double estimate =
          dp::compress::estimatedError2(basis, weights, d.mean, q.model, residual2);
      const double actual = (A - q.model.reconstruct()).squaredNorm();
      if (k == rank)
      {
        EXPECT_NEAR(estimate, actual, 1e-8 * actual) << "step " << step;
      }
      else
      {
        const double bound = 2 * std::sqrt(std::max(0.0, estimate - residual2) * residual2);
        EXPECT_LE(std::abs(estimate - actual), bound * (1 + 1e-9) + 1e-12 * actual)
            << k << " components, step " << step;
        EXPECT_GT(residual2, 0);
      }
      // Rounding every number adds about step^2 / 12 per number: the error grows with the step.
      EXPECT_GT(estimate, residual2);
    }
}

INSTANTIATE_TEST_SUITE_P(BothLayouts, Quantiser,
                         ::testing::Values(dp::PcaLayout::Shapes, dp::PcaLayout::Trajectories),
                         [](const ::testing::TestParamInfo<dp::PcaLayout>& info) {
                           return info.param == dp::PcaLayout::Shapes ? "Shapes" : "Trajectories";
                         });

} // namespace
