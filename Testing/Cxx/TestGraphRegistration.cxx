// SPDX-License-Identifier: BSD-3-Clause
// GraphRegistration: the coarse level's solve, its gradients, models and accelerated steps.

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/LocalThickness.h"
#include "dp/geometry/SurfaceLocator.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/track/AndersonAcceleration.h"
#include "dp/track/ClothEnergy.h"
#include "dp/track/CoverageTerm.h"
#include "dp/track/DeformationGraph.h"
#include "dp/track/DistanceTerm.h"
#include "dp/track/FrameData.h"
#include "dp/track/FrameQuality.h"
#include "dp/track/GraphRegistration.h"
#include "dp/track/InternalEnergyTerm.h"
#include "dp/track/Solvers.h"
#include "dp/track/TemporalTerm.h"
#include "dp/track/TracePreconditioner.h"
#include "dp/track/Tracker.h"

#include "NumericChecks.h"
#include "TrackingShapes.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <random>
#include <utility>

namespace
{

using dp::test::expectGradientMatches;
using dp::test::Frame;
using dp::test::jiggle;
using dp::test::Shape;
using dp::test::tube;

// A 16 x 12 tube and a 20-node deformation graph on it.
struct TubeGraph
{
  Shape shape = tube(16, 12);
  dp::TriangleMesh mesh{shape.triangles, shape.positions.size() / 3};
  dp::DeformationGraph graph{mesh, shape.positions.data(), 20, 4};
};

// The coarse level's test problem: a 16 x 12 tube, its frame's points and masses, and a 20-node
// deformation graph with the registration over it.
struct GraphProblem
{
  Shape shape = tube(16, 12);
  Frame f{shape.positions, false, shape};
  dp::DeformationGraph graph{f.mesh, f.shape.positions.data(), 20, 4};
  dp::GraphRegistration registration{graph, f.L, f.voxel};
};

// The coarse level's data terms on a problem's frame, as registerFrame() uses them: the
// distance term with `options` and the points -> mesh term with its diagonal model.
struct CoarseTerms
{
  dp::DistanceTerm distance;
  dp::CoverageTerm coverage;
  CoarseTerms(const Frame& f, const dp::DistanceTermOptions& options)
      : distance(*f.data, f.mesh, f.mass, f.L, options),
        coverage(f.data->spreadSamples(), f.mesh, f.L, robustCoverage(f))
  {
    coverage.setDiagonalModel(true);
  }
  std::vector<dp::EnergyTerm*> all() { return {&distance, &coverage}; }
  static dp::CoverageOptions robustCoverage(const Frame& f)
  {
    dp::CoverageOptions c;
    c.robustScale = 3 * f.voxel;
    return c;
  }
};

// A state off the data: every node turned by up to `angle` and moved up to 0.01, differently.
dp::DeformationGraph::State turnedState(const dp::DeformationGraph& graph, double angle,
                                        std::mt19937_64& rng)
{
  std::uniform_real_distribution<double> u(-1, 1);
  dp::DeformationGraph::State state = graph.identity();
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
  {
    state.rotation[j] =
        Eigen::AngleAxisd(angle * u(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized())
            .matrix();
    state.translation[j] = 0.01 * Eigen::Vector3d(u(rng), u(rng), u(rng));
  }
  return state;
}

// `state` moved by h along a node-space direction (angle-axis increments, translations).
dp::DeformationGraph::State movedAlong(const dp::DeformationGraph::State& state,
                                       const Eigen::VectorXd& direction, double h)
{
  dp::DeformationGraph::State s = state;
  for (std::size_t j = 0; j < state.rotation.size(); ++j)
  {
    const Eigen::Vector3d w = h * direction.segment<3>(static_cast<Eigen::Index>(6 * j));
    s.rotation[j] =
        Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix() * state.rotation[j];
    s.translation[j] += h * direction.segment<3>(static_cast<Eigen::Index>(6 * j + 3));
  }
  return s;
}

TEST(GraphRegistration, NodeGradientMatchesFiniteDifferences)
{
  // E(theta) = data terms at x(theta) + E_reg(theta): its node-space gradient (the vertex model
  // carried through the blending) against central differences in each node's rotation
  // (angle-axis increment) and translation.
  GraphProblem problem;
  const Frame& f = problem.f;
  const dp::DeformationGraph& graph = problem.graph;
  dp::GraphRegistration& registration = problem.registration;
  // The distance to the points, squared: its model's gradient is exact (the distance to planes
  // holds the interpolation weights), so the test sees the projection alone.
  dp::DistanceTermOptions d;
  d.normalTestDegrees = 180;
  d.measure = dp::DistanceMeasure::Points;
  CoarseTerms data(f, d);
  const std::vector<dp::EnergyTerm*> terms = data.all();
  std::mt19937_64 rng(5);
  const dp::DeformationGraph::State state = turnedState(graph, 0.05, rng);
  std::vector<double> x(f.shape.positions.size());
  graph.deform(state, x.data());
  data.coverage.linearise(x.data());
  const double rigidity = 3.0;
  Eigen::VectorXd gradient;
  registration.model(state, terms, rigidity, gradient);
  auto energyAt = [&](const dp::DeformationGraph::State& s)
  {
    std::vector<double> y(x.size());
    graph.deform(s, y.data());
    return dp::evaluateAll(terms, y.data(), nullptr) + registration.regularisation(s, rigidity);
  };
  const double h = 1e-7;
  double worst = 0, scale = 0;
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
    for (int k = 0; k < 6; ++k)
    {
      dp::DeformationGraph::State plus = state, minus = state;
      Eigen::Vector3d e = Eigen::Vector3d::Zero();
      e[k % 3] = h;
      if (k < 3)
      {
        plus.rotation[j] = Eigen::AngleAxisd(h, e.normalized()).matrix() * state.rotation[j];
        minus.rotation[j] = Eigen::AngleAxisd(-h, e.normalized()).matrix() * state.rotation[j];
      }
      else
      {
        plus.translation[j] += e;
        minus.translation[j] -= e;
      }
      const double numeric = (energyAt(plus) - energyAt(minus)) / (2 * h);
      worst = std::max(worst, std::abs(numeric - gradient[static_cast<Eigen::Index>(6 * j + k)]));
      scale = std::max(scale, std::abs(numeric));
    }
  ASSERT_GT(scale, 0);
  EXPECT_LT(worst, 1e-4 * scale);
}

TEST(GraphRegistration, LimbsBendButDoNotStretch)
{
  // The regulariser alone on a graph stretched uniformly about its centre (every edge longer by
  // the same share): its gradient against central differences, and its growth with the stretch.
  const TubeGraph tubeGraph;
  const dp::DeformationGraph& graph = tubeGraph.graph;
  const double voxel = 0.01;
  dp::GraphRegistration registration(graph, 1.0, voxel);
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
    centre += Eigen::Vector3d(graph.nodePosition(j)) / static_cast<double>(graph.numberOfNodes());
  auto stretched = [&](double factor)
  {
    dp::DeformationGraph::State s = graph.identity();
    for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
      s.translation[j] = (factor - 1) * (Eigen::Vector3d(graph.nodePosition(j)) - centre);
    return s;
  };
  const double rigidity = 2.0;
  auto growth = [&]
  {
    const double e13 = registration.regularisation(stretched(1.3), rigidity);
    EXPECT_GT(e13, 0);
    return registration.regularisation(stretched(1.6), rigidity) / e13;
  };
  // Bending is least squares outside a solve (no Huber weights yet): alone it grows as
  // (0.6 / 0.3)^2 = 4; the stretch term as (0.5 / 0.2)^2 = 6.25.
  registration.setStretchWeight(0);
  EXPECT_NEAR(growth(), 4.0, 1e-9);
  registration.setStretchWeight(1);
  EXPECT_GT(growth(), 4.3);

  const dp::DeformationGraph::State state = stretched(1.3);
  dp::support::BlockSparseMatrixOf<6> hessian(graph.numberOfNodes(), graph.edges());
  Eigen::VectorXd gradient =
      Eigen::VectorXd::Zero(static_cast<Eigen::Index>(6 * graph.numberOfNodes()));
  registration.regularisation(state, rigidity, &hessian, &gradient);
  const double h = 1e-7;
  double worst = 0, scale = 0;
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
    for (int k = 3; k < 6; ++k)
    {
      dp::DeformationGraph::State plus = state, minus = state;
      plus.translation[j][k - 3] += h;
      minus.translation[j][k - 3] -= h;
      const double numeric = (registration.regularisation(plus, rigidity) -
                              registration.regularisation(minus, rigidity)) /
                             (2 * h);
      worst = std::max(worst, std::abs(numeric - gradient[static_cast<Eigen::Index>(6 * j + k)]));
      scale = std::max(scale, std::abs(numeric));
    }
  ASSERT_GT(scale, 0);
  EXPECT_LT(worst, 1e-4 * scale);
}

TEST(GraphRegistration, NodeModelIsTheVertexModelCarriedThroughTheBlending)
{
  // The data terms' part of the node model is J^T H J, H their vertex model and J = dx/dtheta
  // the blending's Jacobian: for any direction d in node space, d^T (model - E_reg's part) d
  // equals (J d)^T H (J d), with J d from central differences of the deformed positions.
  GraphProblem problem;
  const Frame& f = problem.f;
  const dp::DeformationGraph& graph = problem.graph;
  dp::GraphRegistration& registration = problem.registration;
  CoarseTerms data(f, dp::DistanceTermOptions{});
  const std::vector<dp::EnergyTerm*> terms = data.all();
  const std::size_t nodes = graph.numberOfNodes();
  std::mt19937_64 rng(11);
  const dp::DeformationGraph::State state = turnedState(graph, 0.3, rng);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> x(f.shape.positions.size());
  graph.deform(state, x.data());
  data.distance.decide(x.data());
  data.coverage.linearise(x.data());
  const double rigidity = 3.0;
  Eigen::VectorXd gradient;
  registration.model(state, terms, rigidity, gradient);
  const Eigen::SparseMatrix<double> nodeModel = registration.nodeModel().matrix();
  dp::support::BlockSparseMatrixOf<6> regulariser(nodes, graph.edges());
  Eigen::VectorXd unused = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(6 * nodes));
  registration.regularisation(state, rigidity, &regulariser, &unused);
  const Eigen::SparseMatrix<double> dataPart =
      nodeModel - Eigen::SparseMatrix<double>(regulariser.matrix());
  dp::support::BlockSparseMatrix vertexModel(x.size() / 3, {});
  std::vector<double> vertexGradient(x.size(), 0.0);
  for (const dp::EnergyTerm* t : terms)
    t->addModel(x.data(), vertexModel, vertexGradient.data());
  const Eigen::SparseMatrix<double> H = vertexModel.matrix();
  for (int trial = 0; trial < 3; ++trial)
  {
    Eigen::VectorXd direction(static_cast<Eigen::Index>(6 * nodes));
    for (Eigen::Index i = 0; i < direction.size(); ++i)
      direction[i] = u(rng);
    auto deformedAlong = [&](double h)
    {
      std::vector<double> y(x.size());
      graph.deform(movedAlong(state, direction, h), y.data());
      return Eigen::Map<const Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(y.size()))
          .eval();
    };
    const double h = 1e-6;
    const Eigen::VectorXd moved = (deformedAlong(h) - deformedAlong(-h)) / (2 * h);
    const double expected = moved.dot(H.selfadjointView<Eigen::Lower>() * moved);
    const double modelled = direction.dot(dataPart.selfadjointView<Eigen::Lower>() * direction);
    ASSERT_GT(expected, 0);
    EXPECT_NEAR(modelled, expected, 1e-6 * expected) << "direction " << trial;
  }
}

