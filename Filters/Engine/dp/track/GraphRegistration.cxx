// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/GraphRegistration.h"

#include "dp/track/RobustKernel.h"

#include "dp/track/AndersonAcceleration.h"
#include "dp/track/CoverageTerm.h"
#include "dp/track/DistanceTerm.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace dp
{
namespace
{
using Matrix66 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;

// [v]x, the cross-product matrix: [v]x u = v x u.
Eigen::Matrix3d crossMatrix(const Eigen::Vector3d& v)
{
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// The coarse schedule: regularisation weight (times the caller's rigidity) and the reach of the
// data terms in voxels (robust scale = reach / 3, points farther than the reach do not pull).
struct Stage
{
  double rigidity;
  double reach;
};
constexpr Stage Schedule[] = {{10.0, 24.0}, {3.0, 12.0}, {3.0, 6.0}};
// A solve ends when a step gains less than this share of the energy.
constexpr double Tolerance = 1e-6;
// Levenberg-Marquardt's damping (relative to the diagonal) at a solve's start, and the least a
// rejected step is tried again with: on captured takes the step's promised decrease changes by
// 4 % at 1e-1 and by 40 % at 1 (jumping), so smaller retries only repeat the rejected step.
constexpr double StartDamping = 1e-4;
constexpr double RetryDamping = 1.0;
// A rejected step that promised less than this share of the energy ends the stage: it lies in
// the energy's own roughness (trilinear field, correspondences that change). On jumping such
// steps took 5-6 factorisations each and, when a retry was kept, gained under 2e-5 of E.
constexpr double Roughness = 1e-4;
// With acceleration, a stage ends once a step moves no vertex farther than this (voxels, any
// coordinate), as the fine level's solves do: later steps are the energy's noise.
constexpr double SettledMove = 0.1;
// Steps are accelerated once they move no vertex farther than this (voxels, any coordinate).
constexpr double AcceleratedMove = 2.0;
// An accelerated state moves no vertex farther than this from where the plain step put it
// (voxels, any coordinate): beyond, it is brought back toward the plain step.
constexpr double AcceleratedReach = 1.0;
// The stretch term: the share of an edge's length that may change freely (skin over a joint).
constexpr double StretchFreedom = 0.1;
} // namespace

GraphRegistration::GraphRegistration(const DeformationGraph& graph, double lengthScale,
                                     double voxel)
    : Graph(graph), Scale(1.0 / (lengthScale * voxel)), Voxel(voxel)
{
  // The data terms' models are block diagonal here (the points -> mesh term gives its diagonal
  // upper bound), so a vertex couples only the nodes it blends: the graph's own edges.
  const TriangleMesh& mesh = graph.mesh();
  VertexModel = support::BlockSparseMatrix(mesh.numberOfVertices(), {});
  resetReference();
  if (!Arms.empty())
  {
    double sum = 0;
    for (const Eigen::Vector3d& arm : Arms)
      sum += arm.norm();
    MeanArm = sum / static_cast<double>(Arms.size());
  }
  NodeModel = support::BlockSparseMatrixOf<6>(graph.numberOfNodes(), graph.edges());
  // The blocks each directed edge (j, k) of E_reg adds to, found once: (j, j), (k, k), (j, k).
  for (const auto& edge : graph.edges())
    for (int direction = 0; direction < 2; ++direction)
    {
      const std::int64_t j = edge[direction], k = edge[1 - direction];
      EdgeSlots.push_back({NodeModel.slotOf(j, j), NodeModel.slotOf(k, k), NodeModel.slotOf(j, k)});
    }
  // The node block each (vertex block, node of a, node of b) adds to, found once.
  VertexModel.forEachBlock(
      [&](std::int64_t a, std::int64_t b, const double*, int)
      {
        for (auto i = graph.influencesBegin(static_cast<std::size_t>(a));
             i != graph.influencesEnd(static_cast<std::size_t>(a)); ++i)
          for (auto k = graph.influencesBegin(static_cast<std::size_t>(b));
               k != graph.influencesEnd(static_cast<std::size_t>(b)); ++k)
            ProjectionSlots.push_back(NodeModel.slotOf(i->node, k->node));
      });
}

double GraphRegistration::regularisation(const DeformationGraph::State& state, double rigidity,
                                         support::BlockSparseMatrixOf<6>* hessian,
                                         Eigen::VectorXd* gradient) const
{
  const auto& edges = Graph.edges();
  if (edges.empty() || rigidity <= 0)
    return 0;
  const double scale = rigidity * Scale / static_cast<double>(edges.size());
  double e = 0;
  for (std::size_t index = 0; index < edges.size(); ++index)
    for (int direction = 0; direction < 2; ++direction)
    {
      const auto& edge = edges[index];
      const std::int64_t j = edge[direction], k = edge[1 - direction];
      const double c = scale * (EdgeWeight.empty() ? 1.0 : EdgeWeight[2 * index + direction]);
      const Eigen::Vector3d r = edgeResidual(state, index, direction);
      const Eigen::Vector3d arm = state.rotation[j] * Arms[2 * index + direction];
      e += 0.5 * c * r.squaredNorm();
      if (!hessian)
        continue;
      // de/d(w_j, t_j) = Jj = [-[arm]x, I], de/d(w_k, t_k) = Jk = [0, -I]; their products
      // written out ([a]x^T = -[a]x, [a]x^T [a]x = |a|^2 I - a a^T): c Jj^T Jj, c Jk^T Jk,
      // c Jj^T Jk, and the gradients c Jj^T r = c (arm x r, r), c Jk^T r = c (0, -r).
      // Only their non-zero 3 x 3 corners are added (a third of the 6 x 6 entries).
      const Eigen::Matrix3d cross = c * crossMatrix(arm);
      const Eigen::Matrix3d bend =
          c * (arm.squaredNorm() * Eigen::Matrix3d::Identity() - arm * arm.transpose());
      const auto& slots = EdgeSlots[2 * index + direction]; // (j, j), (k, k), (j, k)
      hessian->addCorner(slots[0], 0, 0, bend);
      hessian->addCorner(slots[0], 0, 3, cross);
      hessian->addCorner(slots[0], 3, 0, -cross);
      hessian->addCornerDiagonal(slots[0], 3, 3, c);
      hessian->addCornerDiagonal(slots[1], 3, 3, c);
      hessian->addCorner(slots[2], 0, 3, -cross);
      hessian->addCornerDiagonal(slots[2], 3, 3, -c);
      gradient->segment<3>(6 * j) += c * arm.cross(r);
      gradient->segment<3>(6 * j + 3) += c * r;
      gradient->segment<3>(6 * k + 3) -= c * r;
    }
  return StretchWeight > 0 ? e + stretching(state, StretchWeight * scale, hessian, gradient) : e;
}

double GraphRegistration::stretching(const DeformationGraph::State& state, double weight,
                                     support::BlockSparseMatrixOf<6>* hessian,
                                     Eigen::VectorXd* gradient) const
{
  // Per edge: s = the change of |(g_k + t_k) - (g_j + t_j)| from the reference length beyond a
  // free share; E = weight / 2 * s^2, least squares at any size. Limbs bend at joints but do not
  // stretch: without it a hoof passing close to another limb's data is pulled along with it,
  // and the bending term's L1 penalty hardly resists.
  const auto& edges = Graph.edges();
  double e = 0;
  for (std::size_t index = 0; index < edges.size(); ++index)
  {
    const std::int64_t j = edges[index][0], k = edges[index][1];
    const Eigen::Vector3d d =
        Eigen::Vector3d(Graph.nodePosition(static_cast<std::size_t>(k))) + state.translation[k] -
        Eigen::Vector3d(Graph.nodePosition(static_cast<std::size_t>(j))) - state.translation[j];
    const double length = d.norm(), rest = Arms[2 * index].norm();
    const double change = length - rest, free = StretchFreedom * rest;
    if (std::abs(change) <= free || length <= 0)
      continue;
    const double excess = change > 0 ? change - free : change + free;
    e += 0.5 * weight * excess * excess;
    if (!hessian)
      continue;
    // ds/dt_k = u^T, ds/dt_j = -u^T (u = d / |d|): Gauss-Newton blocks on the translations.
    const Eigen::Vector3d u = d / length;
    const Eigen::Matrix3d along = weight * u * u.transpose();
    const auto& slots = EdgeSlots[2 * index]; // (j, j), (k, k), (j, k)
    hessian->addCorner(slots[0], 3, 3, along);
    hessian->addCorner(slots[1], 3, 3, along);
    hessian->addCorner(slots[2], 3, 3, -along);
    gradient->segment<3>(6 * j + 3) -= weight * excess * u;
    gradient->segment<3>(6 * k + 3) += weight * excess * u;
  }
  return e;
}

void GraphRegistration::project(const DeformationGraph::State& state,
                                const Eigen::VectorXd& vertexGradient,
                                Eigen::VectorXd& nodeGradient)
{
  // B_aj = w_aj [-[r_aj]x, I] with r_aj = R_j (v_a - g_j): how vertex a moves with node j's
  // rotation and translation. The vertex model is block diagonal (M_a, symmetric), so
  // H_nodes += B_aj^T M_a B_ak over the pairs of nodes vertex a blends, written out:
  //   w_aj w_ak [-P_j [r_ak]x, P_j; P_k^T, M_a]  with P_j = [r_aj]x M_a,
  // and g_nodes += B_aj^T g_a = w_aj (r_aj x g_a, g_a).
  std::vector<Eigen::Vector3d> arms;
  std::vector<Eigen::Matrix3d> products;
  std::size_t next = 0; // into ProjectionSlots, in the order forEachBlock visits the blocks
  VertexModel.forEachBlock(
      [&](std::int64_t a, std::int64_t, const double* block, int stride)
      {
        const auto v = static_cast<std::size_t>(a);
        const auto n = static_cast<std::size_t>(Graph.influencesEnd(v) - Graph.influencesBegin(v));
        const std::size_t slots = next;
        next += n * n;
        Eigen::Matrix3d M;
        for (int c = 0; c < 3; ++c)
          for (int r = 0; r < 3; ++r)
            M(r, c) = block[c * stride + r];
        projectGradient(state, v, M, vertexGradient, arms, products, nodeGradient);
        if (M.isZero(0.0))
          return;
        projectModel(v, M, arms, products, slots);
      });
}

void GraphRegistration::projectGradient(const DeformationGraph::State& state, std::size_t v,
                                        const Eigen::Matrix3d& M,
                                        const Eigen::VectorXd& vertexGradient,
                                        std::vector<Eigen::Vector3d>& arms,
                                        std::vector<Eigen::Matrix3d>& products,
                                        Eigen::VectorXd& nodeGradient) const
{
  const auto influences = Graph.influencesBegin(v);
  const auto n = static_cast<std::size_t>(Graph.influencesEnd(v) - influences);
  const Eigen::Vector3d rest(Graph.rest() + 3 * v);
  const Eigen::Vector3d g = vertexGradient.segment<3>(static_cast<Eigen::Index>(3 * v));
  arms.resize(n);
  products.resize(n);
  for (std::size_t p = 0; p < n; ++p)
  {
    const std::int64_t j = influences[p].node;
    const double w = influences[p].weight;
    arms[p] = state.rotation[j] *
              (rest - Eigen::Vector3d(Graph.nodePosition(static_cast<std::size_t>(j))));
    nodeGradient.segment<3>(6 * j) += w * arms[p].cross(g);
    nodeGradient.segment<3>(6 * j + 3) += w * g;
    products[p] = crossMatrix(arms[p]) * M;
  }
}

void GraphRegistration::projectModel(std::size_t v, const Eigen::Matrix3d& M,
                                     const std::vector<Eigen::Vector3d>& arms,
                                     const std::vector<Eigen::Matrix3d>& products,
                                     std::size_t slots)
{
  const auto influences = Graph.influencesBegin(v);
  const auto n = static_cast<std::size_t>(Graph.influencesEnd(v) - influences);
  for (std::size_t p = 0; p < n; ++p)
    for (std::size_t q = 0; q < n; ++q)
    {
      // (j, k) and (k, j) are transposes: each pair is added once, to j <= k.
      if (influences[p].node > influences[q].node)
        continue;
      const double w = influences[p].weight * influences[q].weight;
      Matrix66 m;
      m.topLeftCorner<3, 3>() = -w * products[p] * crossMatrix(arms[q]);
      m.topRightCorner<3, 3>() = w * products[p];
      m.bottomLeftCorner<3, 3>() = w * products[q].transpose();
      m.bottomRightCorner<3, 3>() = w * M;
      NodeModel.addBlock(ProjectionSlots[slots + p * n + q], m.data());
    }
}

Eigen::Vector3d GraphRegistration::edgeResidual(const DeformationGraph::State& state,
                                                std::size_t index, int direction) const
{
  const std::int64_t j = Graph.edges()[index][direction], k = Graph.edges()[index][1 - direction];
  const Eigen::Vector3d gj(Graph.nodePosition(static_cast<std::size_t>(j)));
  const Eigen::Vector3d gk(Graph.nodePosition(static_cast<std::size_t>(k)));
  return state.rotation[j] * Arms[2 * index + direction] + gj + state.translation[j] - gk -
         state.translation[k];
}

void GraphRegistration::resetReference()
{
  // The arm of edge (j, k) in node j's frame, as in the template: g_k - g_j.
  const auto& edges = Graph.edges();
  Arms.resize(2 * edges.size());
  for (std::size_t index = 0; index < edges.size(); ++index)
    for (int direction = 0; direction < 2; ++direction)
      Arms[2 * index + direction] =
          Eigen::Vector3d(
              Graph.nodePosition(static_cast<std::size_t>(edges[index][1 - direction]))) -
          Eigen::Vector3d(Graph.nodePosition(static_cast<std::size_t>(edges[index][direction])));
}

void GraphRegistration::yield(const DeformationGraph::State& state, double rate, double limit)
{
  // Plasticity: where an edge stays bent beyond `limit` from its reference, the reference gives
  // way by `rate` of the excess (in node j's frame), so lasting deformation stops being pulled
  // back while near-rigid parts keep the template's shape.
  const auto& edges = Graph.edges();
  for (std::size_t index = 0; index < edges.size(); ++index)
    for (int direction = 0; direction < 2; ++direction)
    {
      const std::int64_t j = edges[index][direction], k = edges[index][1 - direction];
      const Eigen::Vector3d gj(Graph.nodePosition(static_cast<std::size_t>(j)));
      const Eigen::Vector3d gk(Graph.nodePosition(static_cast<std::size_t>(k)));
      const Eigen::Vector3d current =
          state.rotation[j].transpose() * (gk + state.translation[k] - gj - state.translation[j]);
      Eigen::Vector3d& arm = Arms[2 * index + direction];
      const Eigen::Vector3d excess = current - arm;
      const double size = excess.norm();
      if (size > limit)
        arm += rate * (1 - limit / size) * excess;
    }
}

void GraphRegistration::reweightEdges(const DeformationGraph::State& state, double robustScale)
{
  // Huber weights of each directed edge's bending at the current state (iteratively reweighted
  // least squares): beyond the scale an edge costs in proportion to |e| (L1), not |e|^2, so the
  // regulariser prefers a few edges bending much (joints) to many bending a little: the graph
  // moves as near-rigid pieces. A redescending weight (Geman-McClure) frees the joints entirely
  // and lets symmetric parts (a limb about its axis) drift; least squares spreads bending
  // everywhere and pulls tracked shapes away from the truth (BenchmarkTracker,
  // Documentation/Tracking.md).
  const auto& edges = Graph.edges();
  EdgeWeight.assign(2 * edges.size(), 1.0);
  const RobustKernel kernel{RobustKernel::Kind::Huber, robustScale};
  if (!kernel.active())
    return;
  for (std::size_t index = 0; index < edges.size(); ++index)
    for (int direction = 0; direction < 2; ++direction)
      EdgeWeight[2 * index + direction] = kernel.weightOfSquaredRatio(
          edgeResidual(state, index, direction).squaredNorm() / (kernel.scale * kernel.scale));
}

DeformationGraph::State GraphRegistration::retract(const DeformationGraph::State& state,
                                                   const Eigen::VectorXd& step)
{
  DeformationGraph::State next = state;
  for (std::size_t j = 0; j < state.rotation.size(); ++j)
  {
    const Eigen::Vector3d w = step.segment<3>(static_cast<Eigen::Index>(6 * j));
    const double angle = w.norm();
    if (angle > 0)
      next.rotation[j] = Eigen::AngleAxisd(angle, w / angle).toRotationMatrix() * state.rotation[j];
    next.translation[j] += step.segment<3>(static_cast<Eigen::Index>(6 * j + 3));
  }
  return next;
}

double GraphRegistration::model(const DeformationGraph::State& state,
                                const std::vector<EnergyTerm*>& terms, double rigidity,
                                Eigen::VectorXd& gradient)
{
  const std::size_t nv = Graph.mesh().numberOfVertices();
  std::vector<double> x(3 * nv);
  Graph.deform(state, x.data());
  Eigen::VectorXd vertexGradient = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(3 * nv));
  VertexModel.setZero();
  double energy = 0;
  for (const EnergyTerm* t : terms)
    energy += t->addModel(x.data(), VertexModel, vertexGradient.data());
  NodeModel.setZero();
  gradient = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(6 * Graph.numberOfNodes()));
  project(state, vertexGradient, gradient);
  return energy + regularisation(state, rigidity, &NodeModel, &gradient);
}

