// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DistanceField.h
 * @brief Unsigned distance field of a point cloud on a sparse OpenVDB grid, with the nearest
 *        point of every voxel: the D_i of the paper's distance energy E_dis = sum m_i D_i.
 *
 * Build: every point is offered to the 27 voxels around it; a front then propagates the index
 * of the nearest point voxel by voxel through the 26-neighbourhood (a vector distance
 * transform, in the spirit of the paper's vector-city transform), keeping the voxels whose
 * nearest point is within the band. Cost is linear in the number of active voxels (each is
 * touched a small, bounded number of times); no point-to-voxel brute force. Voxels store the
 * *index* of their nearest point, so distances are exact and the point's normal is at hand.
 * Before allocating, an upper bound on the band's voxel count (from band-wide blocks) is
 * checked against a limit, so absurd settings fail at once instead of exhausting memory.
 *
 * Sampling at any x (thread-safe, no locks): each of the 8 voxel centres around x names a
 * point p_c (its stored nearest point; for a voxel outside the band, the exact nearest point
 * from a kd-tree) and D(x) = sum_c w_c(x) |x - p_c| with trilinear weights w_c. So D is
 * continuous everywhere (across voxel faces and the band's edge), never below the true
 * distance, equal to it wherever the 8 voxels agree on their nearest point (away from the
 * data), and its gradient is D's analytic derivative: a unit vector away from the data far
 * out, so it pulls toward the data from any distance, never a silent zero.
 * (Measured alternatives: trilinear interpolation of stored distances overestimates as much
 * near the data and is not exact away from it; the distance to the closest of the 8 candidate
 * points is exact near dense data but jumps across voxel faces in sparse clouds.)
 *
 * Limits: near the data (within about a voxel) D overestimates the distance to the nearest
 * point by up to about a voxel (the tests bound it); pick the voxel size at the data's accuracy,
 * as the paper does. D is the distance to points, not to the sampled surface. The transform's
 * stored nearest point can be slightly farther than the true one (26-neighbour propagation;
 * the tests bound how far). At most 2^31 - 1 points.
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

namespace dp
{

struct DistanceFieldOptions
{
  double voxelSize = 0.0; // world units; must be positive
  double bandWidth = 0.0; // world units around the points kept in the grid; 0: 3 voxels
  std::size_t maxActiveVoxels = 200'000'000; // refuse grids larger than this (memory guard)
};

struct DistanceSample
{
  double distance = 0.0;
  double gradient[3] = {0.0, 0.0, 0.0};
  std::int64_t nearest = -1; // index of the nearest point
  bool inBand = false;       // all 8 surrounding voxels were in the band (else: kd-tree)
};

/** Thrown when the requested grid would exceed DistanceFieldOptions::maxActiveVoxels. */
class GridTooLarge : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
};

class DistanceField
{
public:
  DistanceField();
  ~DistanceField();
  DistanceField(DistanceField&&) noexcept;
  DistanceField& operator=(DistanceField&&) noexcept;

  /**
   * Builds the field of `count` points (x y z each). Throws std::invalid_argument for no
   * points, non-finite coordinates (naming the first), a voxel size or band that is not a
   * positive finite number, and GridTooLarge when the estimated grid exceeds the limit.
   */
  void build(const double* points, std::size_t count, const DistanceFieldOptions& options);

  bool empty() const;
  double voxelSize() const;
  double bandWidth() const;
  std::size_t numberOfPoints() const;
  const double* points() const;
  std::size_t activeVoxelCount() const;
  /** Bytes held by the grid and the kd-tree (approximate). */
  std::size_t memoryBytes() const;

  /** Distance, gradient and nearest point at x. Thread-safe. */
  DistanceSample sample(const double x[3]) const;
  /** sample() for many positions (x y z each), in parallel. */
  void sampleMany(const double* positions, std::size_t count, DistanceSample* out) const;

  /** The exact nearest point to x by kd-tree search, and its squared distance. Thread-safe. */
  std::int64_t nearestPoint(const double x[3], double* squaredDistance = nullptr) const;

  /** The point index stored in voxel (i,j,k) (centre at (i,j,k)*voxelSize); -1 outside the band. */
  std::int64_t voxelNearest(int i, int j, int k) const;

private:
  struct Impl;
  std::unique_ptr<Impl> P;
};

/**
 * Unit normals of a point cloud by PCA over each point's `neighbours` nearest points, oriented
 * consistently: orientation spreads along a minimum spanning tree of the neighbour graph
 * (Hoppe et al. 1992) from, in each connected part, the point of largest x, whose normal is
 * made to point to +x (outward on a closed surface). Returns nx ny nz per point.
 */
std::vector<float> estimateNormals(const double* points, std::size_t count,
                                   std::size_t neighbours = 16);

} // namespace dp