TEST(GraphRegistration, RegulariserModelIsItsHessianWhereNoEdgeBends)
{
  // Under a rigid motion of the whole graph no edge bends or stretches (E_reg = 0, residuals 0),
  // so the Gauss-Newton model J^T J is E_reg's exact Hessian there: the model times a direction
  // against central differences of the gradient along it (rotation increments and translations).
  const TubeGraph tubeGraph;
  const dp::DeformationGraph& graph = tubeGraph.graph;
  dp::GraphRegistration registration(graph, 1.0, 0.01);
  const std::size_t nodes = graph.numberOfNodes();
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  dp::DeformationGraph::State rigid = graph.identity();
  for (std::size_t j = 0; j < nodes; ++j)
  {
    const Eigen::Vector3d g(graph.nodePosition(j));
    rigid.rotation[j] = turn;
    rigid.translation[j] = turn * g + Eigen::Vector3d(0.1, -0.2, 0.3) - g;
  }
  const double rigidity = 2.0;
  ASSERT_LT(registration.regularisation(rigid, rigidity), 1e-20);
  auto modelAt = [&](const dp::DeformationGraph::State& s, Eigen::VectorXd& gradient)
  {
    dp::support::BlockSparseMatrixOf<6> hessian(nodes, graph.edges());
    gradient = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(6 * nodes));
    registration.regularisation(s, rigidity, &hessian, &gradient);
    return Eigen::SparseMatrix<double>(hessian.matrix());
  };
  Eigen::VectorXd gradient;
  const Eigen::SparseMatrix<double> lower = modelAt(rigid, gradient);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::VectorXd direction(static_cast<Eigen::Index>(6 * nodes));
  for (Eigen::Index i = 0; i < direction.size(); ++i)
    direction[i] = u(rng);
  const Eigen::VectorXd modelled = lower.selfadjointView<Eigen::Lower>() * direction;
  const double h = 1e-6;
  Eigen::VectorXd plus, minus;
  modelAt(movedAlong(rigid, direction, h), plus);
  modelAt(movedAlong(rigid, direction, -h), minus);
  const Eigen::VectorXd numeric = (plus - minus) / (2 * h);
  ASSERT_GT(numeric.norm(), 0);
  EXPECT_LT((numeric - modelled).norm(), 1e-5 * numeric.norm());
}