double GraphRegistration::linearise(const DeformationGraph::State& state,
                                    const std::vector<EnergyTerm*>& terms, double rigidity,
                                    std::vector<double>& x)
{
  Graph.deform(state, x.data());
  for (EnergyTerm* t : terms)
    t->linearise(x.data());
  reweightEdges(state, RobustScale);
  return model(state, terms, rigidity, NodeGradient);
}

double GraphRegistration::largestDifference(const std::vector<double>& a,
                                            const std::vector<double>& b)
{
  double largest = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    largest = std::max(largest, std::abs(a[i] - b[i]));
  return largest;
}

Eigen::VectorXd GraphRegistration::coordinates(const DeformationGraph::State& state,
                                               const DeformationGraph::State& origin) const
{
  Eigen::VectorXd u(static_cast<Eigen::Index>(6 * state.rotation.size()));
  for (std::size_t j = 0; j < state.rotation.size(); ++j)
  {
    const auto at = static_cast<Eigen::Index>(6 * j);
    const Eigen::AngleAxisd turn(
        Eigen::Matrix3d(state.rotation[j] * origin.rotation[j].transpose()));
    u.segment<3>(at) = MeanArm * turn.angle() * turn.axis();
    u.segment<3>(at + 3) = state.translation[j];
  }
  return u;
}

