// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file PartRegrowth.h
 * @brief A start for a frame that lost a part: the part the data left, moved rigidly onto the
 *        points nothing explains, so that the coarse level, whose reach is a few tens of voxels,
 *        can find a limb that moved farther within one frame.
 *
 * The lost part L is the largest connected set of vertices (along the mesh's edges) farther than
 * `reach` from every data point; the unexplained points Q are the frame's subsample points
 * (strays left out) farther than `reach` from the mesh. The rigid motion (R, t) minimises
 *
 *   sum_{v in L} |R x_v + t - q(v)|^2 + sum_{q in Q} |q - (R x_l(q) + t)|^2,
 *
 * with q(v) the point of Q nearest the moved vertex and l(q) the moved vertex nearest q (both
 * ways, so neither set may shrink onto a corner of the other): iterative closest points, each step
 * solved exactly (Kabsch). It starts from no rotation and from L's and Q's principal axes agreeing
 * (both signs), the centroids matched; the end kept is the one whose mean squared distance plus
 * the mean squared shift of the part's border (its vertices next to the rest of the mesh: where a
 * limb joins the body) is the smallest, which tells a limb from the limb turned end for end.
 *
 * Limits: one part a frame (the largest); a part that bent at a joint as well as moved is brought
 * near, not fitted (the coarse level that follows bends it); brute-force nearest neighbours, so
 * its cost grows as |L| |Q| (a few hundred of each in practice).
 */
#pragma once

#include "dp/geometry/TriangleMesh.h"
#include "dp/track/FrameData.h"

#include <vector>

namespace dp
{

/** `x` (3 per vertex) with its lost part moved onto the frame's unexplained points (see the file
 *  comment); empty when there is no such part or too few such points to place it. */
std::vector<double> regrowLostPart(const FrameData& frame, const TriangleMesh& mesh,
                                   const std::vector<double>& x, double reach);

} // namespace dp
