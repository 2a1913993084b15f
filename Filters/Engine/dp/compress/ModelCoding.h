// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file ModelCoding.h
 * @brief The quantised PCA model's integers, predicted over the mesh and along time and written
 *        by the adaptive binary range coder (RangeCoder.h): the geometry of a .dpz file from
 *        format version 4 on (beyond the paper, which stores floats; after the dynamic-mesh
 *        coders that predict PCA coefficients from decoded neighbours, Vasa & Skala's CoDDyaC,
 *        and code them with context-adaptive arithmetic coding, MPEG-4 FAMC).
 *
 * The integers fall in two kinds:
 *   per vertex  the shape layout's mean and basis (a row of 3 + 3k per vertex), the trajectory
 *               layout's weights (k per vertex): coded vertex by vertex in VertexTraversal's
 *               order, each column predicted from the vertex's earlier neighbours by the
 *               MeshPrediction predictor chosen for that column (none, their mean, or the
 *               neighbourhood regression at one of two ridges);
 *   along time  the shape layout's weights (k columns of a value per frame), the trajectory
 *               layout's mean and basis (1 + k columns of x y z per frame): each column predicted
 *               from the value one frame back, or linearly from two, or not at all, as is
 *               cheapest for it.
 * Each residual is coded with an adaptive model chosen by its context: the component's rank
 * (strong components first), and how large the residuals around it were (per vertex: the earlier
 * neighbours' in the same column and the vertex's own in the column before; along time: the
 * frame before's). Quiet and busy parts of the mesh, and strong and weak components, thus learn
 * their statistics apart.
 *
 * Internal to the compression; not installed API. Limits: every integer within +-2^60
 * (std::invalid_argument when encoding); the decoder refuses a stream that runs out or decodes a
 * value beyond that (std::runtime_error naming `what`); the file's checksum catches the rest.
 */
#pragma once

#include "dp/compress/MeshPrediction.h"
#include "dp/compress/PcaCompression.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace dp::compress
{

/** How hard the encoder works: Full tries every predictor; Quick leaves out the regressions
 *  (a valid stream, a few percent larger, in a fraction of the time: the bit-rate search ranks
 *  its candidates so). */
enum class ModelEffort
{
  Full,
  Quick
};

/** The range coder's bytes of q's mean, basis and weights integers. */
std::vector<std::uint8_t> encodeModel(const QuantisedPca& q, const VertexTraversal& traversal,
                                      ModelEffort effort = ModelEffort::Full);

/** Fills q.meanIntegers, basisIntegers and weightIntegers from `bytes`, for the model of
 *  `layout` with the counts given (q.model's other fields are left as they are). */
void decodeModel(const std::uint8_t* bytes, std::size_t size, const std::string& what,
                 const VertexTraversal& traversal, PcaLayout layout, std::size_t frames,
                 std::size_t components, QuantisedPca& q);

} // namespace dp::compress
