// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DetailLevels.h
 * @brief How many levels of detail a take's data hold, measured on its first frame.
 *
 * The candidate is the level whose fine mesh has about as many vertices as the capture resolves:
 * a mesh frame's own vertex count, or for points half their count (a surface through noisy
 * points resolves fewer vertices than it has points), rounded in powers of four from the
 * tracked mesh's count, at most MaximumAutomaticLevels. The candidate is fitted to the frame
 * and kept only where the data hold detail the tracked mesh cannot carry: when its fine mesh lies
 * at least a fifth closer to the frame's samples (RMS distance, DataFit) than the tracked mesh
 * does. Else 0 levels: a smooth or noisy take gains nothing worth its bits and time.
 *
 * Limits: one frame decides for the take; a candidate of 0 is not measured.
 */
#pragma once

#include "dp/detail/DisplacementFit.h"
#include "dp/geometry/FrameSamples.h"

#include <cstdint>
#include <string>
#include <vector>

namespace dp
{

/** The most levels the automatic choice takes (a 1000-vertex base: 64 000 fine vertices). */
constexpr int MaximumAutomaticLevels = 3;
/** The share of the tracked mesh's distance to the data the fine mesh must at least save. */
constexpr double DetailGainThreshold = 0.2;

struct DetailLevelChoice
{
  int levels = 0;
  int candidate = 0;       // the level the capture's density suggested
  double baseDistance = 0; // RMS distance of the samples to the tracked mesh (world units)
  double fineDistance = 0; // ... to the candidate's fine mesh (0 when not measured)
  std::string summary;     // what was measured and chosen, in a sentence
};

/** The mean length of the mesh's edges (each edge once). */
double meanEdgeLength(const std::vector<std::int64_t>& triangles, const double* positions);

/** The levels whose fine mesh has about `captureVertices` vertices over a base of
 *  `baseVertices` (see the file comment), 0 to MaximumAutomaticLevels. */
int levelsForDensity(std::size_t baseVertices, std::size_t captureVertices);

/**
 * The levels for the take whose first frame's tracked mesh is (`triangles`, `positions`) over
 * `data` (its samples `samples`; `captureVertices` as levelsForDensity takes it), the candidate
 * fitted with `options` (see the file comment).
 */
DetailLevelChoice chooseDetailLevels(const std::vector<std::int64_t>& triangles,
                                     const std::vector<double>& positions, const FrameSurface& data,
                                     const FrameSamples& samples, std::size_t captureVertices,
                                     const DisplacementFitOptions& options);

} // namespace dp
