// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file HandleRemoval.h
 * @brief A closed surface made genus 0 by cutting its handles where they are thinnest: what a
 *        template of a body needs when a noisy capture bridged two parts (an arm to the torso,
 *        the legs) or left a tunnel in its layer.
 *
 * A closed, oriented, connected triangle mesh of genus g has 2g independent non-separating
 * loops. From each of a sample of roots, a shortest-path tree T (edge lengths) and a spanning
 * tree of the faces across the edges not in T leave exactly 2g edges; each closes a loop through
 * T (tree-cotree, Eppstein 2003; the shortest such loops over the roots are the greedy system of
 * Erickson & Whittlesey 2005). The shortest loop found is cut: the mesh is split along it and
 * both sides are capped by a fan to their centroid. Each cut lowers the genus by one; repeated
 * until the genus is 0, the shortest loop is longer than asked (a handle of the subject's own:
 * a handle the noise made is thin beside the subject) or `maximumCuts` cuts were made.
 *
 * Limits: the caps are flat fans (remesh after, IsotropicRemesher.h); a handle the subject truly
 * has (a hand on the hip closes a loop of the arm) is cut too, at its thinnest place. Roots are at
 * most 64 vertices spread over the mesh, so the loop cut is short, not proven shortest.
 */
#pragma once

#include "dp/geometry/IsotropicRemesher.h"

#include <cstddef>

namespace dp::support
{

/** The genus of a closed, connected mesh (2 - V + E - F) / 2; -1 when it has a boundary or an
 *  edge of more than two triangles. */
int genusOf(const IndexedMesh& mesh);

/** Cuts handles of `mesh` (closed, consistently oriented, connected) until its genus is 0 or
 *  the shortest loop left is longer than `longestLoop` (a handle the subject has: a torus's);
 *  returns the number of cuts. Leaves a mesh that is not closed or not manifold unchanged. */
std::size_t removeHandles(IndexedMesh& mesh, double longestLoop, std::size_t maximumCuts = 64);

} // namespace dp::support
