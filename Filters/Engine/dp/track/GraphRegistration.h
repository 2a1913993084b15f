// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file GraphRegistration.h
 * @brief The tracker's coarse level: moves the nodes of a deformation graph (DeformationGraph)
 *        so that the deformed template fits the frame's data, minimising
 *
 *   E(theta) = sum_terms E_term(x(theta)) + E_reg(theta),
 *   E_reg = k_reg / (L voxel |G|) * sum_{(j,k) in G} (h(|e_jk|) + h(|e_kj|)),
 *   e_jk  = R_j a_jk + g_j + t_j - (g_k + t_k)        (Sumner et al. 2007, E_reg)
 *
 * over each node's rotation and translation (6 unknowns a node; rotations stay rotations: steps
 * are angle-axis increments R <- exp([w]x) R).
 *
 * The regulariser: a_jk is the edge's reference in node j's frame, g_k - g_j in the template, so
 * bending is measured against the reference pose, not the last frame, and shapes do not drift;
 * E_reg is zero for any rigid motion of the whole graph. h is the Huber penalty of scale s
 * (e^2 / 2 below s, linear above: an L1 penalty on bending, minimised by iteratively
 * reweighted least squares), so the graph bends at a few places (joints) and stays rigid
 * elsewhere, the way bodies move. Least squares instead spreads bending over every edge and,
 * along the surface where the data say nothing, pulls the shape centimetres off the truth on
 * captured humans; a redescending penalty frees joints entirely and lets symmetric parts drift.
 * E_reg also holds a stretch term, k_s / 2 * sum_(j,k) s_jk^2 with s_jk the change of the
 * deformed edge's length |g_k + t_k - g_j - t_j| from |a_jk| beyond a free 10 %: least squares
 * at any size, so limbs bend (Huber) but do not stretch (a hoof passing by another limb's data
 * is not pulled along with it, horse-gallop with holes).
 * Plasticity (yield()): where frames keep an edge bent beyond a limit, its reference gives way
 * by a share of the excess, so lasting deformation (a collapse, clothes) is not pulled back,
 * while near-rigid parts keep the template's shape.
 *
 * The data terms are the fine level's own (DistanceTerm mesh -> points, CoverageTerm points ->
 * mesh) in vertex space; their Gauss-Newton models are carried to the nodes through the
 * blending, H_nodes = B^T H_vertices B with B = dx/dtheta (the points -> mesh term's model
 * replaced by its block-diagonal upper bound, so the nodes' system has the graph's sparsity).
 *
 * registerFrame() runs the schedule that gives the coarse level its capture range: three stages
 * from stiff and far-reaching (the data terms see points up to ~24 voxels away, robustly) to
 * supple and local, a few Levenberg-Marquardt steps each, correspondences re-decided every step
 * (the points -> mesh term's searched over the whole surface at each stage's start and, with
 * CoverageOptions::followMatches, followed over it from step to step within the stage).
 *
 * The steps converge linearly (the data's points slide along the surface a little each step).
 * With setAcceleration() (the tracker's default: three steps) they are Anderson-accelerated
 * (AndersonAcceleration) once a step moves no vertex farther than two voxels; an accelerated state
 * moves no vertex more than a voxel beyond the plain step (it is brought back toward it), one
 * whose energy is higher than where its step started gives way to the plain step and the history
 * is cleared, and a stage also ends once a step moves no vertex a tenth of a voxel.
 *
 * Limits: the normal equations are solved exactly by a sparse Cholesky factorisation of 6 x 6
 * blocks (6 x nodes unknowns); the schedule's reaches are in voxels of the distance field.
 */
#pragma once

#include "dp/support/BlockCholesky.h"
#include "dp/support/BlockSparseMatrix.h"
#include "dp/track/DeformationGraph.h"
#include "dp/track/EnergyTerm.h"

#include <array>
#include <memory>
#include <vector>

namespace dp
{

class AndersonAcceleration;
class CoverageTerm;
class DistanceTerm;

/** How stiff the coarse level is for one frame: `rigidity` scales the schedule's k_reg,
 *  `stretchWeight` is k_s (0: no stretch term). A value per call, so a stiffer retry leaves no
 *  state behind. */
struct GraphStiffness
{
  double rigidity = 1.0;
  double stretchWeight = 1.0;
};

class GraphRegistration
{
public:
  /** `lengthScale` L and `voxel` set E_reg's units (those of the data terms). */
  GraphRegistration(const DeformationGraph& graph, double lengthScale, double voxel);

  /** Levenberg-Marquardt on the nodes: at most `iterations` steps minimising the terms plus
   *  E_reg with weight `rigidity` (k_reg). Returns the steps taken. */
  int solve(DeformationGraph::State& state, const std::vector<EnergyTerm*>& terms, double rigidity,
            int iterations);

  /** The coarse schedule (see the file comment) on the frame's data terms; `coverage` may be
   *  null. `stiffness`: its rigidity scales the schedule's k_reg, its stretch weight is k_s for
   *  this frame (setStretchWeight); `robustScale` (world units) is E_reg's Huber
   *  scale (0: least squares). `extra` terms (whose models couple no vertices, e.g. ColourTerm)
   *  join every stage as they are. Returns the steps taken. */
  int registerFrame(DeformationGraph::State& state, DistanceTerm& distance, CoverageTerm* coverage,
                    GraphStiffness stiffness, double robustScale, int iterationsPerStage,
                    const std::vector<EnergyTerm*>& extra = {});

  /** The Gauss-Newton model of the terms (as they were last linearised) plus E_reg at a state:
   *  returns E and sets the node-space gradient (6 per node: rotation, translation); the matrix
   *  is kept for the solve. */
  double model(const DeformationGraph::State& state, const std::vector<EnergyTerm*>& terms,
               double rigidity, Eigen::VectorXd& gradient);

  /** Anderson acceleration of the steps, combining `depth` earlier steps (0: plain steps; see
   *  solve()). */
  void setAcceleration(int depth) { Acceleration = depth; }

  /** k_s, the stretch term's weight against the bending term's (0: no stretch term). */
  void setStretchWeight(double weight) { StretchWeight = weight; }

  /** E_reg measures bending against the template again (undoes yield()). */
  void resetReference();

  /** Lets E_reg's reference give way where `state` (a frame's result) bends an edge beyond
   *  `limit` (world units): by `rate` of the excess. */
  void yield(const DeformationGraph::State& state, double rate, double limit);

  /** E_reg of a state with weight `rigidity`; adds its Gauss-Newton model when asked (to a
   *  `hessian` of the graph's pattern: nodes, graph.edges()). */
  double regularisation(const DeformationGraph::State& state, double rigidity,
                        support::BlockSparseMatrixOf<6>* hessian = nullptr,
                        Eigen::VectorXd* gradient = nullptr) const;

  const DeformationGraph& graph() const { return Graph; }
  /** The node-space matrix model() last built (lower triangle of 6 x 6 blocks). */
  const support::BlockSparseMatrixOf<6>& nodeModel() const { return NodeModel; }

private:
  // The vertex model and gradient as the nodes' (NodeModel, `nodeGradient`): see project().
  void project(const DeformationGraph::State& state, const Eigen::VectorXd& vertexGradient,
               Eigen::VectorXd& nodeGradient);
  // Vertex v's arms r_aj to the nodes it blends and P_j = [r_aj]x M (its model block M), and its
  // gradient added to theirs, w_aj (r_aj x g_a, g_a).
  void projectGradient(const DeformationGraph::State& state, std::size_t v,
                       const Eigen::Matrix3d& M, const Eigen::VectorXd& vertexGradient,
                       std::vector<Eigen::Vector3d>& arms, std::vector<Eigen::Matrix3d>& products,
                       Eigen::VectorXd& nodeGradient) const;
  // Adds B_aj^T M B_ak over the pairs of nodes vertex v blends to NodeModel, at ProjectionSlots
  // from `slots` on.
  void projectModel(std::size_t v, const Eigen::Matrix3d& M,
                    const std::vector<Eigen::Vector3d>& arms,
                    const std::vector<Eigen::Matrix3d>& products, std::size_t slots);
  Eigen::Vector3d edgeResidual(const DeformationGraph::State& state, std::size_t index,
                               int direction) const;
  void reweightEdges(const DeformationGraph::State& state, double robustScale);
  // Deforms to `state` (into x), re-decides the terms' correspondences and E_reg's weights there
  // and builds the model: returns E at the state.
  double linearise(const DeformationGraph::State& state, const std::vector<EnergyTerm*>& terms,
                   double rigidity, std::vector<double>& x);
  // After a plain step that moved the mesh by `move` voxels (from `start` to `state`, its mesh
  // `plainMesh`): forgets the accelerator's history while steps are large; otherwise, when
  // `allowed`, replaces state by the accelerated one (towardAccelerated), the plain one kept in
  // `plain`. Returns whether it did.
  bool accelerate(AndersonAcceleration& anderson, double move, bool allowed,
                  const DeformationGraph::State& start, const DeformationGraph::State& origin,
                  const std::vector<double>& plainMesh, DeformationGraph::State& state,
                  DeformationGraph::State& plain) const;
  // The largest difference of two meshes' coordinates (world units).
  static double largestDifference(const std::vector<double>& a, const std::vector<double>& b);
  // The accelerator's `accelerated` coordinates as a state, brought back toward the plain step
  // (its coordinates `plain`, its mesh `plainMesh`) where they would move a vertex too far from it.
  DeformationGraph::State towardAccelerated(const Eigen::VectorXd& plain,
                                            Eigen::VectorXd accelerated,
                                            const DeformationGraph::State& origin,
                                            const std::vector<double>& plainMesh) const;
  // The state as coordinates for the accelerator, relative to `origin`: per node its rotation's
  // angle-axis from origin's times the mean arm (so in length units, like the translation), then
  // its translation; and back.
  Eigen::VectorXd coordinates(const DeformationGraph::State& state,
                              const DeformationGraph::State& origin) const;
  DeformationGraph::State fromCoordinates(const Eigen::VectorXd& u,
                                          const DeformationGraph::State& origin) const;
  // One Levenberg-Marquardt step on the model last built (energy E there): true if a step was
  // kept (state moved, decrease set, `trial` its mesh); the damping carries over between steps.
  bool dampedStep(DeformationGraph::State& state, const std::vector<EnergyTerm*>& terms,
                  double rigidity, double energy, double& damping, double& decrease,
                  std::vector<double>& trial);
  double stretching(const DeformationGraph::State& state, double weight,
                    support::BlockSparseMatrixOf<6>* hessian, Eigen::VectorXd* gradient) const;
  static DeformationGraph::State retract(const DeformationGraph::State& state,
                                         const Eigen::VectorXd& step);

  const DeformationGraph& Graph;
  double Scale; // 1 / (L voxel)
  double Voxel;
  double StretchWeight = 1.0;
  int Acceleration = 0;
  double MeanArm = 1;                        // of the template's edges (coordinates())
  double RobustScale = 0;                    // of E_reg's edges (world units; 0: least squares)
  std::vector<double> EdgeWeight;            // per directed edge (2 per edge), decided per step
  std::vector<Eigen::Vector3d> Arms;         // per directed edge (j, k): the reference of g_k - g_j
  support::BlockSparseMatrix VertexModel;    // data terms' model: block diagonal
  support::BlockSparseMatrixOf<6> NodeModel; // pattern: the graph's edges
  std::vector<support::BlockSparseMatrixOf<6>::Slot> ProjectionSlots; // see project()
  // Per directed edge (j, k) of E_reg: its blocks (j, j), (k, k), (j, k) in NodeModel, and in
  // any matrix of the same pattern (regularisation()'s `hessian`: slots follow the pattern).
  std::vector<std::array<support::BlockSparseMatrixOf<6>::Slot, 3>> EdgeSlots;
  Eigen::VectorXd NodeGradient;
  support::BlockCholeskyOf<6> Solver;
  bool Analysed = false;
};

} // namespace dp
