// SPDX-License-Identifier: BSD-3-Clause
/**
 * A sparse Cholesky factorisation L L^T = P A P^T of a symmetric positive definite
 * BlockSparseMatrixOf<Size> that works on its Size x Size blocks as units: the fill-reducing
 * ordering (AMD), the elimination tree and the pattern of L are found once per pattern
 * (analyse()), and the numeric factorisation is a fixed list of dense fixed-size block products
 * whose destinations were found then too. Against a scalar simplicial factorisation of the same
 * matrix (Eigen::SimplicialLDLT) it does the same arithmetic in vectorised blocks with no index
 * search: the coarse level's node systems (6 x nodes unknowns) factor and solve 3.2x faster at
 * 100-600 nodes (BenchmarkSolvers).
 *
 * Limits: serial; a matrix that is not positive definite (a diagonal block whose Cholesky fails
 * once the columns before it are eliminated) is reported by factorise() returning false, with no
 * pivoting to rescue it (the Levenberg-Marquardt callers then damp more).
 */
#pragma once

#include "dp/support/BlockSparseMatrix.h"

#include <Eigen/Cholesky>
#include <Eigen/OrderingMethods>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace dp::support
{

template <int Size>
class BlockCholeskyOf
{
public:
  using Block = Eigen::Matrix<double, Size, Size>;
  using Segment = Eigen::Matrix<double, Size, 1>;

  /** The ordering and the pattern of L for `a`'s pattern (values are not read). */
  void analyse(const BlockSparseMatrixOf<Size>& a)
  {
    const auto n = static_cast<std::int64_t>(a.blockCount());
    order(a, n);
    // Where each stored block of A goes in L (in forEachBlock's order), and the pattern of each
    // column of L below its diagonal: A's rows there plus those of its children in the
    // elimination tree (each column's first off-diagonal row is its parent).
    std::vector<std::vector<std::int64_t>> below(static_cast<std::size_t>(n));
    a.forEachBlock(
        [&](std::int64_t r, std::int64_t c, const double*, int)
        {
          const std::int64_t i = NewOf[static_cast<std::size_t>(r)],
                             j = NewOf[static_cast<std::size_t>(c)];
          if (i != j)
            below[static_cast<std::size_t>(std::min(i, j))].push_back(std::max(i, j));
        });
    std::vector<std::vector<std::int64_t>> children(static_cast<std::size_t>(n));
    First.assign(static_cast<std::size_t>(n) + 1, 0);
    Rows.clear();
    for (std::int64_t j = 0; j < n; ++j)
    {
      auto& rows = below[static_cast<std::size_t>(j)];
      for (std::int64_t child : children[static_cast<std::size_t>(j)])
        for (std::size_t k = First[child]; k < First[child + 1]; ++k)
          if (Rows[k] != j)
            rows.push_back(Rows[k]);
      std::sort(rows.begin(), rows.end());
      rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
      if (!rows.empty())
        children[static_cast<std::size_t>(rows.front())].push_back(j);
      Rows.insert(Rows.end(), rows.begin(), rows.end());
      First[static_cast<std::size_t>(j) + 1] = Rows.size();
    }
    locateSources(a);
    locateUpdates(n);
    Diagonal.assign(static_cast<std::size_t>(n), Block::Zero());
    Lower.assign(Rows.size(), Block::Zero());
  }

  /** Factorises `a` (same pattern as analysed). False if it is not positive definite. */
  bool factorise(const BlockSparseMatrixOf<Size>& a)
  {
    load(a);
    const std::size_t n = Diagonal.size();
    std::size_t update = 0;
    for (std::size_t j = 0; j < n; ++j)
    {
      Eigen::LLT<Block> llt(Diagonal[j]);
      if (llt.info() != Eigen::Success)
        return false;
      Diagonal[j] = llt.matrixL();
      const auto Ljj = Diagonal[j].template triangularView<Eigen::Lower>();
      // L_ij = A_ij L_jj^-T, then the trailing blocks lose L_ij L_kj^T.
      for (std::size_t p = First[j]; p < First[j + 1]; ++p)
        Ljj.solveInPlace(Lower[p].transpose());
      for (std::size_t p = First[j]; p < First[j + 1]; ++p)
        for (std::size_t q = First[j]; q <= p; ++q, ++update)
        {
          Block& target = Targets[update] < 0 ? Diagonal[Rows[p]] : Lower[Targets[update]];
          target.noalias() -= Lower[p] * Lower[q].transpose();
        }
    }
    return true;
  }

  /** x = A^-1 b with the last factorisation. */
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const
  {
    const std::size_t n = Diagonal.size();
    std::vector<Segment> y(n);
    for (std::size_t j = 0; j < n; ++j)
      y[j] = b.template segment<Size>(static_cast<Eigen::Index>(Size * OldOf[j]));
    for (std::size_t j = 0; j < n; ++j) // L y = P b
    {
      Diagonal[j].template triangularView<Eigen::Lower>().solveInPlace(y[j]);
      for (std::size_t p = First[j]; p < First[j + 1]; ++p)
        y[Rows[p]].noalias() -= Lower[p] * y[j];
    }
    for (std::size_t j = n; j-- > 0;) // L^T z = y
    {
      for (std::size_t p = First[j]; p < First[j + 1]; ++p)
        y[j].noalias() -= Lower[p].transpose() * y[Rows[p]];
      Diagonal[j].template triangularView<Eigen::Lower>().transpose().solveInPlace(y[j]);
    }
    Eigen::VectorXd x(b.size());
    for (std::size_t j = 0; j < n; ++j)
      x.template segment<Size>(static_cast<Eigen::Index>(Size * OldOf[j])) = y[j];
    return x;
  }

  /** Blocks of L below the diagonal (the fill the ordering left). */
  std::size_t offDiagonalBlocks() const { return Rows.size(); }

private:
  // AMD on the pattern of blocks: OldOf[new] and NewOf[old].
  void order(const BlockSparseMatrixOf<Size>& a, std::int64_t n)
  {
    std::vector<Eigen::Triplet<double>> entries;
    a.forEachBlock([&](std::int64_t r, std::int64_t c, const double*, int)
                   { entries.emplace_back(static_cast<int>(r), static_cast<int>(c), 1.0); });
    Eigen::SparseMatrix<double, Eigen::ColMajor, int> pattern(n, n);
    pattern.setFromTriplets(entries.begin(), entries.end());
    Eigen::SparseMatrix<double, Eigen::ColMajor, int> full =
        pattern.template selfadjointView<Eigen::Lower>();
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> permutation;
    Eigen::AMDOrdering<int>()(full, permutation);
    OldOf.assign(permutation.indices().data(), permutation.indices().data() + n);
    NewOf.assign(static_cast<std::size_t>(n), 0);
    for (std::int64_t k = 0; k < n; ++k)
      NewOf[static_cast<std::size_t>(OldOf[static_cast<std::size_t>(k)])] = k;
  }

  // Index in Lower of block (i, j), i > j, of L.
  std::int64_t position(std::int64_t i, std::int64_t j) const
  {
    const auto begin = Rows.begin() + static_cast<std::ptrdiff_t>(First[j]);
    const auto end = Rows.begin() + static_cast<std::ptrdiff_t>(First[j + 1]);
    return std::lower_bound(begin, end, i) - Rows.begin();
  }

  void locateSources(const BlockSparseMatrixOf<Size>& a)
  {
    Sources.clear();
    a.forEachBlock(
        [&](std::int64_t r, std::int64_t c, const double*, int)
        {
          const std::int64_t i = NewOf[static_cast<std::size_t>(r)],
                             j = NewOf[static_cast<std::size_t>(c)];
          // A's block (r, c) is L's (i, j) when i > j, its transpose's when i < j.
          Sources.push_back(i == j  ? Source{-1 - i, false}
                            : i > j ? Source{position(i, j), false}
                                    : Source{position(j, i), true});
        });
  }

  void locateUpdates(std::int64_t n)
  {
    Targets.clear();
    for (std::int64_t j = 0; j < n; ++j)
      for (std::size_t p = First[j]; p < First[j + 1]; ++p)
        for (std::size_t q = First[j]; q <= p; ++q)
          Targets.push_back(p == q ? -1 : position(Rows[p], Rows[q]));
  }

  void load(const BlockSparseMatrixOf<Size>& a)
  {
    std::fill(Lower.begin(), Lower.end(), Block::Zero());
    std::size_t k = 0;
    a.forEachBlock(
        [&](std::int64_t, std::int64_t, const double* values, int stride)
        {
          const Source& s = Sources[k++];
          Block& target = s.index < 0 ? Diagonal[static_cast<std::size_t>(-1 - s.index)]
                                      : Lower[static_cast<std::size_t>(s.index)];
          const Eigen::Map<const Block, 0, Eigen::OuterStride<>> block(
              values, Eigen::OuterStride<>(stride));
          if (s.transposed)
            target = block.transpose();
          else
            target = block;
        });
  }

  struct Source
  {
    std::int64_t index; // into Lower; -1 - j for diagonal block j
    bool transposed;
  };
  std::vector<std::int64_t> OldOf, NewOf;
  std::vector<std::size_t> First;    // per column of L: its first entry in Rows / Lower
  std::vector<std::int64_t> Rows;    // row of each block of L below the diagonal
  std::vector<Source> Sources;       // per stored block of A
  std::vector<std::int64_t> Targets; // per update of the factorisation: Lower's index, -1: diagonal
  std::vector<Block> Diagonal;       // L_jj (lower triangular)
  std::vector<Block> Lower;          // L_ij, i > j
};

} // namespace dp::support
