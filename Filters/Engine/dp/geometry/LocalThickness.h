// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file LocalThickness.h
 * @brief How thick the shape is at each vertex: the radius of the largest ball inside the
 *        surface that touches it at the vertex (its inner medial ball), found by shrinking a
 *        ball along the inward normal until no other vertex lies inside it (the shrinking-ball
 *        method of Ma, Bae & Verbeek, 2012), then averaged over a few rings; or, outside, how
 *        narrow the space in front of it is (the outer medial ball: small in creases).
 *
 * The tracker uses it to tell limbs from trunks (ThicknessSoftening): a thin part lies within
 * a few centimetres of other parts' data and has to keep its shape, while a thick one has data
 * all round it and can follow skin that stretches; and to find creases (CreaseSoftening).
 *
 * Limits: vertices stand in for the surface, so a ball can slip between vertices on coarse
 * meshes (the radius is then too large by up to half an edge); normals are taken outward when
 * the faces enclose a positive volume with the vertices' centroid (inward ones are flipped),
 * which holds for closed meshes and tubes but is a guess for other open surfaces; balls that
 * touch nothing (a flat sheet) stop at `largest`.
 */
#pragma once

#include "dp/geometry/TriangleMesh.h"

#include <vector>

namespace dp
{

/** Which side of the surface the ball lies on: inside (how thick the part is) or outside (how
 *  narrow the gap or crease in front of the vertex is; `largest` where nothing faces it). */
enum class MedialSide
{
  Inside,
  Outside
};

/** The medial-ball radius at each vertex of `mesh` at `positions` on `side`, no larger than
 *  `largest` (world units), averaged `smoothing` times over each vertex's one-ring. */
std::vector<double> medialRadii(const TriangleMesh& mesh, const double* positions, double largest,
                                int smoothing = 3, MedialSide side = MedialSide::Inside);

/** `values` per vertex averaged `passes` times over each vertex's one-ring. */
std::vector<double> smoothOverRings(const TriangleMesh& mesh, std::vector<double> values,
                                    int passes);

} // namespace dp