DeformationGraph::State
GraphRegistration::fromCoordinates(const Eigen::VectorXd& u,
                                   const DeformationGraph::State& origin) const
{
  DeformationGraph::State state = origin;
  for (std::size_t j = 0; j < state.rotation.size(); ++j)
  {
    const auto at = static_cast<Eigen::Index>(6 * j);
    const Eigen::Vector3d w = u.segment<3>(at) / MeanArm;
    const double angle = w.norm();
    if (angle > 0)
      state.rotation[j] =
          Eigen::AngleAxisd(angle, w / angle).toRotationMatrix() * origin.rotation[j];
    state.translation[j] = u.segment<3>(at + 3);
  }
  return state;
}

int GraphRegistration::solve(DeformationGraph::State& state, const std::vector<EnergyTerm*>& terms,
                             double rigidity, int iterations)
{
  const std::size_t n = 3 * Graph.mesh().numberOfVertices();
  std::vector<double> x(n), y(n); // the mesh where a step starts, and its last trial
  double damping = StartDamping;
  std::unique_ptr<AndersonAcceleration> anderson;
  if (Acceleration > 0)
    anderson = std::make_unique<AndersonAcceleration>(Acceleration);
  const DeformationGraph::State origin = state; // the accelerator's coordinates start here
  DeformationGraph::State plain;                // the plain step an accelerated state replaced
  double startEnergy = 0;                       // E where that step started
  bool accelerated = false;
  int step = 0;
  for (; step < iterations; ++step)
  {
    double energy = linearise(state, terms, rigidity, x);
    if (accelerated && energy > startEnergy)
    {
      // Worse than where its step started: back to the plain step, the history forgotten.
      state = plain;
      anderson->reset();
      energy = linearise(state, terms, rigidity, x);
    }
    accelerated = false;
    const DeformationGraph::State start = anderson ? state : DeformationGraph::State();
    double decrease = 0;
    const bool accepted = dampedStep(state, terms, rigidity, energy, damping, decrease, y);
    // y holds the mesh of the step just kept.
    const double move = anderson && accepted ? largestDifference(x, y) / Voxel : HUGE_VAL;
    if (!accepted || decrease <= Tolerance * std::abs(energy) || move <= SettledMove)
    {
      step += accepted;
      break;
    }
    if (!anderson)
      continue;
    // Not on the last step: an accelerated state is only kept once its energy is known.
    accelerated =
        accelerate(*anderson, move, step + 1 < iterations, start, origin, y, state, plain);
    if (accelerated)
      startEnergy = energy;
  }
  return step;
}

