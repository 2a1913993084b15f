// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file MeshSurfaceSamples.h
 * @brief A mesh frame read as a surface: points spread evenly over its area, with normals from
 *        its faces and colours from its vertices.
 *
 * Capture meshes (marching cubes, adaptive decimation) have uneven vertex density: their
 * vertices alone would leave the surface between sparse vertices without data (the distance
 * energy of the paper's eq. 1 then reads the distance to the nearest vertex, not to the
 * surface) and would make dense regions pull harder. The samples are spread by area instead:
 * triangles are visited in order and each receives its share of `count` by area (systematic
 * sampling, the fractions carried to the next triangle), placed inside it along a
 * low-discrepancy (R2) sequence. No random numbers: the same mesh gives the same samples.
 * Where the sequence starts (the first carried fraction and the first R2 index) is drawn from a
 * hash of the mesh's coordinates, so a mesh that moved gets samples at other places on its
 * triangles. That matters to tracking: a take of one connectivity sampled at the same places in
 * every frame leaves the same sampling error in every frame, which can add up instead of
 * averaging out. On `jumping` given as its true meshes (BenchmarkTracker --true-meshes,
 * decimated template), vertices end 16.1 mm RMS from their material points with a fixed start,
 * and 15.8 and 13.9 mm with two different starts drawn anew each frame.
 *
 * Normals are the area-weighted vertex normals interpolated across each triangle (smooth, and
 * exact where the faces are consistently oriented; a face's own normal where the vertex normal
 * cancels out). Colours are interpolated from the vertices' colours.
 *
 * Limits: triangles only (split polygons into fans first); triangles without area receive no
 * sample; a mesh with inconsistent orientation gives normals of both signs (the tracker
 * orients data normals against the mesh it tracks, as for points).
 */
#pragma once

#include "dp/io/PointCloud.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dp
{

/** A triangle mesh seen in place (arrays owned by the caller). */
struct MeshSurface
{
  const double* positions = nullptr; // x y z per vertex
  std::size_t vertices = 0;
  const std::int64_t* triangles = nullptr; // 3 vertex indices each
  std::size_t triangleCount = 0;
  const std::uint8_t* colours = nullptr; // colourComponents bytes per vertex, or null
  int colourComponents = 0;              // 3 (RGB) or 4 (RGBA; alpha dropped)
};

/** A point cloud's polygons split into triangle fans (3 indices each); none without polygons. */
std::vector<std::int64_t> triangleFans(const PointCloud& cloud);

/** `cloud` with `triangles` (its polygons as triangleFans gives them), seen as a MeshSurface;
 *  both must outlive the view. */
MeshSurface meshSurfaceOf(const PointCloud& cloud, const std::vector<std::int64_t>& triangles);

/** The surface's area (triangles without area count 0). Throws std::invalid_argument for an
 *  index out of range. */
double meshSurfaceArea(const MeshSurface& mesh);

/**
 * About `count` points spread evenly over the mesh's area (see the file comment), with unit
 * normals and, where the mesh has colours, r g b bytes (colorComponents 3). Fewer only when
 * the mesh has no area (then none). Throws std::invalid_argument for an index out of range or
 * colourComponents other than 0, 3 or 4.
 */
PointCloud sampleMeshSurface(const MeshSurface& mesh, std::size_t count);

} // namespace dp
