// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FrameOrientation.h
 * @brief Orients a frame's normals by the tracked shape. Normals estimated from points are
 *        consistent within each separate part of the data (FrameData's orientation tree) but
 *        perhaps inward; the last tracked shape says which way each part faces.
 *
 * Beyond the paper (whose data had given normals). Each point of the frame's well-spread
 * subsample votes where the shape's surface is within 3 voxels (agree: the surface's normal and
 * the point's point the same way); a part most of whose votes disagree is flipped (all the
 * points, for normals given). Then, within each part, a branch of the orientation tree turned at
 * a sharp edge (a foot's rim) is mended by the sure votes: surface within 2 voxels, at most 45
 * degrees from parallel either way (FrameData::mendOrientation).
 *
 * Limits: a part the shape does not reach (new data far from the mesh) keeps its orientation.
 */
#pragma once

#include <vector>

namespace dp
{

class FrameData;
class TriangleMesh;

/** Orients `frame`'s normals by the shape `x` (3 per vertex of `mesh`); `voxel` in world units. */
void orientToShape(FrameData& frame, const TriangleMesh& mesh, const std::vector<double>& x,
                   double voxel);

} // namespace dp
