// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file TracePreconditioner.h
 * @brief The fine level's preconditioner: z = (P (x) I_3)^-1 r, P the matrix of the Gauss-Newton
 * matrix's 3x3 blocks' traces / 3 (a rotation-invariant, Laplacian-like approximation with a third
 * of the unknowns, so 27x cheaper to factorise), the three coordinates of a vertex solved together.
 *
 * P is factorised exactly, by a sparse Cholesky whose symbolic analysis is done once for the
 * pattern, in METIS's nested-dissection order (on the scaling tube at 50 000 vertices the fine
 * level 1.46x faster than in AMD's order, at 1 000 the same). Two factorisations, chosen by P's
 * size:
 *   - below SupernodalFrom unknowns (small meshes): Eigen's simplicial LDL^T, swept column by
 *     column;
 *   - from SupernodalFrom on: CHOLMOD's supernodal LL^T (dense blocks through BLAS). Its work
 *     grows as n^1.5 on a surface mesh (nested dissection of a planar-like graph); dense kernels
 *     do it several times faster per flop than the simplicial sweep once the supernodes are big.
 *     On the scaling tube at 100 000 vertices the fine level went from 36-42 to 15-16 s a frame.
 *
 * Limits: P must be symmetric positive definite for the supernodal LL^T (a sum of principal
 * submatrices of a positive semi-definite matrix, plus the damping shift, is); `factorise`
 * returns false otherwise and the caller falls back to a diagonal step. CHOLMOD's own OpenMP
 * loops get only the cores that are idle (the tracker's parallelism is TBB's; on 2 cores their
 * fixed 4 threads cost the fine level 40 %). Its speed rests on an optimised BLAS (OpenBLAS):
 * with the reference BLAS it is slower than the simplicial factorisation.
 */
#pragma once

#include "dp/support/BlockSparseMatrix.h"

#include <memory>

namespace dp
{

class TracePreconditioner
{
public:
  /** The size (unknowns of P, i.e. vertices) from which the supernodal factorisation is used.
   *  On the scaling tube, the fine level with it against the simplicial one: 46-51 against
   *  44-45 ms a frame at 1 000 vertices, even at 2 000, 405 against 480-513 at 5 000, 954-1095
   *  against 1285-1376 at 10 000. */
  static constexpr long SupernodalFrom = 2000;

  enum class Kind
  {
    Automatic, // by size (SupernodalFrom)
    Simplicial,
    Supernodal
  };

  explicit TracePreconditioner(long size, Kind kind = Kind::Automatic);
  ~TracePreconditioner();
  TracePreconditioner(const TracePreconditioner&) = delete;
  TracePreconditioner& operator=(const TracePreconditioner&) = delete;

  /** Factorises P (lower triangle stored; the same pattern at every call). False when P is not
   *  positive definite. */
  bool factorise(const support::BlockSparseMatrix::Matrix& P);
  /** z = (P (x) I_3)^-1 r, r holding each vertex's three coordinates in turn. */
  Eigen::VectorXd apply(const Eigen::VectorXd& r) const;
  /** Whether the last factorisation succeeded. */
  bool factorised() const;
  /** Whether the supernodal factorisation is in use. */
  bool supernodal() const;

  class Factorisation;

private:
  std::unique_ptr<Factorisation> Impl;
  bool Factorised = false;
};

} // namespace dp