TEST(GraphRegistration, AcceleratedStepsFitTheDataAsWellInFewerSteps)
{
  // The coarse schedule from nodes turned (up to 0.3 rad each, about different axes) and moved off
  // the data, with plain and with Anderson-accelerated steps: both end on the data (RMS distance
  // of the vertices from it well under a voxel), the accelerated schedule in fewer steps (4
  // against 9 when written).
  auto run = [](int depth, double& rmsDistance)
  {
    const Frame f(tube().positions);
    const dp::DeformationGraph graph(f.mesh, f.shape.positions.data(), 20, 4);
    dp::GraphRegistration registration(graph, f.L, f.voxel);
    registration.setAcceleration(depth);
    CoarseTerms data(f, dp::DistanceTermOptions{});
    std::mt19937_64 rng(11);
    dp::DeformationGraph::State state = turnedState(graph, 0.3, rng);
    const int steps = registration.registerFrame(state, data.distance, &data.coverage, {1.0, 1.0},
                                                 0.5 * f.voxel, 10);
    std::vector<double> x(f.shape.positions.size());
    graph.deform(state, x.data());
    double sum = 0;
    const std::size_t nv = x.size() / 3;
    for (std::size_t v = 0; v < nv; ++v)
      sum += std::pow(data.distance.sample(&x[3 * v], v).distance, 2);
    rmsDistance = std::sqrt(sum / static_cast<double>(nv)) / f.voxel;
    return steps;
  };
  double plainDistance = 0, acceleratedDistance = 0;
  const int plainSteps = run(0, plainDistance);
  const int acceleratedSteps = run(3, acceleratedDistance);
  EXPECT_LT(plainDistance, 0.3);
  EXPECT_LT(acceleratedDistance, 1.05 * plainDistance);
  EXPECT_LT(acceleratedSteps, plainSteps);
}

