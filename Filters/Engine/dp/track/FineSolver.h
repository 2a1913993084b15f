// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FineSolver.h
 * @brief The fine level's minimiser, chosen once from TrackerOptions::solver: Gauss-Newton
 *        (default; its matrix pattern and symbolic analysis kept for the take), L-BFGS, or the
 *        paper's steepest descent (eq. 2-3) with provisional determination. See Solvers.h for
 *        each method.
 */
#pragma once

#include "dp/track/Solvers.h"
#include "dp/track/TrackerOptions.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace dp
{

class TriangleMesh;

class FineSolver
{
public:
  virtual ~FineSolver() = default;

  /** Minimises the sum of `terms` from x (in place). `distance` (may be null) is the term whose
   *  broken promises damp single vertices (Gauss-Newton); `frozen` (one flag per vertex) gets
   *  the vertices provisional determination froze (steepest descent). Returns the steps. */
  virtual int solve(std::vector<double>& x, const std::vector<EnergyTerm*>& terms,
                    const DistanceTerm* distance, const SolveSettings& settings,
                    std::vector<std::uint8_t>& frozen) = 0;

  /** Whether its steps after the coarse level may be capped (GraphOptions::fineIterations):
   *  Gauss-Newton's few steps fit the detail the coarse level left. */
  virtual bool takesFewStepsAfterCoarseLevel() const { return false; }

  /** The solver `options` ask for, for `mesh` (`lengthScale`: ClothEnergy::lengthScale). */
  static std::unique_ptr<FineSolver> make(const TrackerOptions& options, const TriangleMesh& mesh,
                                          double lengthScale);
};

} // namespace dp
