// SPDX-License-Identifier: BSD-3-Clause
// A symmetric matrix of Size x Size blocks (3: one block per mesh vertex; 6: one per node of a
// deformation graph, rotation and translation) whose sparsity pattern is fixed once: the diagonal
// blocks plus the blocks of given pairs. Only the lower triangle of blocks (row block >= column
// block) is stored, in an Eigen column-major sparse matrix that Eigen's Cholesky solvers read
// directly (they reference the lower triangle only). Assembly adds into precomputed slots: no
// triplets, no sorting, the same structure every time, so a solver's symbolic analysis is done
// once for the life of the pattern.
#pragma once

#include <Eigen/Sparse>

#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace dp::support
{

template <int Size>
class BlockSparseMatrixOf
{
public:
  using Matrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

  BlockSparseMatrixOf() = default;

  /** `pairs` may hold repeats and either order; self pairs are ignored. */
  BlockSparseMatrixOf(std::size_t blockCount, const std::vector<std::array<std::int64_t, 2>>& pairs)
      : Rows(blockCount)
  {
    for (std::size_t b = 0; b < blockCount; ++b)
      Rows[b].push_back(static_cast<std::int64_t>(b));
    for (const auto& p : pairs)
    {
      if (p[0] == p[1])
        continue;
      if (p[0] < 0 || p[1] < 0 || static_cast<std::size_t>(std::max(p[0], p[1])) >= blockCount)
        throw std::out_of_range("BlockSparseMatrix: a pair names a block out of range");
      Rows[static_cast<std::size_t>(std::min(p[0], p[1]))].push_back(std::max(p[0], p[1]));
    }
    std::size_t nonZeros = 0;
    for (auto& rows : Rows)
    {
      std::sort(rows.begin(), rows.end());
      rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
      nonZeros += Size * Size * rows.size();
    }
    const auto n = static_cast<Eigen::Index>(Size * blockCount);
    // Column Size b + c holds, for every stored block (a, b), the rows Size a .. Size a + Size-1.
    std::vector<int> outer(Size * blockCount + 1, 0);
    std::vector<int> inner;
    inner.reserve(nonZeros);
    for (std::size_t b = 0; b < blockCount; ++b)
      for (int c = 0; c < Size; ++c)
      {
        outer[Size * b + c] = static_cast<int>(inner.size());
        for (std::int64_t a : Rows[b])
          for (int r = 0; r < Size; ++r)
            inner.push_back(static_cast<int>(Size * a + r));
      }
    outer.back() = static_cast<int>(inner.size());
    const std::vector<double> zeros(inner.size(), 0.0);
    M = Eigen::Map<const Matrix>(n, n, static_cast<Eigen::Index>(inner.size()), outer.data(),
                                 inner.data(), zeros.data());
    M.makeCompressed();
  }

  std::size_t blockCount() const { return Rows.size(); }
  const Matrix& matrix() const { return M; }

  void setZero() { std::fill(M.valuePtr(), M.valuePtr() + M.nonZeros(), 0.0); }

  /** Where block (a, b) of the full symmetric matrix lives: an opaque handle for the add
   *  functions (the same for the life of the pattern, so assembly loops can look their blocks up
   *  once). */
  struct Slot
  {
    std::int64_t offset = 0; // of the block's first value
    int stride = 0;          // between its columns
    bool transposed = false; // (a, b) is stored as (b, a)
  };
  Slot slotOf(std::int64_t a, std::int64_t b) const
  {
    Slot s;
    s.transposed = a < b;
    if (s.transposed)
      std::swap(a, b);
    s.offset = slot(a, b) - M.valuePtr();
    s.stride = columnStride(b);
    return s;
  }
  /** Whether block (a, b) is in the pattern. */
  bool contains(std::int64_t a, std::int64_t b) const
  {
    if (a < b)
      std::swap(a, b);
    const auto& rows = Rows[static_cast<std::size_t>(b)];
    return std::binary_search(rows.begin(), rows.end(), a);
  }

  /** Adds w u v^T to block (a, b) of the full symmetric matrix (and so w v u^T to (b, a)). */
  void addOuter(std::int64_t a, std::int64_t b, const double* u, const double* v, double w)
  {
    addOuter(slotOf(a, b), u, v, w);
  }
  void addOuter(const Slot& s, const double* u, const double* v, double w)
  {
    if (s.transposed)
      std::swap(u, v);
    double* block = M.valuePtr() + s.offset;
    for (int c = 0; c < Size; ++c)
    {
      const double wv = w * v[c];
      for (int r = 0; r < Size; ++r)
        block[c * s.stride + r] += wv * u[r];
    }
  }

  /** Adds a full Size x Size matrix m (row-major) to block (a, b) of the full symmetric matrix
   *  (and m^T to (b, a)); for a diagonal block, m must be symmetric. */
  void addBlock(const Slot& s, const double* m)
  {
    double* block = M.valuePtr() + s.offset;
    for (int c = 0; c < Size; ++c)
      for (int r = 0; r < Size; ++r)
        block[c * s.stride + r] += s.transposed ? m[Size * c + r] : m[Size * r + c];
  }

  /** Adds the 3 x 3 matrix m to rows r0.. r0 + 2, columns c0.. c0 + 2 of block (a, b) of the full
   *  symmetric matrix (and m^T to (b, a)): for assembly loops whose blocks are mostly zero. On a
   *  diagonal block only those entries change: the caller adds the mirrored corner too. */
  void addCorner(const Slot& s, int r0, int c0, const Eigen::Matrix3d& m)
  {
    double* block = M.valuePtr() + s.offset;
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r)
      {
        const int row = r0 + r, column = c0 + c;
        block[s.transposed ? row * s.stride + column : column * s.stride + row] += m(r, c);
      }
  }
  /** Adds `value` to the 3 diagonal entries (r0 + i, r0 + i) of a diagonal block, or to the
   *  entries (r0 + i, c0 + i) of block (a, b). */
  void addCornerDiagonal(const Slot& s, int r0, int c0, double value)
  {
    double* block = M.valuePtr() + s.offset;
    for (int i = 0; i < 3; ++i)
    {
      const int row = r0 + i, column = c0 + i;
      block[s.transposed ? row * s.stride + column : column * s.stride + row] += value;
    }
  }

  /** Adds a full matrix (row-major) to diagonal block a. */
  void addToDiagonalBlock(std::int64_t a, const double m[Size * Size])
  {
    double* block = slot(a, a);
    const int stride = columnStride(a);
    for (int c = 0; c < Size; ++c)
      for (int r = 0; r < Size; ++r)
        block[c * stride + r] += m[Size * r + c];
  }

  /** The scalar diagonal (Size per block). */
  Eigen::VectorXd diagonal() const
  {
    Eigen::VectorXd d(M.rows());
    for (std::size_t a = 0; a < Rows.size(); ++a)
    {
      const double* block = slot(static_cast<std::int64_t>(a), static_cast<std::int64_t>(a));
      const int stride = columnStride(static_cast<std::int64_t>(a));
      for (int k = 0; k < Size; ++k)
        d[static_cast<Eigen::Index>(Size * a + k)] = block[k * stride + k];
    }
    return d;
  }

  /** Adds `value` to every scalar diagonal entry. */
  void addToDiagonal(const Eigen::VectorXd& value)
  {
    for (std::size_t a = 0; a < Rows.size(); ++a)
    {
      double* block = slot(static_cast<std::int64_t>(a), static_cast<std::int64_t>(a));
      const int stride = columnStride(static_cast<std::int64_t>(a));
      for (int k = 0; k < Size; ++k)
        block[k * stride + k] += value[static_cast<Eigen::Index>(Size * a + k)];
    }
  }

  /** Visits every stored block (a >= b) as f(a, b, first value, column stride). */
  template <typename F>
  void forEachBlock(F f) const
  {
    for (std::size_t b = 0; b < Rows.size(); ++b)
    {
      const double* column = M.valuePtr() + M.outerIndexPtr()[Size * b];
      const int stride = columnStride(static_cast<std::int64_t>(b));
      for (std::size_t k = 0; k < Rows[b].size(); ++k)
        f(Rows[b][k], static_cast<std::int64_t>(b), column + Size * k, stride);
    }
  }

  /** The scalar matrix of the blocks' traces / Size (lower triangle, blockCount^2): P (x) I is a
   *  rotation-invariant approximation of this matrix (for Size 3), and P is symmetric positive
   *  (semi)definite when this matrix is (it is the mean of the compressions onto one
   *  coordinate). */
  Matrix traceMatrix() const
  {
    std::vector<Eigen::Triplet<double>> entries;
    forEachBlock(
        [&](std::int64_t a, std::int64_t b, const double* block, int stride)
        {
          double trace = 0;
          for (int k = 0; k < Size; ++k)
            trace += block[k * stride + k];
          entries.emplace_back(static_cast<int>(a), static_cast<int>(b), trace / Size);
        });
    Matrix P(static_cast<Eigen::Index>(Rows.size()), static_cast<Eigen::Index>(Rows.size()));
    P.setFromTriplets(entries.begin(), entries.end());
    return P;
  }

private:
  // Distance between the same row of two consecutive columns of block column b.
  int columnStride(std::int64_t b) const { return static_cast<int>(Size * Rows[b].size()); }

  // First value of block (a, b), a >= b, in column Size b.
  double* slot(std::int64_t a, std::int64_t b)
  {
    return const_cast<double*>(static_cast<const BlockSparseMatrixOf*>(this)->slot(a, b));
  }
  const double* slot(std::int64_t a, std::int64_t b) const
  {
    const auto& rows = Rows[static_cast<std::size_t>(b)];
    const auto it = std::lower_bound(rows.begin(), rows.end(), a);
    if (it == rows.end() || *it != a)
      throw std::out_of_range("BlockSparseMatrix: block outside the pattern");
    return M.valuePtr() + M.outerIndexPtr()[Size * b] + Size * (it - rows.begin());
  }

  std::vector<std::vector<std::int64_t>> Rows; // per block column b: stored block rows a >= b
  Matrix M;
};

/** One 3x3 block per mesh vertex. */
using BlockSparseMatrix = BlockSparseMatrixOf<3>;

} // namespace dp::support