// Adds nothing to the energy; records how far each linearised mesh lies from the trial
// evaluated just before it (the plain step just kept, when an accelerated state follows it).
struct StepRecorder : dp::EnergyTerm
{
  std::vector<double> lastTrial;
  double largestGap = 0;
  int moved = 0; // linearisations away from the last trial
  const char* name() const override { return "recorder"; }
  double evaluate(const double* x, double*) const override
  {
    const_cast<StepRecorder*>(this)->lastTrial.assign(x, x + size);
    return 0;
  }
  double addModel(const double*, dp::support::BlockSparseMatrix&, double*) const override
  {
    return 0;
  }
  void linearise(const double* x) override
  {
    if (lastTrial.empty())
      return;
    double gap = 0;
    for (std::size_t i = 0; i < size; ++i)
      gap = std::max(gap, std::abs(x[i] - lastTrial[i]));
    largestGap = std::max(largestGap, gap);
    moved += gap > 0;
  }
  std::size_t size = 0;
};

// Pulls each vertex toward a point that every linearisation places a tenth of the way from it
// to its goal: the steps converge linearly (0.9x each), as the coarse level's sliding does, so
// Anderson acceleration extrapolates them far.
struct SlowPull : dp::EnergyTerm
{
  std::vector<double> goal, target;
  const char* name() const override { return "slow pull"; }
  void linearise(const double* x) override
  {
    target.resize(goal.size());
    for (std::size_t i = 0; i < goal.size(); ++i)
      target[i] = x[i] + 0.1 * (goal[i] - x[i]);
  }
  double evaluate(const double* x, double* gradient) const override
  {
    double e = 0;
    for (std::size_t i = 0; i < goal.size(); ++i)
    {
      e += 0.5 * (x[i] - target[i]) * (x[i] - target[i]);
      if (gradient)
        gradient[i] += x[i] - target[i];
    }
    return e;
  }
  double addModel(const double* x, dp::support::BlockSparseMatrix& hessian,
                  double* gradient) const override
  {
    const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (std::size_t v = 0; v < goal.size() / 3; ++v)
    {
      const auto vertex = static_cast<std::int64_t>(v);
      hessian.addBlock(hessian.slotOf(vertex, vertex), identity);
    }
    return evaluate(x, gradient);
  }
};

