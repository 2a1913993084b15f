// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file TrackerParts.h
 * @brief Internal to the tracker: what Tracker keeps besides its energy (Tracker::Parts) and one
 *        try at a frame (Tracker::Attempt), shared by Tracker.cxx (construction, the frame's
 *        data, what the next frames remember) and TrackerAttempts.cxx (the tries at a frame:
 *        start, coarse level, fine solve, quality, retries).
 */
#pragma once

#include "dp/track/DeformationGraph.h"
#include "dp/track/FineSolver.h"
#include "dp/track/FrameQuality.h"
#include "dp/track/GraphRegistration.h"
#include "dp/track/MotionPredictor.h"
#include "dp/track/RecoveryPolicy.h"
#include "dp/track/Tracker.h"

#include <chrono>
#include <cstdint>
#include <memory>
#include <vector>

namespace dp
{

/** Seconds since `since` (a frame's timings). */
inline double elapsed(std::chrono::steady_clock::time_point since)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

/** What the tracker keeps besides the energy: the coarse level, the fine solver (its matrix
 *  pattern and symbolic analysis live as long as the tracker), the motion history. */
struct Tracker::Parts
{
  explicit Parts(const RecoveryOptions& recovery) : Recovery(recovery) {}
  std::unique_ptr<DeformationGraph> Graph;
  std::unique_ptr<GraphRegistration> Registration;
  std::unique_ptr<FineSolver> Fine;
  MotionPredictor Predictor;
  // The take's usual quality and whether the last frame is in doubt: a frame in doubt sets no
  // baseline, no reference and no retry's start, whether or not it was flagged.
  RecoveryPolicy Recovery;
  // The last frame that did not fail, while the frames after it fail: a retry starts there.
  std::vector<double> LastGood;
  DeformationGraph::State LastGoodState;
  bool LastFailed = false;
  DeformationGraph::State RegrownState; // Start::Regrown's, set before its try

  // Each vertex's colour in the first frame with colour (where the template lies on its
  // material), read at the colour term's fine and coarse kernels; empty until then.
  std::vector<float> ColourFine, ColourCoarse;
  std::vector<float> LastColours; // the vertices' colours in the last frame (a hole keeps them)
};

/** One way of solving a frame, and how well it did. */
struct Tracker::Attempt
{
  std::vector<double> positions, startPositions, coarsePositions;
  DeformationGraph::State state;
  FrameQuality quality;
  int iterations = 0, coarseIterations = 0;
  bool solvedOn = false; // the fine level went on from a capped try that failed
  std::vector<std::uint8_t> frozen, rejected;
  std::vector<double> residual;
  double internalEnergy = 0, distanceEnergy = 0;
  FrameTimings timings;
  double score() const { return RecoveryPolicy::score(quality); }
};

} // namespace dp
