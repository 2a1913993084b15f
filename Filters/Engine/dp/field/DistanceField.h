// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DistanceField.h
 * @brief Unsigned distance field of a point cloud on a sparse OpenVDB grid, with the nearest
 *        point of every voxel: the D_i of the paper's distance energy E_dis = sum m_i D_i.
 *
 * Build, linear in the active voxels: the voxels holding a point are activated and dilated
 * (OpenVDB morphology, 26-neighbourhood) to cover the band; then every active voxel gets the
 * index of the exact nearest point of its centre from a kd-tree (in parallel over the grid's
 * leaf nodes), and voxels farther than the band are dropped. Voxels store the *index* of their
 * nearest point (the paper's vector distance transform stores the vector), so the distance at
 * every voxel centre is exact and the nearest point's normal is at hand. Before allocating, an
 * upper bound on the voxel count is checked against a limit, so absurd settings fail at once.
 *
 * Sampling at any x (thread-safe, no locks) interpolates, as the paper does: D(x) is the
 * trilinear interpolation of the exact distances at the 8 voxel centres around x, and the
 * gradient is D's analytic derivative. Voxel centres outside the band take their exact value
 * from the kd-tree, so D is continuous everywhere (across voxel faces and the band's edge),
 * defined everywhere, and pulls toward the data from any distance: never a silent zero.
 * `nearest` is the closest to x of the 8 centres' nearest points.
 *
 * Limits: interpolation overestimates the distance right at the data (by up to about half a
 * voxel at a sample point): choose the voxel size at the data's accuracy, as the paper does.
 * D is the distance to the points, not to the sampled surface (sampleToPlanes approximates
 * the latter from the points' normals); its gradient is continuous
 * inside a cell, not across cell faces. Sampling outside the band costs up to 8 kd-tree
 * queries. At most 2^31 - 1 points.
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
  // Lazy: build only the kd-tree and fill voxels on first use (thread-safe, in blocks of 8^3
  // voxels made where first needed): the same values as the eager grid, at a cost proportional
  // to the voxels actually sampled (the tracker touches a few thousand, not the whole band).
  bool lazy = false;
};

struct DistanceSample
{
  double distance = 0.0;
  double gradient[3] = {0.0, 0.0, 0.0};
  std::int64_t nearest = -1; // index of the nearest point
  bool inBand = false;       // all 8 surrounding voxels were in the band (else: kd-tree)
};

/** The 8 voxels around a position, remembered between samples of the same moving vertex:
 *  while it stays in the same cell, sampling skips the voxel lookups. One per caller thread. */
struct VoxelCell
{
  int base[3] = {0, 0, 0};
  std::int32_t nearest[8] = {-1, -1, -1, -1, -1, -1, -1, -1};
  bool inBand = false;
  bool valid = false;
};

/** D^2 near a point x of sampleToPlanes, as a function of a displacement d:
 *  D^2(x + d) ~= constant + 2 vector.d + d^T matrix d (matrix symmetric, stored xx xy xz yy yz zz),
 *  with D^2's value at d = 0, and the linear and quadratic parts of its terms with the
 *  interpolation weights held (the Gauss-Newton model with the corners' correspondences fixed;
 *  it leaves out the voxel-scale ripple the weights' own slopes add to the gradient). */
struct PlaneQuadric
{
  double matrix[6] = {0, 0, 0, 0, 0, 0};
  double vector[3] = {0, 0, 0};
  double constant = 0;

  /** The model at displacement d. */
  double operator()(const double d[3]) const
  {
    return constant + 2 * (vector[0] * d[0] + vector[1] * d[1] + vector[2] * d[2]) +
           matrix[0] * d[0] * d[0] + matrix[3] * d[1] * d[1] + matrix[5] * d[2] * d[2] +
           2 * (matrix[1] * d[0] * d[1] + matrix[2] * d[0] * d[2] + matrix[4] * d[1] * d[2]);
  }
};

/** Thrown when the requested grid would exceed DistanceFieldOptions::maxActiveVoxels. */
class GridTooLarge : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
};

/** Throws std::invalid_argument naming the first point with a NaN or infinite coordinate (the
 *  field's own check, for callers that must not read such points before building it). */
void requireFinitePoints(const double* points, std::size_t count);

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
  /** Bytes held by the grid (lazy mode: the voxels filled so far) and the kd-tree
   *  (approximate). */
  std::size_t memoryBytes() const;

  /** Distance, gradient and nearest point at x. Thread-safe (with a `cell` per thread). */
  DistanceSample sample(const double x[3], VoxelCell* cell = nullptr) const;
  /**
   * Distance to the surface the points sample rather than to the points themselves: D is the
   * root mean square, with the trilinear weights, of the distances from x to the tangent planes
   * at the 8 surrounding voxel centres' nearest points (unit normals from `normals`, 3 per
   * point, orientation irrelevant); beyond `reach` from a corner's point, the distance past
   * `reach` is added in quadrature, so far from the data D still grows like the distance to the
   * points. Along the surface D stays near zero (no dimples at the samples, so a mesh can slide
   * along the data); D^2 is smooth within a voxel cell and continuous everywhere, and
   * `quadric`, when given, receives its Gauss-Newton model around x. Thread-safe.
   */
  DistanceSample sampleToPlanes(const double x[3], const float* normals, double reach,
                                VoxelCell* cell = nullptr, PlaneQuadric* quadric = nullptr) const;
  /** sample() for many positions (x y z each), in parallel. */
  void sampleMany(const double* positions, std::size_t count, DistanceSample* out) const;

  /** The exact nearest point to x by kd-tree search, and its squared distance. Thread-safe. */
  std::int64_t nearestPoint(const double x[3], double* squaredDistance = nullptr) const;
  /** The k nearest points to x, nearest first, with their squared distances; returns how many
   *  (fewer than k when there are fewer points). Thread-safe. */
  std::size_t nearestPoints(const double x[3], std::size_t k, std::uint32_t* indices,
                            double* squaredDistances) const;

  /** The point index stored in voxel (i,j,k) (centre at (i,j,k)*voxelSize); -1 outside the band. */
  std::int64_t voxelNearest(int i, int j, int k) const;

private:
  // The cell around x (from `cell` when x is still in it) and x's position in it (0..1 each).
  const VoxelCell& locate(const double x[3], VoxelCell* cell, double t[3]) const;
  // Sum over the 8 corners c of x's cell of w_c(x) v_c(x), with the gradient: cornerValue(
  // centre, nearest index, nearest point, weight w_c, out: grad v_c) returns v_c; the nearest
  // of the corners' points to x.
  template <typename CornerValue>
  DistanceSample interpolate(const double x[3], VoxelCell* cell, CornerValue cornerValue) const;

  struct Impl;
  std::unique_ptr<Impl> P;
};

} // namespace dp
