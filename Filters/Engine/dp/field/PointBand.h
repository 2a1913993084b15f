// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file PointBand.h
 * @brief The sparse band the field's grids start from (DistanceField's nearest-point grid,
 *        SurfaceReconstruction's distance grid): the voxels holding a point, an upper bound on
 *        the voxels the band will hold (checked before anything proportional to it is
 *        allocated), and the dilation over the band.
 *
 * Internal to dp/field: it includes OpenVDB, which the field concern keeps private. Voxel
 * (i, j, k) is centred at (i, j, k) * voxel: the grids keep OpenVDB's identity transform, which
 * refuses scales whose cube is below 1e-8 (a 2 mm voxel).
 */
#pragma once

#include <openvdb/openvdb.h>
#include <openvdb/tools/Morphology.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

namespace dp::support
{

/** The voxel whose centre is nearest to point `p`. */
inline openvdb::Coord voxelOf(const double* p, double voxel)
{
  return openvdb::Coord(static_cast<int>(std::floor(p[0] / voxel + 0.5)),
                        static_cast<int>(std::floor(p[1] / voxel + 0.5)),
                        static_cast<int>(std::floor(p[2] / voxel + 0.5)));
}

/** Switches on, with `value`, the voxel of each of `count` points (x, y, z interleaved). */
template <typename TreeT>
void seedPointVoxels(TreeT& tree, const double* points, std::size_t count, double voxel,
                     typename TreeT::ValueType value)
{
  openvdb::tree::ValueAccessor<TreeT> access(tree);
  for (std::size_t i = 0; i < count; ++i)
    access.setValueOn(voxelOf(points + 3 * i, voxel), value);
}

/** An upper bound on the voxels within `reach` voxels (Chebyshev) of the seeds: all lie in the
 *  blocks of `reach` voxels a side that touch (26-neighbourhood) a block holding a seed. Costs
 *  O(seeds log seeds) and allocates nothing proportional to the band. */
template <typename TreeT>
double bandVoxelBound(const TreeT& seeds, int reach)
{
  const int side = std::max(reach, 1);
  const auto block = [side](int c) { return c >= 0 ? c / side : -((-c + side - 1) / side); };
  std::vector<std::array<int, 3>> blocks;
  for (auto it = seeds.cbeginValueOn(); it; ++it)
  {
    const openvdb::Coord c = it.getCoord();
    blocks.push_back({block(c.x()), block(c.y()), block(c.z())});
  }
  std::sort(blocks.begin(), blocks.end());
  blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
  if (reach == 0)
    return static_cast<double>(blocks.size());
  std::vector<std::array<int, 3>> touched;
  touched.reserve(blocks.size() * 27);
  for (const auto& b : blocks)
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j)
        for (int k = -1; k <= 1; ++k)
          touched.push_back({b[0] + i, b[1] + j, b[2] + k});
  std::sort(touched.begin(), touched.end());
  const auto unique = std::unique(touched.begin(), touched.end()) - touched.begin();
  return static_cast<double>(unique) * std::pow(static_cast<double>(side), 3);
}

/** Activates every voxel within `reach` voxels (Chebyshev) of an active one. */
template <typename TreeT>
void dilateBand(TreeT& tree, int reach)
{
  if (reach > 0)
    openvdb::tools::dilateActiveValues(tree, reach, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                       openvdb::tools::IGNORE_TILES);
}

} // namespace dp::support
