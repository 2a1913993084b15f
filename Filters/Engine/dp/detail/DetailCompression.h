// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DetailCompression.h
 * @brief The detail layer of a take compressed against its data, after its base.
 *
 * The displacements were fitted to each frame on the tracked base; the file stores the base
 * compressed. So first each fitted fine vertex x_i = p_i + d_i n_i is carried over to the
 * decoded base (closed loop): its new displacement is where the decoded base's normal line at
 * p'_i meets the plane through x_i across the fitted fine mesh's normal m_i,
 * d'_i = (x_i - p'_i) . m_i / (n'_i . m_i) (or the plain projection on n'_i where the two
 * normals part by more than 60 degrees). The base's coding error is thus undone along the
 * normals, and what remains to code is the detail itself.
 *
 * Then the quantisation step: as the base's (dp::compressAgainstData), the decompressed fine
 * mesh's RMS distance to each frame's samples may grow by at most `growth` over the fitted fine
 * mesh's. A deviation of the displacements of RMS e adds about c e^2 to the squared fit (c near
 * 1: the deviations are along the normals); the first step tried, sqrt(12) e, is the one that
 * would give the allowed growth with c = 1; each round measures c on its quantisation and asks
 * again (a little under: 0.97), at most five rounds; the largest step that keeps the fit wins
 * (the fewest bits). The rounds measure about 30 frames spread over the take (each measure
 * builds a closest-point tree of the fine mesh per frame); the step found is then checked on
 * every frame, and made smaller until the whole take keeps the fit. Only the kept step is
 * range-coded (dp::setDetail); the rounds quantise alone. With a motion target instead (KG), the
 * detail is quantised to the base's own RMS deviation (compressDetailAtDeviation).
 *
 * Limits: the take's fitted displacements and their carried-over copy are held in memory (16
 * bytes a fine vertex a frame).
 */
#pragma once

#include "dp/compress/DataFitCompression.h"
#include "dp/compress/PcaCompression.h"
#include "dp/geometry/SubdivisionMap.h"

#include <functional>
#include <vector>

namespace dp
{

/** A take's detail layer as fitted: what its coding reads. */
struct FittedDetail
{
  const SubdivisionMap& map;
  const double* base;          // the tracked base, frame-major (3 per base vertex a frame)
  const double* displacements; // the fitted displacements, frame-major (1 per fine vertex)
  std::size_t frames = 0;
};

struct DetailCompression
{
  DataFit fitted;       // the fitted fine mesh's fit to the samples
  DataFit decompressed; // the decompressed fine mesh's, on the same samples
  double growth = 0;    // decompressed.rms / fitted.rms - 1
  int rounds = 0;       // quantisations measured
};

/** The fitted displacements carried over to the decoded base of `sequence` (see the file
 *  comment): frames x fine vertices, frame-major. */
std::vector<double> carriedToDecodedBase(const FittedDetail& detail,
                                         const CompressedSequence& sequence);

/**
 * Gives `sequence` (its base compressed) the detail layer of `detail` at the step that keeps
 * the fine mesh's fit to `samples` (one per frame, null or empty: no data) within `growth`;
 * samples farther than `reach` from the fitted fine mesh are left out (DataFit). Throws
 * std::invalid_argument for a growth <= 0 or a frame count that is not the sequence's.
 * `progress` (may be empty) gets a fraction in [0, 1]; returning false aborts
 * (std::runtime_error "aborted").
 */
DetailCompression compressDetailAgainstData(CompressedSequence& sequence,
                                            const FittedDetail& detail,
                                            const std::vector<const FrameSamples*>& samples,
                                            double reach, double growth,
                                            const std::function<bool(double)>& progress = {});

/** Gives `sequence` the detail layer of `detail` quantised to an RMS deviation of
 *  `rmsDeviation` (world units, > 0), e.g. the base's own coding error under a KG target. */
void compressDetailAtDeviation(CompressedSequence& sequence, const FittedDetail& detail,
                               double rmsDeviation);

} // namespace dp
