// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file NormalEstimation.h
 * @brief Normals for point clouds that come without them (scans, most 3D video): local PCA,
 *        then one orientation spread over the cloud.
 *
 * Limits: orientation is a guess per connected part (see estimateNormals); parts thinner than
 * the neighbourhood (a hand on the body) can still be oriented inward, which the tracker's
 * FrameData corrects part by part against the mesh.
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dp
{

/**
 * Unit normals of a point cloud by PCA over each point's `neighbours` nearest points, oriented
 * consistently: orientation spreads along a minimum spanning tree of the neighbour graph
 * (Hoppe et al. 1992) from, in each connected part, the point of largest x, whose normal is
 * made to point to +x (outward on a closed surface). Returns nx ny nz per point; `parts`, when
 * given, receives each point's part (0, 1, ... in the order the parts were seeded), since the
 * +x rule can orient a small part (a patch cut off by a hole) inward while the rest is right.
 */
std::vector<float> estimateNormals(const double* points, std::size_t count,
                                   std::size_t neighbours = 16,
                                   std::vector<std::uint32_t>* parts = nullptr);

} // namespace dp