TEST(GraphRegistration, AcceleratedStatesStayWithinAVoxelOfThePlainStep)
{
  // A rigid shift of 8 voxels approached by steps 0.9x the one before: each accelerated state
  // (linearised right after the plain step it replaces was evaluated) moves no vertex more than
  // a voxel from that step (6.5 voxels without that limit, when written), and the solve still
  // ends at the goal (0.14 voxel off after 5 accelerated states).
  const TubeGraph tubeGraph;
  const dp::DeformationGraph& graph = tubeGraph.graph;
  const double voxel = 0.01;
  dp::GraphRegistration registration(graph, 1.0, voxel);
  registration.setAcceleration(3);
  SlowPull pull;
  pull.goal = tubeGraph.shape.positions;
  for (std::size_t i = 0; i < pull.goal.size(); i += 3)
    pull.goal[i] += 8 * voxel;
  StepRecorder recorder;
  recorder.size = tubeGraph.shape.positions.size();
  dp::DeformationGraph::State state = graph.identity();
  registration.solve(state, {&pull, &recorder}, 1.0, 40);
  std::vector<double> x(tubeGraph.shape.positions.size());
  graph.deform(state, x.data());
  double offGoal = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
    offGoal = std::max(offGoal, std::abs(x[i] - pull.goal[i]));
  EXPECT_GT(recorder.moved, 0) << "no accelerated state";
  EXPECT_LE(recorder.largestGap, voxel * (1 + 1e-9));
  EXPECT_LT(offGoal, 0.5 * voxel);
}

} // namespace
