// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DistanceImage.h
 * @brief The unsigned distance from every voxel of a dense image to a point cloud, with each
 *        voxel's nearest point: the field D of the paper's distance energy on the paper's own
 *        kind of grid (a dense box of voxels filled by a distance transform, Shinya et al. §3),
 *        as vtkDistanceFieldFilter returns it. The tracker uses the sparse, lazily filled
 *        DistanceField instead: it only needs the voxels the mesh touches.
 *
 * Two steps, each linear in its input:
 * 1. The exact band. The points are sorted into the image's rows (a counting sort); each slice of
 *    voxels then reads the rows whose points can reach it, and every such point offers itself to
 *    the slice's voxels within `bandWidth` of it, walking each row outward from its own column; a
 *    voxel keeps the nearest offer (ties to the lower point index). One task writes each slice,
 *    so the result is the same in any input order and on any number of threads. A voxel whose
 *    nearest point lies within the band gets that point exactly.
 * 2. Beyond the band, a vector distance transform: the exact Euclidean distance transform of the
 *    seed voxels (those holding a point) by separable lower envelopes of parabolas (Felzenszwalb &
 *    Huttenlocher, "Distance Transforms of Sampled Functions", 2012: one pass per axis, the
 *    image's lines in parallel) gives each voxel its nearest seed, and the voxel takes that
 *    seed's nearest point (its band point in the band); a last pass lets each voxel beyond the
 *    band take the point a face neighbour knows of when nearer.
 * The distance is to a real input point, so it is never below the true distance, and above it by a
 * fraction of a voxel (RMS about 0.1 voxel).
 *
 * Limits: the band is at least half a voxel diagonal (seeds must be exact). Points outside the
 * image are found beyond the band by a kd-tree (slower: one query per such voxel). Up to
 * 2^32 - 1 points and 2^31 - 1 voxels; the caller bounds the voxel count (memory: 9 bytes per
 * voxel in the result, 12 more with the gradient, and 4 more while computing, as the result's own
 * arrays hold the band and the transform until the last pass; plus about 56 per point). Distances
 * and gradients are in single precision.
 */
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace dp
{

/** A dense axis-aligned image: voxel (i, j, k) is at origin + (i, j, k) * spacing, x fastest. */
struct ImageGrid
{
  std::array<int, 3> dimensions{1, 1, 1};
  std::array<double, 3> origin{0, 0, 0};
  std::array<double, 3> spacing{1, 1, 1};

  std::size_t voxelCount() const
  {
    return static_cast<std::size_t>(dimensions[0]) * static_cast<std::size_t>(dimensions[1]) *
           static_cast<std::size_t>(dimensions[2]);
  }
};

/** A distance image's arrays, in storage its caller owns (e.g. VTK arrays, so that nothing is
 *  copied): `voxels` entries each. */
struct DistanceImageView
{
  std::size_t voxels = 0;
  float* distance = nullptr;        // per voxel, to `nearest`
  std::uint32_t* nearest = nullptr; // per voxel: index of its nearest point
  std::uint8_t* exact = nullptr;    // per voxel: 1 within the band (the distance is exact)
  // Optional (null: not computed): 3 per voxel, the distance's gradient, the unit vector away from
  // the nearest point (zero on a point).
  float* gradient = nullptr;
};

/** What computeDistanceImage reports besides the arrays. */
struct DistanceImageBand
{
  double bandWidth = 0;       // the band used (at least half a voxel diagonal)
  std::size_t bandVoxels = 0; // voxels with exact = 1
};

/** A distance image in its own storage. */
struct DistanceImage : DistanceImageBand
{
  std::vector<float> distance;
  std::vector<std::uint32_t> nearest;
  std::vector<std::uint8_t> exact;

  DistanceImageView view()
  {
    return {distance.size(), distance.data(), nearest.data(), exact.data()};
  }
};

/**
 * The distance image of `count` points (x y z each) on `grid`, exact within `bandWidth` of the
 * points. Throws std::invalid_argument naming the problem for no points, a non-finite
 * coordinate, a dimension below 1, a spacing not positive, or a negative or non-finite band.
 */
DistanceImage computeDistanceImage(const double* points, std::size_t count, const ImageGrid& grid,
                                   double bandWidth);
/** The same into `out`, whose arrays hold grid.voxelCount() entries (checked). */
DistanceImageBand computeDistanceImage(const double* points, std::size_t count,
                                       const ImageGrid& grid, double bandWidth,
                                       const DistanceImageView& out);

/** Per voxel, the `components` values its nearest point has in `perPoint` (e.g. normals). */
void gatherNearest(const DistanceImageView& image, const float* perPoint, int components,
                   float* out);
/** Per voxel, its nearest point's entry in `perPoint` (e.g. ids). */
void gatherNearest(const DistanceImageView& image, const long long* perPoint, long long* out);

} // namespace dp
