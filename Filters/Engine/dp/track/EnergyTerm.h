// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file EnergyTerm.h
 * @brief One term of the tracking energy E(x) over the mesh's vertex positions x (3 per vertex):
 *        its value, its gradient and its Gauss-Newton model, so that every solver (Gauss-Newton,
 *        L-BFGS, the paper's steepest descent, the deformation graph's coarse solve) works on any
 *        sum of terms.
 *
 * A term may hold things fixed while a step is taken (correspondences, robust weights, the
 * normal test): linearise() re-decides the per-step ones at the current shape (every
 * Gauss-Newton iteration), decide() the discrete choices that should change only once a solve
 * has settled. Between two such calls the term is a smooth function of x, which is what the
 * value, gradient and model describe (checked against finite differences in the tests).
 *
 * Units: every term is dimensionless (the data terms divide squared lengths by voxel x L, with L
 * = sqrt(template area)), so weights mean the same at any scale of the data.
 */
#pragma once

#include "dp/support/BlockSparseMatrix.h"

#include <array>
#include <cstdint>
#include <vector>

namespace dp
{

class EnergyTerm
{
public:
  virtual ~EnergyTerm() = default;
  virtual const char* name() const = 0;

  /** The term at x; adds its gradient to `gradient` (3 per vertex) when it is not null. */
  virtual double evaluate(const double* x, double* gradient) const = 0;

  /** Adds the term's Gauss-Newton matrix to `hessian` and its gradient to `gradient` at x;
   *  returns the value. The matrix's pattern must hold the pairs of couplings(). */
  virtual double addModel(const double* x, support::BlockSparseMatrix& hessian,
                          double* gradient) const = 0;

  /** Re-decides what a step holds fixed (correspondences, robust weights) at x. */
  virtual void linearise(const double* /*x*/) {}
  /** Re-decides discrete choices at a settled x; returns how many changed. */
  virtual std::size_t decide(const double* /*x*/) { return 0; }

  /** Pairs of vertices the model couples, beyond each vertex with itself. */
  virtual void couplings(std::vector<std::array<std::int64_t, 2>>& /*pairs*/) const {}
};

/** The sum of several terms at x, with the gradient added when asked for. */
inline double evaluateAll(const std::vector<EnergyTerm*>& terms, const double* x, double* gradient)
{
  double e = 0;
  for (const EnergyTerm* t : terms)
    e += t->evaluate(x, gradient);
  return e;
}

} // namespace dp
