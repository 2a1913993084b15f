// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file TakeRefinement.h
 * @brief The take's refinement (beyond the paper): once the forward pass (Tracker) has tracked
 *        every frame, all frames are solved again together, each against its own data, the
 *        template's rest state and the frames on both sides of it:
 *
 *   E = sum_t [ E_cov(X_t; samples_t) + E_int(X_t; template) ]
 *     + k_time / (L voxel) sum_t sum_i m_i / 2 |X_i[t+1] - 2 X_i[t] + X_i[t-1]|^2
 *
 * with E_cov the points -> mesh term (CoverageTerm) on the frame's well-spread subsample,
 * E_int the cloth energy (ClothEnergy) with the template as its rest state in every frame (the
 * forward pass lets its rest state follow the last frame, so a slide once made is kept) and
 * the last term the vertices' accelerations, in both directions of time (a causal term lags
 * real motion; this one does not). Holes in the data pull nothing: where a frame has no points
 * the mesh is held by its shape and by the frames around it.
 *
 * Solved by block Gauss-Seidel over time: in each pass the frames are split into three
 * interleaved sets (t mod 3); the frames of a set do not share a term, so they are solved side
 * by side (TBB), each by a few Levenberg-Marquardt steps (GaussNewtonSolver) with its
 * neighbours held, the acceleration term then being a pull toward a blend of them. The same
 * bits for any thread count.
 *
 * Limits: a local refinement of the forward pass's result (it does not recover a lost limb);
 * the data say nothing about where a vertex lies along the surface, so what holds it there is
 * the template's shape and the motion's smoothness; frames are taken as evenly spaced in time.
 */
#pragma once

#include "dp/track/ClothEnergy.h"
#include "dp/track/FrameSamples.h"
#include "dp/track/TrackerOptions.h"

#include <functional>
#include <vector>

namespace dp
{

class Tracker;

class TakeRefinement
{
public:
  /** Refines takes tracked by `tracker` (its mesh, template, cloth and voxel; it must outlive
   *  this). Throws std::invalid_argument for options out of range. */
  TakeRefinement(const Tracker& tracker, const RefinementOptions& options);
  ~TakeRefinement();

  /** Refines `positions` (one vector of 3 per vertex for each frame, in time order) in place
   *  against `samples` (one per frame; empty for a frame without data). `progress`, when given,
   *  is told the share done (0 to 1) after each set of frames; returning false stops the
   *  refinement there (the frames keep the last complete set's positions). Returns false when
   *  stopped. Throws std::invalid_argument when the counts do not match the template's or each
   *  other. */
  bool refine(std::vector<std::vector<double>>& positions,
              const std::vector<const FrameSamples*>& samples,
              const std::function<bool(double)>& progress = {}) const;

  /** E of a take (the sum above) with the current correspondences of a fresh linearisation;
   *  for tests and diagnosis. */
  double energy(const std::vector<std::vector<double>>& positions,
                const std::vector<const FrameSamples*>& samples) const;

private:
  struct FrameProblem;
  struct ColourCue;
  ColourCue colourCue(const std::vector<const FrameSamples*>& samples,
                      const std::vector<std::vector<double>>& positions) const;
  // One frame's solve with its neighbours held.
  void solveFrame(std::size_t t, std::vector<std::vector<double>>& positions,
                  const std::vector<const FrameSamples*>& samples,
                  const std::vector<std::vector<double>>& forward, const ColourCue* cue,
                  class GaussNewtonSolver& solver, int iterations) const;

  const Tracker& Source;
  RefinementOptions Options;
  ClothEnergy Cloth; // the tracker's, with the template as its rest state
};

} // namespace dp
