// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DistanceTerm.h
 * @brief The paper's distance energy (eq. 1), mesh -> points: each vertex is pulled onto the
 *        frame's data through the distance field D,
 *
 *   E_dis = k_dis / L * sum_i m_i w_i P(D_i(x_i)),   P(D) = D^2 / (2 voxel) (default) or D,
 *
 * with m_i the vertex masses (area shares, summing to 1), L = sqrt(template area), and w_i the
 * data weight of vertex i: 0 when it fails the normal test (its normal and its nearest point's
 * normal differ by more than normalTestDegrees), lies beyond outlierDistance, its nearest point
 * is stray (FrameData::isStray: a flying pixel, a stray return), or, with `reciprocal`, another
 * part of the mesh is nearer to that point by more than two voxels (the point is that part's
 * data: a body seen from one side, whose unseen side's nearest points are the seen side's
 * rims; a hole, whose vertices' nearest points are its rim's), else 1 or, with
 * a robust scale s, the Geman-McClure weight 1 / (1 + (D/s)^2)^2 decided at the last
 * linearisation (iteratively reweighted least squares: far vertices, in holes or on another
 * part of the data, pull little). D is the distance to the tangent planes of the nearest points
 * (DistanceField::sampleToPlanes; default) or to the points themselves (the paper).
 *
 * Gauss-Newton model: per vertex, the quadric of D^2 with its tangent planes held (for the
 * paper's D, reweighted by 1 / max(D, voxel)); no coupling between vertices. The model of the
 * last addModel() is kept for the solver's per-vertex damping (which vertices broke its promise).
 *
 * Limits: the gradient of D is continuous inside a voxel cell, not across cell faces (the field
 * is trilinear); the normal test needs oriented normals.
 */
#pragma once

#include "dp/geometry/SurfaceLocator.h"
#include "dp/track/EnergyTerm.h"
#include "dp/track/FrameData.h"

#include "dp/geometry/TriangleMesh.h"
#include "dp/track/TrackerOptions.h"

#include <cstdint>
#include <vector>

namespace dp
{

class DistanceTerm : public EnergyTerm
{
public:
  /** `mass` per vertex; `lengthScale` L; `voxel` the field's voxel size. The frame, mesh and
   *  masses must outlive the term. Without data (an empty frame) the term is zero. */
  DistanceTerm(const FrameData& frame, const TriangleMesh& mesh, const std::vector<double>& mass,
               double lengthScale, const DistanceTermOptions& options);

  const char* name() const override { return "distance"; }
  double evaluate(const double* x, double* gradient) const override;
  double addModel(const double* x, support::BlockSparseMatrix& hessian,
                  double* gradient) const override;
  /** Normal test, outlier cut-off and robust weights at x; returns how many vertices changed
   *  side (kept or rejected). */
  std::size_t decide(const double* x) override;

  /** The field's distance, gradient and nearest point for vertex v at position p. */
  DistanceSample sample(const double* p, std::size_t v) const;
  /** Each vertex's share of the term at x (0 where rejected). */
  void vertexValues(const double* x, double* values) const;
  /** The last model's promise for vertex v's share after moving it by d. */
  double promised(std::size_t v, const double d[3]) const;
  /** The last model's stiffness of vertex v (0: no data term) and its quadric of D^2. */
  double stiffness(std::size_t v) const { return Stiffness[v]; }
  const PlaneQuadric& quadric(std::size_t v) const { return Quadric[v]; }

  /** Per vertex: the data weight (0: rejected by the normal test or the cut-off). */
  const std::vector<double>& weights() const { return Weights; }
  bool active() const { return !Frame.empty(); }
  const DistanceTermOptions& options() const { return Options; }
  void setRobustScale(double scale) { Options.robustScale = scale; }

private:
  double penalty(double distance) const;

  const FrameData& Frame;
  const TriangleMesh& Mesh;
  const std::vector<double>& Mass;
  DistanceTermOptions Options;
  double Scale = 0; // k_dis / L
  double Voxel = 0;
  std::vector<double> Weights;
  // Per vertex, the voxels last sampled (vertices move little between evaluations): one entry
  // per vertex, so sampling different vertices on different threads is safe.
  mutable std::vector<VoxelCell> Cells;
  mutable std::vector<PlaneQuadric> Quadric; // the last model, per vertex
  mutable std::vector<double> Stiffness;     // ... and its weight c_v
  // The mesh's surface for the reciprocal test: built at the first decision, refitted after
  // (the term lives for one frame, whose steps move the mesh little).
  SurfaceLocator Surface;
  bool SurfaceBuilt = false;
};

} // namespace dp