bool GraphRegistration::accelerate(AndersonAcceleration& anderson, double move, bool allowed,
                                   const DeformationGraph::State& start,
                                   const DeformationGraph::State& origin,
                                   const std::vector<double>& plainMesh,
                                   DeformationGraph::State& state,
                                   DeformationGraph::State& plain) const
{
  // Accelerated only in the tail, where steps are small and converge linearly: larger steps
  // still jump between correspondences, and extrapolating them carried a passing leg's
  // vertices toward the other leg's data (Tracker.KeepsALegThatPassesAnother).
  Eigen::VectorXd next;
  if (move > AcceleratedMove)
    anderson.reset();
  else if (const Eigen::VectorXd atPlain = coordinates(state, origin);
           allowed && anderson.next(coordinates(start, origin), atPlain, next))
  {
    plain = state;
    state = towardAccelerated(atPlain, next, origin, plainMesh);
    return true;
  }
  return false;
}

DeformationGraph::State
GraphRegistration::towardAccelerated(const Eigen::VectorXd& plain, Eigen::VectorXd accelerated,
                                     const DeformationGraph::State& origin,
                                     const std::vector<double>& plainMesh) const
{
  // The accelerated state, brought back toward the plain step (along the straight line between
  // their coordinates) until no vertex lies farther than AcceleratedReach from where the plain
  // step put it. Without this limit two horse-gallop takes lost a part near their end (seeds 1
  // and 3); with it they keep it (Documentation/TrackingHistory.md).
  std::vector<double> z(plainMesh.size());
  Graph.deform(fromCoordinates(accelerated, origin), z.data());
  const double beyond = largestDifference(plainMesh, z) / Voxel;
  if (beyond > AcceleratedReach)
    accelerated = plain + (AcceleratedReach / beyond) * (accelerated - plain);
  return fromCoordinates(accelerated, origin);
}

