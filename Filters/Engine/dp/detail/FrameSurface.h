// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FrameSurface.h
 * @brief A frame's data as the detail layer reads it: where a line from a fine vertex along its
 *        normal meets the captured surface.
 *
 * Two kinds of frame. A mesh (a capture's per-frame mesh) is read exactly: from the query point
 * the closest point of its triangles (SurfaceLocator), then along the line to that triangle's
 * plane, repeated from the new point until the step is under a thousandth of the reach (two or
 * three steps on a curved surface; one on a plane). Points (a scan, 3D video) are read as a
 * local surface: the nearest points' tangent planes, each met by the line and averaged with a
 * weight that falls with the point's distance from the line (a Gaussian of width `radius`, about
 * the fine mesh's edge length), so the noise of single points averages out.
 *
 * A crossing is refused (no data there) when the surface met faces away from the line's
 * direction by more than the normal test's angle (the other side of a thin part, a limb touching
 * the body: oriented data only), or lies farther than `reach` along the line (a hole's far side,
 * a stray part). Points whose normals are estimated have no trustworthy orientation: there the
 * test reads the angle between the lines, not their directions.
 *
 * Limits: a mesh frame's orientation is taken from the majority of its faces as seen from the
 * tracked mesh (orientAgainst), one sign for the whole frame; triangles that repeat a vertex are
 * left out. Queries are const and thread-safe.
 */
#pragma once

#include "dp/geometry/MeshSurfaceSamples.h"

#include <cstddef>
#include <memory>

namespace dp
{

class FrameSurface
{
public:
  /** What a line met: the signed distance along it, and the data's weight there (1 for a mesh;
   *  for points, up to 1 as more points lie near the line). */
  struct Crossing
  {
    bool found = false;
    double distance = 0;
    double weight = 0;
  };

  /** A mesh frame (copied: `mesh` need not outlive it). Throws std::invalid_argument for an
   *  index out of range, a coordinate that is not finite, or no triangle with three corners. */
  static FrameSurface ofMesh(const MeshSurface& mesh);
  /** Points with unit normals (nx ny nz each, pointing out of the surface) or null (estimated
   *  by local PCA, unoriented: the normal test then reads the lines); copied. Throws
   * std::invalid_argument for no points or a coordinate that is not finite (naming the point). */
  static FrameSurface ofPoints(const double* points, std::size_t count, const float* normals);

  FrameSurface(FrameSurface&&) noexcept;
  FrameSurface& operator=(FrameSurface&&) noexcept;
  ~FrameSurface();

  /** Data points (a mesh's vertices). */
  std::size_t size() const;

  /**
   * Turns the data's orientation to agree with a mesh's (positions, unit normals, `count`
   * vertices) when most of the data it sees within `reach` faces the other way: a capture
   * whose triangles wind inward. Returns whether it turned.
   */
  bool orientAgainst(const double* positions, const double* normals, std::size_t count,
                     double reach);

  /** Where the line p + s n (n a unit vector) meets the data within |s| <= reach, with the
   *  normal test of `minimumCosine` (the cosine of its angle) and, for points, the Gaussian
   *  width `radius` (see the file comment). */
  Crossing cross(const double p[3], const double n[3], double reach, double minimumCosine,
                 double radius) const;

private:
  struct Data;
  explicit FrameSurface(std::unique_ptr<Data> data);
  std::unique_ptr<Data> D;
};

} // namespace dp
