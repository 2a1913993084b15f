// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Solvers.h
 * @brief The fine level's minimisers of a sum of energy terms over the vertex positions:
 *
 *   GaussNewtonSolver (default): Levenberg-Marquardt. Each iteration re-linearises the terms and
 *     assembles their Gauss-Newton models into a matrix of fixed sparsity pattern (the terms'
 *     couplings); each step is an inexact Newton step, conjugate gradients preconditioned by
 *     the factorised matrix of its 3x3 blocks' traces (a third of the unknowns), applied to a
 *     vertex's three coordinates at once. A step is kept when E falls by at least a tenth of what
 *     the model promised; where one vertex's distance term breaks that promise (it sits between
 *     two parts of the data), that vertex alone is damped. A solve ends when E's relative
 *     decrease falls under the tolerance or no vertex moves a tenth of a voxel; the terms'
 *     discrete choices (normal test) are then decided again at the new shape (twice at most).
 *   solveLbfgs: quasi-Newton (libLBFGS, More-Thuente line search), two passes with the choices
 *     decided again between them.
 *   solveSteepestDescent: the paper's solver (eq. 2-3): x <- x - h grad E, h = 1.9 / k_max with
 *     k_max the Hessian's largest eigenvalue by power iteration (halved where a step would raise
 *     E); stops when ten iterations gain less than a tenth of the tolerance. With provisional
 *     determination (PD), every 5 iterations a vertex whose net motion is under a quarter of the
 *     path it stepped is frozen, until a neighbour moves steadily (net motion over half its path).
 *
 * Limits: Gauss-Newton's matrix pattern is fixed at construction (the union of the couplings of
 * the terms it will see); the paper's solver needs many iterations (it is kept as a mode).
 */
#pragma once

#include "dp/geometry/TriangleMesh.h"
#include "dp/support/BlockSparseMatrix.h"
#include "dp/track/EnergyTerm.h"
#include "dp/track/TracePreconditioner.h"

#include <cstdint>
#include <vector>

namespace dp
{

class DistanceTerm;

struct SolveSettings
{
  int maxIterations = 300;
  double tolerance = 1e-3; // relative energy decrease that ends a solve
  double settledStep = 0;  // world units: a step moving no vertex farther ends a solve
  int decisions = 2;       // how often a settled solve may re-decide the terms' choices
};

class GaussNewtonSolver
{
public:
  /** A solver for `vertexCount` vertices whose terms couple at most `pairs`. */
  GaussNewtonSolver(std::size_t vertexCount, const std::vector<std::array<std::int64_t, 2>>& pairs);

  /** Minimises the sum of `terms` from x (in place); `distance`, when not null, is the term whose
   *  broken promises damp single vertices. Returns the iterations taken. */
  int solve(std::vector<double>& x, const std::vector<EnergyTerm*>& terms,
            const DistanceTerm* distance, const SolveSettings& settings);

private:
  /** Linearises the terms at x and fills Hessian and gradient with their model; returns E(x). */
  double buildModel(const std::vector<double>& x, const std::vector<EnergyTerm*>& terms,
                    Eigen::VectorXd& gradient);
  /** The step of the model damped by `shift` (on the diagonal): conjugate gradients
   *  preconditioned by the trace matrix, factorised again when `factorise`. */
  Eigen::VectorXd dampedStep(const Eigen::VectorXd& gradient, const Eigen::VectorXd& shift,
                             bool factorise);

  support::BlockSparseMatrix Hessian;
  TracePreconditioner Preconditioner; // (P (x) I_3)^-1, P the matrix of the blocks' traces / 3
};

/** L-BFGS on the sum of `terms`; returns the energy evaluations. */
int solveLbfgs(std::vector<double>& x, const std::vector<EnergyTerm*>& terms,
               const SolveSettings& settings);

/** The paper's steepest descent, with provisional determination when `frozen` is not null (one
 *  flag per vertex, set for the vertices frozen at the end). `lengthScale` sets the finite
 *  differences of the curvature estimate. Returns the iterations taken. */
int solveSteepestDescent(std::vector<double>& x, const std::vector<EnergyTerm*>& terms,
                         const TriangleMesh& mesh, double lengthScale,
                         const SolveSettings& settings, std::vector<std::uint8_t>* frozen);

} // namespace dp