bool GraphRegistration::dampedStep(DeformationGraph::State& state,
                                   const std::vector<EnergyTerm*>& terms, double rigidity,
                                   double energy, double& damping, double& decrease,
                                   std::vector<double>& trial)
{
  // The factorisation's pattern (the graph's edges) is analysed at the first step of the first
  // solve; every factorisation after reuses it.
  if (!Analysed)
  {
    Solver.analyse(NodeModel);
    Analysed = true;
  }
  // Levenberg-Marquardt on the model just built: a step is kept when E falls by at least a tenth
  // of what the model promised; otherwise the damping grows tenfold, to at least RetryDamping
  // (each try costs a factorisation), at most eight tries. A rejected step whose model promised
  // less than Roughness of E ends the tries: more damping only promises less, and so little is
  // within the energy's noise.
  const Eigen::VectorXd diagonal = NodeModel.diagonal();
  const double floor = 1e-12 * std::max(diagonal.maxCoeff(), 1e-300);
  for (int attempt = 0; attempt < 8; ++attempt)
  {
    const Eigen::VectorXd shift = damping * diagonal.array() + floor;
    NodeModel.addToDiagonal(shift);
    const bool solved = Solver.factorise(NodeModel);
    Eigen::VectorXd delta;
    if (solved)
      delta = Solver.solve(-NodeGradient);
    NodeModel.addToDiagonal(-shift);
    if (!solved || !delta.allFinite())
    {
      damping *= 10;
      continue;
    }
    const double predicted =
        -(NodeGradient.dot(delta) +
          0.5 * delta.dot(NodeModel.matrix().selfadjointView<Eigen::Lower>() * delta));
    const DeformationGraph::State candidate = retract(state, delta);
    Graph.deform(candidate, trial.data());
    const double after =
        evaluateAll(terms, trial.data(), nullptr) + regularisation(candidate, rigidity);
    decrease = energy - after;
    if (predicted > 0 && decrease > 0.1 * predicted)
    {
      state = candidate;
      if (decrease > 0.75 * predicted)
        damping = std::max(damping * 0.3, 1e-9);
      return true;
    }
    if (predicted <= Roughness * std::abs(energy))
      return false;
    damping = std::max(damping * 10, RetryDamping);
  }
  return false;
}

