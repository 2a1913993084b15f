// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DataFitCompression.h
 * @brief Compression judged by a take's fit to its data (DataFit.h).
 *
 * compressAgainstData(): compression whose error target is the data's, not a share of the
 * motion's size: the decompressed take's distance to the samples may grow by at most `growth`
 * (0.1: 10 %) over the tracked take's. A deviation d of the vertices along the surface's normal
 * adds to a fit f as sqrt(f^2 + d^2), and along the surface it adds nothing, so an RMS deviation
 * of sqrt(3 ((1 + growth)^2 - 1)) f (spread evenly over the three directions) is asked of the
 * codec (PcaErrorMeasure::RmsDeviation); the decompressed take is then measured, and where it
 * grew more than allowed the deviation is asked again from what the measurement shows (at most 5
 * codings).
 *
 * slideAlongSurface(), with `slide`: a tracked vertex also wanders along the surface from frame to
 * frame (its sliding, which the data do not see and a low-rank model does not explain), and the
 * codec pays for that wander in components. So the take is also coded slid: each vertex moved
 * along its surface (across its normal only, a little each step) toward where a model of fewer
 * components (0.55, and in a second coding 0.8, of those the take needed as tracked) puts it,
 * and the fewest bits that keep the fit win. Measured on jumping against its true motion, the slide
 * leaves the vertex error against the truth as it was (it removes wander, not motion).
 *
 * Limits: a take without samples (no points in any frame) has no fit to keep; it is compressed
 * at KG 0.2 %, the codec's default. The slide holds one more copy of the take and its
 * decomposition, and codes the take twice more (about twice the time of the coding alone).
 */
#pragma once

#include "dp/compress/PcaCompression.h"
#include "dp/geometry/DataFit.h"

#include <functional>
#include <vector>

namespace dp
{

struct DataFitCompression
{
  CompressedSequence sequence;
  DataFit tracked;            // the take as given
  DataFit decompressed;       // the decompressed take, on the same samples
  double growth = 0;          // decompressed.rms / tracked.rms - 1
  double deviationTarget = 0; // the RMS deviation last asked of the codec (world units)
  int rounds = 0;             // codings
  bool slid = false; // the take slid along its surface was coded in fewer bits (the report's
                     // errors are still measured against the take as given)
};

/** The take (frame-major positions of the mesh's vertices) with each vertex slid along its
 *  surface toward where `components` principal components in `layout` put it: a few steps, each
 *  across the vertex's normal only and at most a share of its mean edge length. */
std::vector<double> slideAlongSurface(const TriangleMesh& mesh, const double* positions,
                                      std::size_t frames, std::size_t components, PcaLayout layout);

/** Compresses a take (positions frame-major, `frames` frames of the mesh's vertices) so that its
 *  fit to the samples grows by at most `growth`; `options` gives the layout (its measure and
 *  target are set here); `slide`: also code the take slid along its surface. Throws
 * std::invalid_argument for a growth <= 0 or non-finite, and what compressSequence throws. */
DataFitCompression compressAgainstData(const TriangleMesh& mesh, const double* positions,
                                       std::size_t frames,
                                       const std::vector<const FrameSamples*>& samples,
                                       double reach, double growth, PcaOptions options,
                                       bool slide = true, const std::vector<double>& times = {},
                                       const std::function<bool(double)>& progress = {});

} // namespace dp
