// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file IsotropicRemesher.h
 * @brief The second stage of reconstructSurface: a fine triangle surface (OpenVDB's mesh of the
 *        zero crossing) remeshed to a wanted vertex count with evenly shaped triangles, every
 *        vertex on the fine surface.
 *
 * Method: isotropic remeshing (Botsch & Kobbelt 2004, "A remeshing approach to multiresolution
 * modeling"): iterations of edge splits (longer than 4/3 L), collapses (shorter than 4/5 L),
 * flips towards valence 6 and tangential relaxation, each vertex projected back onto the fine
 * surface. A collapse keeps the link condition, folds no triangle and puts the merged vertex at
 * the end or the midpoint that best keeps the fine surface's planes around the edge, as in
 * Garland & Heckbert's quadric simplification (1997), so that tips and thin parts do not shrink.
 * The edge length L is the one that the fine surface's area and the wanted count call for,
 * corrected once from the count reached; then the shortest edges are collapsed or the longest
 * split until the count is met, the triangles are evened out again and the diagonals of poorly
 * shaped pairs flipped.
 *
 * Limits: the count is met exactly unless the checks (link condition, no folds, no edge longer
 * than allowed) refuse the last collapses, or the mesh is down to four vertices. Edges of the
 * input shared by more than two triangles, or by two of the same orientation, become boundaries,
 * and vertices where separate fans meet are split: the output is manifold, not necessarily
 * closed. Parts much thinner than L are kept only coarsely. The orientation is the input's.
 */
#pragma once

#include "dp/support/Vec3.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace dp::support
{

/** A triangle mesh as positions and vertex index triples. */
struct IndexedMesh
{
  std::vector<Vec3> positions;
  std::vector<std::array<int, 3>> triangles;
};

/** The remeshed surface: x y z per vertex, three vertex indices per triangle. */
struct RemeshedSurface
{
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;
  bool closed = false; // every edge has two triangles
};

/**
 * Remeshes `fine` (at least a few triangles, of positive total area) to about `targetVertices`
 * vertices (see Limits). `fine` is the reference surface the vertices stay on; its triangles
 * should be consistently oriented (the projection matches each vertex with the fine triangles
 * facing its way).
 */
RemeshedSurface remeshIsotropic(const IndexedMesh& fine, std::size_t targetVertices);

} // namespace dp::support
