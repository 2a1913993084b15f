// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file SurfaceReconstruction.h
 * @brief A triangle mesh from an oriented point cloud: the paper's first step ("polygonize the
 *        first frame's points and simplify to a working resolution") when the user has no
 *        template and the first frame has no polygons.
 *
 * Method: a narrow band of voxels around the points (OpenVDB) holds the signed distance to the
 * points' tangent planes (Hoppe et al. 1992), averaged over each voxel's k nearest points with
 * Gaussian weights so that noise is smoothed; OpenVDB's volumeToMesh meshes its zero crossing
 * (quads, split along their shorter diagonal). Crossings that lie farther than the band's half
 * from the points (where the band ends inside the shape) are dropped, and so are all but the
 * largest connected piece. The voxel size is chosen for the wanted vertex count: a first mesh at
 * a guess, then the size rescaled by sqrt(vertices / wanted) (a surface's vertex count goes as
 * 1 / voxel^2), at most a few times, until the count is within 25% of the wish.
 *
 * Limits: the normals must be consistently oriented (estimateNormals orients them; a scanner's
 * face its position); parts thinner than about two voxels merge or vanish; where the data have
 * holes wider than the band, the mesh has holes too (the tracker handles open meshes). The
 * vertex count is approximate.
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dp
{

struct ReconstructionOptions
{
  std::size_t targetVertices = 1000;        // wanted vertex count (approximate)
  std::size_t neighbours = 8;               // points whose planes each voxel averages
  std::size_t maxActiveVoxels = 50'000'000; // refuse larger grids (memory guard)
};

struct ReconstructedMesh
{
  std::vector<double> positions;       // x y z per vertex
  std::vector<std::int64_t> triangles; // 3 vertex indices each, consistently oriented
  double voxelSize = 0;                // the voxel size the mesh was made at
};

/**
 * Reconstructs a surface from `count` points (x y z each) with unit normals (nx ny nz each;
 * estimateNormals gives them). Throws std::invalid_argument for fewer than 16 points,
 * non-finite coordinates or normals, or a target under 20 vertices, and std::runtime_error
 * when no surface comes out (points too sparse or too flat for any voxel size tried).
 */
ReconstructedMesh reconstructSurface(const double* points, const float* normals, std::size_t count,
                                     const ReconstructionOptions& options = {});

} // namespace dp
