// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DataFit.h
 * @brief How well a tracked take fits its data.
 *
 * measureDataFit(): the RMS distance from each frame's samples (the well-spread subsample the
 * tracker kept, FrameResult::samples) to that frame's mesh surface, over every frame. Samples
 * farther than `reach` from the mesh are counted apart (data the mesh does not explain: parts
 * the template lacks, outliers) and left out of the RMS, so that a few of them do not hide the
 * fit of the rest. Holes in the data cost nothing: the measure runs from the points to the mesh.

 */
#pragma once

#include "dp/geometry/FrameSamples.h"
#include "dp/geometry/TriangleMesh.h"

#include <vector>

namespace dp
{

struct DataFit
{
  double rms = 0;              // of the samples within reach (world units)
  std::size_t samples = 0;     // within reach
  std::size_t beyondReach = 0; // farther (not in the RMS)
};

/** The fit of a take: frame t's mesh is `positions` + 3 nv t (frame-major, nv = the mesh's
 *  vertices), its samples samples[t] (null or empty: a frame without data). Only the samples
 *  that `within` marks (one flag per frame's sample, in order; empty: all within `reach`)
 *  count. */
DataFit measureDataFit(const TriangleMesh& mesh, const double* positions,
                       const std::vector<const FrameSamples*>& samples, double reach,
                       std::vector<std::vector<bool>>* within = nullptr);

} // namespace dp
