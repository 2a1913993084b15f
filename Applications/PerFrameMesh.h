// SPDX-License-Identifier: BSD-3-Clause
// dynamicpoints-sample --per-frame-mesh: a frame's samples turned into a mesh of its own
// connectivity, as a volumetric-video studio publishes them (a surface reconstructed from the
// points, each vertex coloured by the nearest sample), with --mesh-defects what marching cubes
// and exporters leave in it.
#pragma once

#include "dp/io/PointCloud.h"

#include <cstddef>

namespace dp::cli
{

/** The mesh of about `vertices` vertices reconstructed from `samples` (their normals, or
 *  estimated ones), with the samples' colours carried to the nearest vertex and vertex normals
 *  when the samples had normals. Every piece of at least 1 % of the largest's size is kept (a
 *  part cut off by a hole in the data, a tail, stays, as marching cubes keep it). With `defects`:
 * duplicate vertices (5 vertices split off, one triangle each using the copy), triangles without
 * area (two with a repeated corner, one with collinear corners) and a small stray part (a
 * tetrahedron of 1 % of the diagonal beside the surface). */
PointCloud perFrameMesh(const PointCloud& samples, std::size_t vertices, bool defects);

} // namespace dp::cli
