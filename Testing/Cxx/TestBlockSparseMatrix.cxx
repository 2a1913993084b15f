// SPDX-License-Identifier: BSD-3-Clause
// The fixed-pattern block matrix of the Gauss-Newton solver against a dense assembly of the
// same blocks, and its trace matrix.
#include "dp/detail/BlockSparseMatrix.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <random>

TEST(BlockSparseMatrix, AssemblesLikeADenseMatrix)
{
  const std::size_t blocks = 12;
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> pick(0, blocks - 1);
  std::normal_distribution<double> value;
  std::vector<std::array<std::int64_t, 2>> pairs;
  for (int k = 0; k < 30; ++k)
    pairs.push_back({pick(rng), pick(rng)}); // repeats, both orders and self pairs included
  dp::detail::BlockSparseMatrix sparse(blocks, pairs);
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * blocks, 3 * blocks);
  for (int round = 0; round < 2; ++round) // the second round starts from setZero()
  {
    sparse.setZero();
    dense.setZero();
    for (int k = 0; k < 200; ++k)
    {
      const auto& p = pairs[static_cast<std::size_t>(k) % pairs.size()];
      const Eigen::Vector3d u(value(rng), value(rng), value(rng)),
          v(value(rng), value(rng), value(rng));
      const double w = value(rng);
      // Symmetric: (a, b) gets w u v^T, (b, a) its transpose; a diagonal block gets w u u^T.
      if (p[0] == p[1])
      {
        sparse.addOuter(p[0], p[0], u.data(), u.data(), w);
        dense.block<3, 3>(3 * p[0], 3 * p[0]) += w * u * u.transpose();
      }
      else
      {
        sparse.addOuter(sparse.slotOf(p[0], p[1]), u.data(), v.data(), w);
        dense.block<3, 3>(3 * p[0], 3 * p[1]) += w * u * v.transpose();
        dense.block<3, 3>(3 * p[1], 3 * p[0]) += w * v * u.transpose();
      }
    }
    // A symmetric block added to a diagonal block (as the data terms do).
    const Eigen::Matrix3d R = Eigen::Matrix3d::Random();
    const Eigen::Matrix3d M = R + R.transpose();
    const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> rowMajor = M;
    sparse.addToDiagonalBlock(3, rowMajor.data());
    dense.block<3, 3>(9, 9) += M;
    // The stored lower triangle, read as a symmetric matrix, is the dense sum.
    const Eigen::MatrixXd stored = Eigen::MatrixXd(sparse.matrix());
    const Eigen::MatrixXd full = Eigen::MatrixXd(stored.selfadjointView<Eigen::Lower>());
    EXPECT_LT((full - dense).cwiseAbs().maxCoeff(), 1e-12) << "round " << round;
    Eigen::MatrixXd expected = dense;

    // The diagonal, and adding to it.
    EXPECT_LT((sparse.diagonal() - expected.diagonal()).cwiseAbs().maxCoeff(), 1e-12);
    sparse.addToDiagonal(Eigen::VectorXd::Constant(3 * blocks, 2.5));
    EXPECT_LT(
        (sparse.diagonal() - (expected.diagonal().array() + 2.5).matrix()).cwiseAbs().maxCoeff(),
        1e-12);

    // The trace matrix: entry (a, b) is the trace of block (a, b) / 3.
    const Eigen::MatrixXd P = Eigen::MatrixXd(sparse.traceMatrix());
    expected.diagonal().array() += 2.5;
    for (std::size_t a = 0; a < blocks; ++a)
      for (std::size_t b = 0; b <= a; ++b)
      {
        const double trace = expected.block<3, 3>(3 * a, 3 * b).trace();
        EXPECT_NEAR(P(a, b), trace / 3, 1e-12);
      }
  }
}

TEST(BlockSparseMatrix, RefusesBlocksOutsideThePattern)
{
  dp::detail::BlockSparseMatrix m(4, {{{0, 1}}, {{2, 3}}});
  const double u[3] = {1, 2, 3};
  EXPECT_THROW(m.addOuter(0, 2, u, u, 1.0), std::out_of_range);
  EXPECT_THROW(dp::detail::BlockSparseMatrix(2, {{{0, 5}}}), std::out_of_range);
  EXPECT_NO_THROW(m.addOuter(3, 2, u, u, 1.0));
}
