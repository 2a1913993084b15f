// SPDX-License-Identifier: BSD-3-Clause
// The fixed-pattern block matrix of the Gauss-Newton solver against a dense assembly of the
// same blocks, its trace matrix, and the block Cholesky factorisation against a dense one.
#include "dp/support/BlockCholesky.h"
#include "dp/support/BlockSparseMatrix.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <random>

namespace
{
// Adds 200 random symmetric outer products on `pairs` to both the sparse and the dense matrix:
// (a, b) gets w u v^T, (b, a) its transpose, a diagonal block w u u^T.
void addRandomOuters(const std::vector<std::array<std::int64_t, 2>>& pairs, std::mt19937_64& rng,
                     dp::support::BlockSparseMatrix& sparse, Eigen::MatrixXd& dense)
{
  std::normal_distribution<double> value;
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
}
} // namespace

TEST(BlockSparseMatrix, AssemblesLikeADenseMatrix)
{
  const std::size_t blocks = 12;
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> pick(0, blocks - 1);
  std::vector<std::array<std::int64_t, 2>> pairs;
  for (int k = 0; k < 30; ++k)
    pairs.push_back({pick(rng), pick(rng)}); // repeats, both orders and self pairs included
  dp::support::BlockSparseMatrix sparse(blocks, pairs);
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * blocks, 3 * blocks);
  for (int round = 0; round < 2; ++round) // the second round starts from setZero()
  {
    sparse.setZero();
    dense.setZero();
    addRandomOuters(pairs, rng, sparse, dense);
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

TEST(BlockSparseMatrix, CornersAddWhatTheirFullBlocksAdd)
{
  // 3 x 3 corners of 6 x 6 blocks, in both orders of an off-diagonal pair and on a diagonal
  // block (with its mirrored corner), against addBlock() of the same blocks written out in full.
  using Block = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;
  const std::vector<std::array<std::int64_t, 2>> pairs = {{0, 2}, {1, 2}};
  dp::support::BlockSparseMatrixOf<6> corners(3, pairs), full(3, pairs);
  std::mt19937_64 rng(4);
  std::normal_distribution<double> value;
  auto random = [&]
  {
    Eigen::Matrix3d m;
    for (int i = 0; i < 9; ++i)
      m(i / 3, i % 3) = value(rng);
    return m;
  };
  for (const auto& [a, b] : std::vector<std::array<std::int64_t, 2>>{{0, 2}, {2, 1}, {1, 1}})
  {
    const auto slot = corners.slotOf(a, b);
    const Eigen::Matrix3d m = random(), n = random();
    const double d = value(rng);
    Block block = Block::Zero();
    if (a == b)
    {
      corners.addCorner(slot, 0, 3, m);
      corners.addCorner(slot, 3, 0, m.transpose());
      block.topRightCorner<3, 3>() = m;
      block.bottomLeftCorner<3, 3>() = m.transpose();
    }
    else
    {
      corners.addCorner(slot, 0, 3, m);
      corners.addCorner(slot, 3, 0, n);
      block.topRightCorner<3, 3>() = m;
      block.bottomLeftCorner<3, 3>() = n;
    }
    corners.addCornerDiagonal(slot, 3, 3, d);
    block.bottomRightCorner<3, 3>().diagonal().setConstant(d);
    full.addBlock(full.slotOf(a, b), block.data());
  }
  const Eigen::MatrixXd difference =
      Eigen::MatrixXd(corners.matrix()) - Eigen::MatrixXd(full.matrix());
  EXPECT_EQ(difference.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_GT(Eigen::MatrixXd(full.matrix()).cwiseAbs().maxCoeff(), 0.0);
}

TEST(BlockSparseMatrix, RefusesBlocksOutsideThePattern)
{
  dp::support::BlockSparseMatrix m(4, {{{0, 1}}, {{2, 3}}});
  const double u[3] = {1, 2, 3};
  EXPECT_THROW(m.addOuter(0, 2, u, u, 1.0), std::out_of_range);
  EXPECT_THROW(dp::support::BlockSparseMatrix(2, {{{0, 5}}}), std::out_of_range);
  EXPECT_NO_THROW(m.addOuter(3, 2, u, u, 1.0));
}

namespace
{
// A symmetric positive definite block matrix on a random pattern (a ring plus random pairs, so
// elimination fills in), assembled both sparse and dense.
template <int Size>
void randomSpd(std::size_t blocks, std::mt19937_64& rng,
               dp::support::BlockSparseMatrixOf<Size>& sparse, Eigen::MatrixXd& dense)
{
  std::uniform_int_distribution<int> pick(0, static_cast<int>(blocks) - 1);
  std::normal_distribution<double> value;
  std::vector<std::array<std::int64_t, 2>> pairs;
  for (std::size_t b = 0; b < blocks; ++b)
    pairs.push_back({static_cast<std::int64_t>(b), static_cast<std::int64_t>((b + 1) % blocks)});
  for (std::size_t k = 0; k < 2 * blocks; ++k)
    pairs.push_back({pick(rng), pick(rng)});
  sparse = dp::support::BlockSparseMatrixOf<Size>(blocks, pairs);
  dense = Eigen::MatrixXd::Zero(Size * blocks, Size * blocks);
  // Sums of w u u^T over pairs (u spanning both blocks): positive semidefinite, plus a diagonal.
  for (const auto& p : pairs)
    for (int k = 0; k < Size; ++k)
    {
      Eigen::Matrix<double, Size, 1> u, v;
      for (int i = 0; i < Size; ++i)
      {
        u[i] = value(rng);
        v[i] = value(rng);
      }
      const double w = 1.0 + std::abs(value(rng));
      Eigen::VectorXd whole = Eigen::VectorXd::Zero(Size * blocks);
      whole.segment<Size>(Size * p[0]) += u;
      whole.segment<Size>(Size * p[1]) += v;
      dense += w * whole * whole.transpose();
      if (p[0] == p[1])
      {
        const Eigen::Matrix<double, Size, 1> s = u + v;
        sparse.addOuter(p[0], p[0], s.data(), s.data(), w);
        continue;
      }
      sparse.addOuter(p[0], p[0], u.data(), u.data(), w);
      sparse.addOuter(p[1], p[1], v.data(), v.data(), w);
      sparse.addOuter(p[0], p[1], u.data(), v.data(), w);
    }
  sparse.addToDiagonal(Eigen::VectorXd::Constant(Size * blocks, 0.1));
  dense.diagonal().array() += 0.1;
}
} // namespace

TEST(BlockCholesky, SolvesLikeADenseFactorisation)
{
  std::mt19937_64 rng(11);
  dp::support::BlockSparseMatrixOf<6> sparse;
  Eigen::MatrixXd dense;
  randomSpd<6>(40, rng, sparse, dense);
  const Eigen::MatrixXd stored = Eigen::MatrixXd(sparse.matrix());
  ASSERT_LT((Eigen::MatrixXd(stored.selfadjointView<Eigen::Lower>()) - dense).cwiseAbs().maxCoeff(),
            1e-9);
  dp::support::BlockCholeskyOf<6> cholesky;
  cholesky.analyse(sparse);
  EXPECT_GT(cholesky.offDiagonalBlocks(), 40u); // the ring and the pairs, with fill
  const Eigen::VectorXd b = Eigen::VectorXd::Random(6 * 40);
  const Eigen::VectorXd expected = dense.llt().solve(b);
  for (int round = 0; round < 2; ++round) // the pattern's analysis serves every factorisation
  {
    ASSERT_TRUE(cholesky.factorise(sparse));
    const Eigen::VectorXd x = cholesky.solve(b);
    EXPECT_LT((x - expected).norm(), 1e-9 * expected.norm()) << "round " << round;
    EXPECT_LT((dense * x - b).norm(), 1e-9 * b.norm());
  }
  // A matrix that is not positive definite is refused, not factorised into garbage.
  sparse.addToDiagonal(Eigen::VectorXd::Constant(6 * 40, -1e6));
  EXPECT_FALSE(cholesky.factorise(sparse));
}
