// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file SubdivisionMap.h
 * @brief The fine mesh's connectivity and the fixed linear map from the tracked (base) mesh's
 *        vertices to it: Loop subdivision applied L times (Loop 1987; the sharp rules of Hoppe
 *        et al. 1994 on boundaries and non-manifold edges).
 *
 * Each level splits every triangle into four at its edges' midpoints. The vertices of level l+1
 * are level l's vertices first (same indices), then one per edge of level l, in the order of the
 * sorted edge list (a < b); the triangles are each parent's four children in turn, (a ab ca),
 * (ab b bc), (ca bc c), (ab bc ca), orientation kept. Positions follow Loop's masks:
 *
 *   new edge vertex, interior edge (two triangles):  3/8 (a + b) + 1/8 (c + d)
 *   new edge vertex, sharp edge (one, or > 2):        1/2 (a + b)
 *   old vertex of valence n, no sharp edge:           (1 - n beta) v + beta sum(neighbours),
 *                                                     beta = 3 / (8 n) (n > 3), 3/16 (n = 3)
 *   old vertex on exactly two sharp edges (crease):   3/4 v + 1/8 (s1 + s2)
 *   old vertex on one or more than two sharp edges:   v (a corner)
 *
 * so a frame's fine positions are a fixed linear function of its base positions, the same map
 * for every frame of a take: the fine mesh has one connectivity through the take, and the
 * detail layer's displacements are in correspondence from frame to frame. The map is stored as
 * one sparse matrix per level (at most 7 + valence entries a row) and applied level by level:
 * O(fine vertices), multi-threaded, the same result for any thread count.
 *
 * Loop's surface is approximating: it does not pass through the base vertices and shrinks
 * convex parts a little (a 642-vertex sphere by at most 0.6 % of its radius after two levels);
 * the displacements along the normal put the surface back on the data.
 *
 * Limits: triangles only; a triangle that repeats a vertex is refused (std::invalid_argument).
 * Fine vertex counts grow as 4^L (a 1000-vertex base: 4 000, 16 000, 64 000 at L = 1, 2, 3).
 */
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace dp
{

/** The largest number of levels a map may have (a 1000-vertex base: 16 million fine vertices). */
constexpr int MaximumDetailLevels = 6;

class SubdivisionMap
{
public:
  /** The map of `levels` (0 .. MaximumDetailLevels) Loop subdivisions of the base mesh. Throws
   *  std::invalid_argument for an index out of range, a repeated vertex or too many levels. */
  SubdivisionMap(const std::vector<std::int64_t>& baseTriangles, std::size_t baseVertices,
                 int levels);

  int levels() const { return static_cast<int>(Levels.size()); }
  std::size_t baseVertices() const { return BaseVertices; }
  std::size_t fineVertices() const { return Counts.back(); }
  /** Vertices of level l (0: the base, levels(): the fine mesh). */
  std::size_t verticesOf(int level) const { return Counts[static_cast<std::size_t>(level)]; }
  const std::vector<std::int64_t>& fineTriangles() const { return Triangles; }
  /** For each vertex of the fine mesh that a split made (index >= baseVertices()), the edge of
   *  the level before it was made on: (a, b), a < b, both of smaller index. */
  const std::vector<std::array<std::int64_t, 2>>& parents() const { return Parents; }

  /** The fine positions (3 per fine vertex) of base positions (3 per base vertex). */
  void apply(const double* base, double* fine) const;
  /** The same, and the fine mesh's unit area-weighted vertex normals there (vertexNormalsOf). */
  void subdivide(const double* base, double* fine, double* normals) const;

private:
  // One level's masks: row r of the level's output is sum of weight[k] * input[column[k]],
  // k in [start[r], start[r + 1]).
  struct Level
  {
    std::vector<std::size_t> start;
    std::vector<std::int64_t> column;
    std::vector<double> weight;
  };
  // Adds the level that subdivides `triangles` (of `vertices` vertices); replaces `triangles`
  // by the level's own.
  void subdivide(std::vector<std::int64_t>& triangles, std::size_t vertices);

  std::size_t BaseVertices = 0;
  std::vector<std::size_t> Counts; // vertices per level, base first
  std::vector<Level> Levels;
  std::vector<std::int64_t> Triangles;
  std::vector<std::array<std::int64_t, 2>> Parents;
};

/** r g b bytes per base vertex carried to the fine vertices by the map (each channel as a
 *  coordinate, rounded): 3 bytes per fine vertex. */
std::vector<std::uint8_t> subdividedColours(const SubdivisionMap& map, const std::uint8_t* rgb);

/** A detail layer's fine positions: out_i = fine_i + displacement_i normal_i (3 per vertex). */
void displaceAlongNormals(const double* fine, const double* normals, const double* displacements,
                          std::size_t vertices, double* out);

} // namespace dp
