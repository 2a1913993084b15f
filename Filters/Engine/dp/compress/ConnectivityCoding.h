// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file ConnectivityCoding.h
 * @brief The triangles of a .dpz file from format version 5 on: each corner's vertex named by
 *        where it stands in a short list of likely vertices, by the adaptive binary range coder
 *        (RangeCoder.h), or the varints through zstd of versions 1 to 4, whichever is smaller.
 *
 * The triangles and their corners are kept in their order (the detail layer's fine vertices are
 * numbered from it, and the decoded mesh is the tracked one), so a vertex cannot be renumbered or
 * a triangle moved, as connectivity coders that choose their own traversal do (Edgebreaker,
 * Draco). What remains is locality: a triangle's vertices are mostly ones seen lately or
 * neighbours of its corners already decoded. Each corner, in order, is coded as
 *   - the next new vertex (one more than the largest index so far: meshes numbered as built), or
 *   - its position in a candidate list: for the second corner the first corner's neighbours (by
 *     the edges decoded so far), for the third the second's and then the first's, then the
 *     vertices of the last triangles (most recent first), at most ListSize in all, or
 *   - an escape and its index's difference from the largest so far.
 * Each kind of corner (first, second, third) has its own adaptive models. On a tracked human's
 * template (1000 vertices, 2045 triangles) this takes 13 bits a triangle, where the predicted
 * varints through zstd of versions 1-4 took 22. A mesh numbered in a regular pattern (generated
 * grids and tubes) is another matter: zstd finds the pattern and packs it to almost nothing, so
 * the encoder codes both and keeps the smaller, saying which in the first byte (0 the varints,
 * 1 the corners).
 *
 * Limits: the decoder refuses (std::runtime_error naming `what`) an index outside the vertex
 * count, a position beyond its list, more triangles than its bytes can hold, and a stream that
 * runs out; the checksum of the file catches what decodes to a valid but wrong mesh. Time
 * and memory linear in the triangles (lists of at most ListSize).
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace dp::compress
{

/** The range coder's bytes of `triangles` (3 vertex indices each, all below `vertices`). */
std::vector<std::uint8_t> encodeConnectivity(const std::vector<std::int64_t>& triangles,
                                             std::size_t vertices);

/** The `triangleCount` triangles decoded from `bytes`; throws std::runtime_error naming `what`. */
std::vector<std::int64_t> decodeConnectivity(const std::uint8_t* bytes, std::size_t size,
                                             const std::string& what, std::size_t triangleCount,
                                             std::size_t vertices);

/** The triangles from the unpacked varints of versions 1 to 4 (IntegerCodec.h's putSequence,
 *  stride 3); throws std::runtime_error naming `what` when they are not `triangleCount`
 *  triangles of indices below `vertices`. */
std::vector<std::int64_t> unpackTriangles(const std::vector<std::uint8_t>& raw,
                                          const std::string& what, std::size_t triangleCount,
                                          std::size_t vertices);

} // namespace dp::compress
