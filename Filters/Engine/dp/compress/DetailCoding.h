// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DetailCoding.h
 * @brief The detail layer's displacements coded through the take: one scalar per fine vertex
 *        per frame, quantised at one step, predicted over the subdivision's hierarchy and from
 *        the frame before, and written by an adaptive binary range coder (RangeCoder.h).
 *
 * Frame by frame, level by level of the subdivision (SubdivisionMap: the base's vertices, then
 * each level's new vertices, which lie on edges of the level before), each displacement is
 * predicted from what the decoder already has, and the difference quantised at the step q
 * (closed loop: every decoded value is within q / 2 of the given one, RMS about q / sqrt(12)):
 *
 *   a new vertex on the edge (a, b):  spatial   (d_a + d_b) / 2, this frame's decoded values;
 *                                     temporal  the spatial prediction plus the same vertex's
 *                                               difference from its own prediction a frame before
 *                                               (detail that moves with the surface stays put);
 *   a base vertex:                    spatial   0 (it has no parents);
 *                                     temporal  its decoded value a frame before.
 *
 * Each level of each frame takes the predictor whose residuals cost fewer bits (one adaptive
 * bit says which). The residuals go through one range coder for the whole take, with a model
 * per level and per how large the parents' residuals were (0, 1, 2 or more steps), so quiet and
 * busy regions learn apart. On `jumping` tracked at 1000 vertices and fitted at two levels
 * against per-frame meshes, most of the field is the capture's own per-frame noise: the
 * temporal predictor wins few levels.
 *
 * Limits: decoding runs through the whole take in order (no random access to a frame); the
 * step must be positive and finite and every displacement within 2^52 steps of its prediction
 * (std::invalid_argument otherwise).
 */
#pragma once

#include "dp/compress/PcaCompression.h"
#include "dp/geometry/SubdivisionMap.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace dp
{

/** The decoded displacements of `frames` frames at `step` (frames x fine vertices, frame-major),
 *  without coding them: what a decoder will give back. The encoder's search for a step calls it
 *  on each candidate. `given` is frames x fine vertices, frame-major. */
std::vector<double> quantiseDetail(const SubdivisionMap& map, const double* given,
                                   std::size_t frames, double step);

/** Quantises and codes the displacements: the range coder's bytes. `decoded`, when given,
 *  receives the values a decoder gives back (as quantiseDetail). */
std::vector<std::uint8_t> encodeDetail(const SubdivisionMap& map, const double* given,
                                       std::size_t frames, double step,
                                       std::vector<double>* decoded = nullptr);

/** The displacements `bytes` hold for `frames` frames of `map`'s fine mesh at `step`. Throws
 *  std::runtime_error naming `what` for a stream that runs out or bytes left over. */
std::vector<double> decodeDetail(const SubdivisionMap& map, std::size_t frames, double step,
                                 const std::uint8_t* bytes, std::size_t size,
                                 const std::string& what);

/** Gives `sequence` its detail layer: `displacements` (frames x fine vertices of its base
 *  subdivided `levels` times, frame-major) quantised and coded at `step`. The decoded values
 *  replace them in sequence.detail; report.detailBytes says what the file's section takes.
 *  Throws std::invalid_argument for levels out of range or displacements of another count. */
void setDetail(CompressedSequence& sequence, int levels, const std::vector<double>& displacements,
               double step);

/** Frame t of a sequence with a detail layer at its fine level (3 per fine vertex of `map`, the
 *  sequence's base subdivided detail.levels times): the base frame subdivided and displaced
 *  along its normals. */
void detailedFrame(const CompressedSequence& sequence, const SubdivisionMap& map, std::size_t t,
                   double* fine);

} // namespace dp