int GraphRegistration::registerFrame(DeformationGraph::State& state, DistanceTerm& distance,
                                     CoverageTerm* coverage, GraphStiffness stiffness,
                                     double robustScale, int iterationsPerStage,
                                     const std::vector<EnergyTerm*>& extra)
{
  const double rigidity = stiffness.rigidity;
  StretchWeight = stiffness.stretchWeight;
  std::vector<EnergyTerm*> terms{&distance};
  if (coverage)
  {
    coverage->setDiagonalModel(true);
    terms.push_back(coverage);
  }
  terms.insert(terms.end(), extra.begin(), extra.end());
  std::vector<double> x(3 * Graph.mesh().numberOfVertices());
  RobustScale = robustScale;
  int steps = 0;
  for (const Stage& stage : Schedule)
  {
    const double reach = stage.reach * Voxel;
    distance.setRobustScale(reach / 3);
    if (coverage)
    {
      coverage->setRobustScale(reach / 3);
      coverage->setMaxDistance(reach);
      coverage->searchWholeSurface(); // followed within the stage if CoverageOptions says so
    }
    Graph.deform(state, x.data());
    distance.decide(x.data());
    steps += solve(state, terms, rigidity * stage.rigidity, iterationsPerStage);
  }
  if (coverage)
    coverage->setDiagonalModel(false);
  return steps;
}

} // namespace dp
