// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Tracker.h
 * @brief Deforms one template mesh through a sequence of point clouds, frame by frame, by
 *        minimising E = E_int + E_dis (Shinya, Shioya & Shiraishi, "Unification of Dynamic
 *        Point Data", eq. 1):
 *
 *   E_int  the cloth energy of ClothEnergy (stretch, shear, bend; rest state = the template);
 *   E_dis  = k_dis * sum_i m_i w_i P(D(x_i)) / L, with D the distance field of the frame's
 *          points (DistanceField), m_i the vertex masses, L = sqrt(template area) (so nothing
 *          depends on units), and w_i in {0, 1}: 0 when vertex i fails the normal test (its
 *          normal and its nearest point's normal differ by more than normalTestDegrees) or is
 *          farther than outlierDistance from the data. P(D) = D in the paper; by default
 *          D^2 / (2 voxel). D is by default the distance to the tangent planes of the nearest
 *          points (DistanceField::sampleToPlanes: the weighted RMS over the 8 voxel corners
 *          around x_i) rather than to the points themselves.
 *
 * Beyond the paper (each measured in BenchmarkTracker; the paper's choices stay as options):
 * the plane distance and the squared penalty remove the pull toward individual samples that
 * held vertices back along the surface; the rest state of E_int for frame t is
 * (1 - restUpdate) * template + restUpdate * frame t-1, since real sequences (horse-collapse)
 * stray so far from the template that the template's rest state pulls even the true shape
 * 2-4% of the diagonal away.
 *
 * Solvers on the same energy:
 *   SteepestDescent (the paper, eq. 2-3): x <- x - h grad E with h = 1.9 / k_max, k_max the
 *     largest eigenvalue of the Hessian estimated by power iteration (halved where a step
 *     would raise E); stops when ten iterations gain less than a tenth of the tolerance
 *     (relative). With provisional determination (PD), every 5 iterations a vertex whose net
 *     motion is under a quarter of the path it stepped (it jitters in place) is frozen, until a
 *     neighbour moves steadily (net motion over half its path).
 *   GaussNewton (default): Levenberg-Marquardt on the same E. Each cloth term 1/2 k r^2
 *     contributes k grad(r) grad(r)^T; each vertex's data term the Gauss-Newton quadric of
 *     its D^2 with the tangent planes held (DistanceField::sampleToPlanes; for the paper's D,
 *     reweighted by 1 / max(D, voxel), whose fixed point minimises the sum of distances). The
 *     matrix has a fixed sparsity pattern (the mesh's), assembled in place; each step is an
 *     inexact Newton step, conjugate gradients preconditioned by the factorised matrix of its
 *     3x3 blocks' traces (a third of the unknowns). A step is kept when E falls by at least a
 *     tenth of what the model promised; where one vertex's data term breaks that promise (it
 *     sits between two parts of the data), that vertex alone is damped. A frame ends when E's
 *     relative decrease falls under the tolerance or no vertex moves a tenth of a voxel; the
 *     normal test is then decided again at the new shape (twice at most).
 *   LBFGS: quasi-Newton (libLBFGS, More-Thuente line search) on the same E and gradient.
 * Motion prediction (MP): the start of frame t is the minimum of E along the constant, linear
 * and quadratic extrapolations of the trajectories (a 1-D search on each). Rigid alignment
 * (beyond the paper, default on): the predicted mesh is then moved rigidly onto the data
 * (point-to-plane ICP weighted by vertex mass, each step kept only if E_dis falls), since E_int
 * holds a rigid motion only weakly along the surface and a turning shape would otherwise slip.
 *
 * Defaults (k_st 1, k_sh 0, k_ben 0.5, k_dis 50, restUpdate 0.3) were chosen on horse-collapse
 * and horse-gallop with templates reconstructed from frame 0's points; k_sh = 0 assumes a
 * well-shaped template (slivers fold without shear terms; TriangleMesh::poorlyShapedShare).
 *
 * Missing data: an empty frame continues the motion (linear extrapolation of the last two
 * frames), relaxed by E_int alone, and is flagged; vertices with no data near them (holes) are
 * held by E_int. The paper's solver backs off (halves h) where a step would raise the energy.
 *
 * Limits: one global step of motion prediction per frame (not per vertex); the distance field
 * is rebuilt for every frame; the optimiser is local, so parts that move more than their own
 * width between frames (legs crossing at a gallop) can be captured by the wrong data; tangential
 * motion is held only by the prior, so where the true motion is not near-isometric the vertices
 * sit on the right surface at a biased place; time grows faster than linearly beyond ~2k vertices
 * (the factorisation of the preconditioner).
 */
#pragma once

#include "dp/ClothEnergy.h"
#include "dp/DistanceField.h"
#include "dp/TriangleMesh.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

namespace dp
{

/** What D_i of the distance energy measures. */
enum class DistanceMeasure
{
  Points, // the distance to the nearest data point (the paper)
  Planes  // the distance to the tangent planes of the nearest data points (DistanceField::
          // sampleToPlanes): no pull toward individual samples, so the mesh slides along the data
};

enum class TrackerSolver
{
  GaussNewton,
  LBFGS,
  SteepestDescent
};

struct TrackerOptions
{
  ClothParameters cloth;
  double distanceWeight = 50.0;    // k_dis
  double normalTestDegrees = 90.0; // >= 180 switches the normal test off
  double outlierDistance = 0.0;    // world units; 0: no cut-off
  DistanceMeasure distanceMeasure = DistanceMeasure::Planes;
  // true: each vertex's term is D_i^2 / (2 voxel) (smooth at the data, so vertices do not stick
  // where they first touch it); false: the paper's D_i.
  bool squaredDistance = true;
  double voxelSize = 0.0; // world units; 0: template diagonal / 200
  double bandWidth = 0.0; // world units; 0: 4 voxels
  TrackerSolver solver = TrackerSolver::GaussNewton;
  // Rest state of E_int for frame t: (1 - restUpdate) * template + restUpdate * frame t-1.
  // 0 is the paper (the template); a share of the last frame lets the rest state follow shapes
  // that stray far from the template (a collapse), so that E_int stops pulling them back.
  double restUpdate = 0.3;
  bool motionPrediction = true;
  // Before the deformable solve, move the predicted mesh rigidly onto the data (point-to-plane
  // ICP weighted by vertex mass): the cloth energy holds a rigid motion only weakly along the
  // surface, so without it a turning shape slips tangentially a little more each frame.
  bool rigidAlignment = true;
  bool provisionalDetermination = true; // steepest descent only
  int maxIterations = 300;
  double tolerance = 1e-3; // relative energy decrease that ends a solve
};

struct FrameResult
{
  std::vector<double> positions;      // 3 per vertex
  std::vector<double> residual;       // distance to the data per vertex (D), -1 if no data
  std::vector<std::uint8_t> frozen;   // PD: frozen at the end of the solve
  std::vector<std::uint8_t> rejected; // normal test or outlier cut-off dropped the data term
  int iterations = 0;
  double internalEnergy = 0;
  double distanceEnergy = 0;
  double seconds = 0;
  bool emptyFrame = false;
};

class Tracker
{
public:
  /** `templatePositions` is the rest state and the start of frame 0. Throws
   *  std::invalid_argument for a mesh without area or options out of range. */
  Tracker(TriangleMesh mesh, std::vector<double> templatePositions, const TrackerOptions& options);
  // The cloth energy refers to the tracker's own mesh: a tracker does not move.
  Tracker(const Tracker&) = delete;
  Tracker& operator=(const Tracker&) = delete;
  ~Tracker();

  /**
   * Fits the mesh to the next frame's points (x y z each; normals nx ny nz each or nullptr to
   * estimate them) and returns the result; the tracker remembers it for the next frame.
   */
  FrameResult track(const double* points, std::size_t count, const float* normals);

  /** Forgets the trajectory: the next track() starts from the template again. */
  void reset() { History.clear(); }

  /** Continues from `positions` as if it had been the last result (no motion history). */
  void restartFrom(const std::vector<double>& positions) { History = {positions}; }

  const TriangleMesh& mesh() const { return Mesh; }
  const std::vector<double>& templatePositions() const { return Template; }
  const TrackerOptions& options() const { return Options; }
  const ClothEnergy& clothEnergy() const { return Cloth; }
  double voxelSize() const { return Voxel; }

  /** E = E_int + E_dis at x against `field` with the given per-vertex data weights; adds the
   *  gradient when `gradient` is not null. Exposed for tests. */
  double energy(const double* x, const DistanceField* field, const std::vector<double>& weights,
                double* gradient, double* internal = nullptr, double* distance = nullptr) const;

private:
  std::vector<double> predict() const;
  void alignRigidly(std::vector<double>& x, const DistanceField& field,
                    const std::vector<double>& weights);
  double distanceEnergy(const double* x, const DistanceField* field,
                        const std::vector<double>& weights, double* gradient,
                        double* perVertex = nullptr) const;
  DistanceSample sampleData(const DistanceField& field, const double* x, std::size_t vertex) const;
  int solveGaussNewton(std::vector<double>& x, const DistanceField* field,
                       std::vector<double>& weights,
                       const std::function<std::size_t(const std::vector<double>&)>& decideWeights);

  TriangleMesh Mesh;
  std::vector<double> Template;
  TrackerOptions Options;
  ClothEnergy Cloth;
  ClothRestState TemplateRest;
  std::vector<float> FrameNormals; // the current frame's point normals (Planes, normal test)
  // Per vertex, the voxels last sampled in this frame's field (a cache: vertices move little
  // between evaluations). Makes energy() unsafe to call concurrently on one tracker.
  mutable std::vector<VoxelCell> Cells;
  double Voxel = 0;
  std::vector<std::vector<double>> History; // the last three results, most recent last
  struct NewtonState;
  std::unique_ptr<NewtonState> Newton; // made at the first Gauss-Newton solve
};

} // namespace dp
