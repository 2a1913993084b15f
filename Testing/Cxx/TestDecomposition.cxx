// SPDX-License-Identifier: BSD-3-Clause
// Decomposition: the principal components of an animated mesh in both layouts (one through the
// Gram matrix of the columns, the other of the rows). Its singular values are those of a direct
// SVD of the centred data, its basis orthonormal, all its components reconstruct the input and k
// of them leave the truncation error it reports; the error measures are their closed forms.
#include "dp/compress/Decomposition.h"

#include <gtest/gtest.h>

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <random>

namespace
{

using Eigen::MatrixXd;

// 3 nv x nt positions: a mean shape and a motion of decaying components, each frame a column.
MatrixXd animation(std::size_t nv, std::size_t nt, unsigned seed)
{
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  MatrixXd A(3 * nv, nt);
  for (Eigen::Index i = 0; i < A.rows(); ++i)
    for (Eigen::Index t = 0; t < A.cols(); ++t)
      A(i, t) = g(rng);
  // Scaled frame by frame and row by row: singular values spread over a few decades.
  for (Eigen::Index t = 0; t < A.cols(); ++t)
    A.col(t) *= std::pow(0.7, static_cast<double>(t));
  for (Eigen::Index i = 0; i < A.rows(); ++i)
    A.row(i).array() += 5 * std::sin(static_cast<double>(i));
  return A;
}

// The data in the layout's orientation, centred as the layout centres it.
MatrixXd centredData(const MatrixXd& A, dp::PcaLayout layout)
{
  if (layout == dp::PcaLayout::Shapes)
    return A.colwise() - A.rowwise().mean();
  const Eigen::Index nv = A.rows() / 3, nt = A.cols();
  MatrixXd B(nv, 3 * nt);
  for (Eigen::Index t = 0; t < nt; ++t)
    for (Eigen::Index i = 0; i < nv; ++i)
      for (int c = 0; c < 3; ++c)
        B(i, 3 * t + c) = A(3 * i + c, t);
  return B.rowwise() - B.colwise().mean();
}

dp::PcaModel modelOf(const dp::compress::Decomposition& d, std::size_t k)
{
  dp::PcaModel m;
  m.layout = d.layout;
  m.vertices = d.vertices;
  m.frames = d.frames;
  m.mean = d.mean;
  d.factors(k, m.basis, m.weights);
  return m;
}

class Decomposition : public ::testing::TestWithParam<dp::PcaLayout>
{
};

TEST_P(Decomposition, ItsSingularValuesAreTheCentredDatas)
{
  const MatrixXd A = animation(40, 15, 1);
  const Eigen::Map<const MatrixXd> map(A.data(), A.rows(), A.cols());
  const dp::compress::Decomposition d = dp::compress::decompose(map, GetParam());
  const MatrixXd C = centredData(A, GetParam());
  EXPECT_EQ(d.gramOfColumns, C.cols() <= C.rows());
  EXPECT_NEAR(d.centredNorm2, C.squaredNorm(), 1e-10 * C.squaredNorm());
  EXPECT_LT((d.centred - C).norm(), 1e-12 * C.norm());
  const Eigen::JacobiSVD<MatrixXd> svd(C);
  const Eigen::VectorXd& s = svd.singularValues();
  // The centring takes one dimension: the rank is the smaller side less one.
  const Eigen::Index rank = std::min(C.rows(), C.cols()) - 1;
  ASSERT_EQ(d.sigma.size(), rank);
  for (Eigen::Index j = 0; j < rank; ++j)
    EXPECT_NEAR(d.sigma[j], s[j], 1e-9 * s[0]) << "component " << j;
  EXPECT_EQ(d.meanRepeats(), GetParam() == dp::PcaLayout::Shapes ? d.frames : d.vertices);
  EXPECT_EQ(d.vertices, 40u);
  EXPECT_EQ(d.frames, 15u);
}

TEST_P(Decomposition, AllComponentsReconstructTheInputAndFewerLeaveTheirTruncationError)
{
  const MatrixXd A = animation(40, 15, 2);
  const Eigen::Map<const MatrixXd> map(A.data(), A.rows(), A.cols());
  const dp::compress::Decomposition d = dp::compress::decompose(map, GetParam());
  const auto rank = static_cast<std::size_t>(d.sigma.size());
  for (std::size_t k = 0; k <= rank; ++k)
  {
    const dp::PcaModel m = modelOf(d, k);
    ASSERT_EQ(m.components(), k);
    // An orthonormal basis, weights carrying the singular values.
    const MatrixXd gram = m.basis.transpose() * m.basis;
    EXPECT_LT((gram - MatrixXd::Identity(k, k)).norm(), 1e-9) << k << " components";
    for (std::size_t j = 0; j < k; ++j)
      EXPECT_NEAR(m.weights.col(j).norm(), d.sigma[j], 1e-9 * d.sigma[0]);
    const double error = (A - m.reconstruct()).norm();
    double rest = 0;
    for (std::size_t j = k; j < rank; ++j)
      rest += d.sigma[j] * d.sigma[j];
    EXPECT_NEAR(d.truncationError(k), std::sqrt(rest), 1e-9 * d.sigma[0]) << k;
    EXPECT_NEAR(error, d.truncationError(k), 1e-8 * d.sigma[0]) << k << " components";
  }
  EXPECT_LT((A - modelOf(d, rank).reconstruct()).norm(), 1e-9 * A.norm());
}

INSTANTIATE_TEST_SUITE_P(BothLayouts, Decomposition,
                         ::testing::Values(dp::PcaLayout::Shapes, dp::PcaLayout::Trajectories),
                         [](const ::testing::TestParamInfo<dp::PcaLayout>& info) {
                           return info.param == dp::PcaLayout::Shapes ? "Shapes" : "Trajectories";
                         });

TEST(DecompositionErrors, KarniGotsmanAndTheLargestVertexErrorAreTheirClosedForms)
{
  // A model of 3 components against the input: KG = 100 ||A - A'|| / ||A - E(A)|| (E: each
  // frame's centroid), the largest error the farthest vertex of any frame.
  const MatrixXd A = animation(30, 12, 3);
  const Eigen::Map<const MatrixXd> map(A.data(), A.rows(), A.cols());
  const dp::compress::Decomposition d = dp::compress::decompose(map, dp::PcaLayout::Shapes);
  const dp::PcaModel m = modelOf(d, 3);
  const MatrixXd approx = m.reconstruct();
  double spread = 0, largest = 0;
  for (Eigen::Index t = 0; t < A.cols(); ++t)
  {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (Eigen::Index i = 0; i < A.rows(); i += 3)
      centroid += A.col(t).segment<3>(i) / static_cast<double>(A.rows() / 3);
    for (Eigen::Index i = 0; i < A.rows(); i += 3)
    {
      spread += (A.col(t).segment<3>(i) - centroid).squaredNorm();
      largest = std::max(largest, (A.col(t).segment<3>(i) - approx.col(t).segment<3>(i)).norm());
    }
  }
  const dp::compress::Errors e = dp::compress::errorsOf(map, m);
  EXPECT_NEAR(e.kg, 100 * (A - approx).norm() / std::sqrt(spread), 1e-9);
  EXPECT_NEAR(e.max, largest, 1e-12);
  EXPECT_EQ(dp::compress::measured(e, dp::PcaErrorMeasure::KarniGotsman, 2.0), e.kg);
  EXPECT_EQ(dp::compress::measured(e, dp::PcaErrorMeasure::MaxVertexError, 2.0), e.max / 2.0);
}

TEST(DecompositionErrors, AStillTakeIsItsMeanShape)
{
  // Every frame the same shape: in the shape layout nothing but the mean, reconstructed exactly.
  // (In the trajectory layout each vertex's constant offset from the centroid is a component.)
  MatrixXd A(9, 5);
  for (Eigen::Index t = 0; t < 5; ++t)
    A.col(t) << 0, 1, 2, 3, 4, 5, 6, 7, 8;
  const Eigen::Map<const MatrixXd> map(A.data(), A.rows(), A.cols());
  const dp::compress::Decomposition d = dp::compress::decompose(map, dp::PcaLayout::Shapes);
  EXPECT_EQ(d.sigma.size(), 0);
  EXPECT_EQ(d.truncationError(0), 0.0);
  EXPECT_EQ(modelOf(d, 0).reconstruct(), A);
  const dp::compress::Decomposition t = dp::compress::decompose(map, dp::PcaLayout::Trajectories);
  ASSERT_GE(t.sigma.size(), 1);
  EXPECT_LT((modelOf(t, static_cast<std::size_t>(t.sigma.size())).reconstruct() - A).norm(),
            1e-12 * A.norm());
}

} // namespace
