// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file SignedField.h
 * @brief SurfaceReconstruction's first stage: the signed distance to the points' tangent planes
 *        in a band of fine voxels around them, across the holes in the data and outside the band
 *        (OutsideBand.h), and its zero crossing as triangles (the fine surface).
 *
 * Internal to dp/field: its implementation uses OpenVDB, which the field concern keeps private.
 */
#pragma once

#include "dp/field/SurfaceReconstruction.h"
#include "dp/geometry/IsotropicRemesher.h"
#include "dp/support/KdTree.h"

#include <cstddef>

namespace dp::support
{

/** The fine surface: the zero crossing of the field, the reference of the remeshing. */
using FineMesh = IndexedMesh;

/** Half-width of the band around the points, in voxels. */
constexpr double NarrowBand = 3.0;

/** The oriented points the field is made of, and their kd-tree. */
struct FieldInput
{
  const double* points;
  const float* normals;
  std::size_t count;
  const KdTree& tree;
  double spacing; // median distance from a point to its nearest neighbour
};

/**
 * The zero crossing of the band-limited signed field at voxel size h, as triangles. The band:
 * every voxel within NarrowBand voxels of a point (the plane distance, averaged over each voxel's
 * `k` nearest points), plus the voxels of holes (interpolated; gaps up to about twice `reach`).
 * Outside the band, each piece of space takes the sign of most of its border (OutsideBand), so
 * no crossing appears where the band ends; points whose normals most of their piece's border
 * contradicts are flipped first. `open` tells whether some piece's border has both signs in large
 * parts (open data: the crossings at the band's end there are to be dropped). Throws
 * std::runtime_error when the grid would exceed options.maxActiveVoxels.
 */
FineMesh meshField(const FieldInput& in, double h, double reach, std::size_t k,
                   const ReconstructionOptions& options, bool& open);

} // namespace dp::support
