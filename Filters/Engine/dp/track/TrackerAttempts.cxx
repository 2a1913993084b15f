// SPDX-License-Identifier: BSD-3-Clause
// The tracker's tries at a frame (Tracker.h): the start, the coarse level, the fine solve, the
// frame's quality, and the retries from other starts while it fails; and an empty frame's solve.
#include "dp/track/TrackerParts.h"

#include "dp/track/ColourTerm.h"
#include "dp/track/CoverageTerm.h"
#include "dp/track/DistanceTerm.h"
#include "dp/track/FrameData.h"
#include "dp/track/InternalEnergyTerm.h"
#include "dp/track/PartRegrowth.h"
#include "dp/track/RigidAlignment.h"
#include "dp/track/Solvers.h"
#include "dp/track/TemporalTerm.h"

#include <Eigen/LU>
#include <Eigen/SVD>

#include <chrono>
#include <memory>
#include <vector>

namespace dp
{
namespace
{
// The fine level's settled step, in voxels: a step moving no vertex farther ends a solve (the
// field resolves nothing finer).
constexpr double SettledStep = 0.1;
// The fine level's points -> mesh term: robust scale and reach, in voxels (defaults).
constexpr double FineCoverageScale = 3.0;
constexpr double FineCoverageReach = 8.0;
// Robust scale, in voxels, of the distance term that chooses the coarse level's start.
constexpr double StartChoiceScale = 3.0;

// The rigid motion (R, t) that moves `from` closest to `to` (Kabsch, weights `mass`).
void rigidFit(const std::vector<double>& from, const std::vector<double>& to,
              const std::vector<double>& mass, Eigen::Matrix3d& R, Eigen::Vector3d& t)
{
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
  double total = 0;
  for (std::size_t v = 0; v < mass.size(); ++v)
  {
    a += mass[v] * Eigen::Vector3d(&from[3 * v]);
    b += mass[v] * Eigen::Vector3d(&to[3 * v]);
    total += mass[v];
  }
  a /= total;
  b /= total;
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (std::size_t v = 0; v < mass.size(); ++v)
    C += mass[v] * (Eigen::Vector3d(&to[3 * v]) - b) *
         (Eigen::Vector3d(&from[3 * v]) - a).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(C, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  R = svd.matrixU() * D * svd.matrixV().transpose();
  t = b - R * a;
}

// The points -> mesh term over the frame's well-spread subsample, or null when it is off or the
// frame has no subsample.
std::unique_ptr<CoverageTerm> coverageTerm(const FrameData& frame, const TriangleMesh& mesh,
                                           double lengthScale, const TrackerOptions& options)
{
  std::unique_ptr<CoverageTerm> coverage;
  if (options.coverage.weight > 0 && !frame.spread().empty())
    coverage =
        std::make_unique<CoverageTerm>(frame.spreadSamples(), mesh, lengthScale, options.coverage);
  return coverage;
}

// The colour term at the coarse level's kernel, or null when it is off or the frame or the
// vertices' colour reference (`reference`) has no colour.
std::unique_ptr<ColourTerm> colourTerm(const FrameData& frame, const TriangleMesh& mesh,
                                       const ClothEnergy& cloth,
                                       const std::vector<float>& reference,
                                       const TrackerOptions& options, double voxel)
{
  std::unique_ptr<ColourTerm> colour;
  if (options.colourWeight > 0 && frame.colourField() && !reference.empty())
    colour = std::make_unique<ColourTerm>(*frame.colourField(), mesh, reference, cloth.vertexMass(),
                                          options.colourWeight, cloth.lengthScale(), voxel,
                                          frame.colourField()->kernel(options.colourCoarseKernel));
  return colour;
}
} // namespace

void Tracker::startState(Start start, Attempt& a) const
{
  const DeformationGraph& graph = *P->Graph;
  const MotionPredictor& predictor = P->Predictor;
  DeformationGraph::State& state = a.state;
  state = graph.identity();
  if (predictor.empty())
    return;
  if (start == Start::Predicted || start == Start::Stiff)
    predictor.predictState(graph, Options.motionPrediction ? 1.0 : 0.0, state);
  else if (start == Start::Still)
    state = *predictor.lastState();
  else if (start == Start::LastGood)
    state = P->LastGoodState;
  else if (start == Start::Regrown)
    state = P->RegrownState;
  else
  {
    // The template, moved rigidly onto the last shape: every node takes the same motion.
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    rigidFit(Template, predictor.last(), Cloth.vertexMass(), R, t);
    for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
    {
      const Eigen::Vector3d g(graph.nodePosition(j));
      state.rotation[j] = R;
      state.translation[j] = R * g + t - g;
    }
  }
}

void Tracker::preferStraightIfCloser(DistanceTerm& distance, Attempt& a,
                                     std::vector<double>& x) const
{
  // The data decides between a turning and a straight continuation, as the paper's MP decides
  // along the vertices' extrapolations: the distance term, robust at a few voxels so that the
  // parts both starts leave far from the data do not decide.
  DeformationGraph::State straight;
  P->Predictor.predictState(*P->Graph, 1.0, straight, Extrapolation::Straight);
  std::vector<double> y(x.size());
  P->Graph->deform(straight, y.data());
  distance.setRobustScale(StartChoiceScale * Voxel);
  distance.decide(x.data());
  const double turning = distance.evaluate(x.data(), nullptr);
  distance.decide(y.data());
  if (distance.evaluate(y.data(), nullptr) < turning)
  {
    a.state = std::move(straight);
    x.swap(y);
  }
}

Tracker::Attempt Tracker::attempt(const FrameData& frame, Start start, const Attempt* capped)
{
  Attempt a;
  auto clock = std::chrono::steady_clock::now();
  const double L = Cloth.lengthScale();
  DistanceTerm distance(frame, Mesh, Cloth.vertexMass(), L, Options.distance);
  std::unique_ptr<CoverageTerm> coverage = coverageTerm(frame, Mesh, L, Options);
  std::unique_ptr<ColourTerm> colour =
      colourTerm(frame, Mesh, Cloth, P->ColourCoarse, Options, Voxel);
  InternalEnergyTerm internal(Cloth);

  std::vector<double> x;
  if (capped)
  {
    a = *capped; // its start and coarse level; the fine level goes on from where it stopped
    a.solvedOn = true;
    x = capped->positions;
  }
  else
  {
    x = startPositions(start, a, distance, internal);
    a.timings.prediction = elapsed(clock);
    a.startPositions = x;

    clock = std::chrono::steady_clock::now();
    solveCoarse(start, a, distance, coverage.get(), colour.get(), x);
    a.timings.coarse = elapsed(clock);
    a.coarsePositions = x;
  }

  clock = std::chrono::steady_clock::now();
  const int stepsBefore = capped ? capped->iterations : 0;
  if (colour)
    colour->setKernel(frame.colourField()->kernel(), P->ColourFine);
  solveFine(a, distance, coverage.get(), colour.get(), internal, x,
            capped || start != Start::Predicted);
  a.iterations += stepsBefore;
  a.timings.fine = elapsed(clock) + (capped ? capped->timings.fine : 0.0);

  clock = std::chrono::steady_clock::now();
  a.quality = qualityOf(frame, x, a);
  a.timings.quality = elapsed(clock);
  a.positions = std::move(x);
  return a;
}

FrameQuality Tracker::qualityOf(const FrameData& frame, const std::vector<double>& x,
                                const Attempt& a) const
{
  FrameQuality quality =
      assessFrame(frame, Mesh, x.data(), Cloth.vertexMass(), Options.recovery.reach * Voxel,
                  a.startPositions.empty() ? nullptr : a.startPositions.data());
  quality.tear = largestEdgeGrowth(Mesh, Template, x, Cloth.stretchScales());
  return quality;
}

std::vector<double> Tracker::startPositions(Start start, Attempt& a, DistanceTerm& distance,
                                            InternalEnergyTerm& internal) const
{
  const MotionPredictor& predictor = P->Predictor;
  std::vector<double> x;
  if (P->Graph)
  {
    startState(start, a);
    x.resize(Template.size());
    P->Graph->deform(a.state, x.data());
    if ((start == Start::Predicted || start == Start::Stiff) && Options.motionPrediction &&
        predictor.hasMotion())
      preferStraightIfCloser(distance, a, x);
    return x;
  }
  x = predictor.empty() ? Template : start == Start::LastGood ? P->LastGood : predictor.last();
  if (!predictor.empty() && Options.motionPrediction && start == Start::Predicted)
  {
    distance.decide(x.data());
    x = predictor.searchExtrapolations(
        [&](const double* y)
        { return internal.evaluate(y, nullptr) + distance.evaluate(y, nullptr); });
  }
  distance.decide(x.data());
  if (Options.rigidAlignment)
    alignRigidly(x, distance);
  return x;
}

void Tracker::solveCoarse(Start start, Attempt& a, DistanceTerm& distance, CoverageTerm* coverage,
                          ColourTerm* colour, std::vector<double>& x)
{
  if (!P->Graph)
    return;
  const double stiffer = start == Start::Stiff ? Options.recovery.stiffening : 1.0;
  const GraphStiffness stiffness{stiffer * Options.graph.rigidity,
                                 stiffer * stiffer * Options.graph.stretchWeight};
  a.coarseIterations = P->Registration->registerFrame(
      a.state, distance, coverage, stiffness, Options.graph.robustScale * Voxel,
      Options.graph.iterations,
      colour ? std::vector<EnergyTerm*>{colour} : std::vector<EnergyTerm*>{});
  P->Graph->deform(a.state, x.data());
}

void Tracker::solveFine(Attempt& a, DistanceTerm& distance, CoverageTerm* coverage,
                        ColourTerm* colour, InternalEnergyTerm& internal, std::vector<double>& x,
                        bool converge)
{
  const MotionPredictor& predictor = P->Predictor;
  // The fine level starts within reach of the data: the paper's term, not robust (the coarse
  // level left it with its own robust scale).
  distance.setRobustScale(0.0);
  if (coverage)
  {
    coverage->setRobustScale(Options.coverage.robustScale > 0 ? Options.coverage.robustScale
                                                              : FineCoverageScale * Voxel);
    coverage->setMaxDistance(Options.coverage.maxDistance > 0 ? Options.coverage.maxDistance
                                                              : FineCoverageReach * Voxel);
    coverage->searchWholeSurface();
  }
  distance.decide(x.data());
  std::vector<double> target;
  std::unique_ptr<TemporalTerm> temporal;
  if (Options.temporalWeight > 0 && predictor.depth() >= 2)
  {
    target = predictor.constantVelocity();
    temporal = std::make_unique<TemporalTerm>(target, Cloth.vertexMass(), Options.temporalWeight,
                                              Cloth.lengthScale(), Voxel);
  }
  std::vector<EnergyTerm*> terms{&internal, &distance};
  if (coverage)
    terms.push_back(coverage);
  if (temporal)
    terms.push_back(temporal.get());
  if (colour)
    terms.push_back(colour);
  SolveSettings settings;
  settings.maxIterations = Options.maxIterations;
  if (!converge && capsFineLevel())
    settings.maxIterations = Options.graph.fineIterations;
  settings.tolerance = Options.tolerance;
  settings.settledStep = SettledStep * Voxel;
  a.frozen.assign(Mesh.numberOfVertices(), 0);
  a.iterations = P->Fine->solve(x, terms, &distance, settings, a.frozen);
  a.internalEnergy = internal.evaluate(x.data(), nullptr);
  a.distanceEnergy = distance.evaluate(x.data(), nullptr);
  a.rejected.resize(Mesh.numberOfVertices());
  a.residual.resize(Mesh.numberOfVertices());
  for (std::size_t v = 0; v < Mesh.numberOfVertices(); ++v)
  {
    a.rejected[v] = distance.weights()[v] == 0;
    a.residual[v] = distance.sample(&x[3 * v], v).distance;
  }
}

void Tracker::trackEmptyFrame(FrameResult& result)
{
  // Keep moving as before (linear), relaxed by E_int alone; the frame is flagged.
  result.emptyFrame = true;
  std::vector<double> x = P->Predictor.empty() ? Template : P->Predictor.constantVelocity();
  InternalEnergyTerm internal(Cloth);
  const std::vector<EnergyTerm*> terms{&internal};
  SolveSettings settings;
  settings.maxIterations = Options.maxIterations;
  settings.tolerance = Options.tolerance;
  settings.settledStep = SettledStep * Voxel;
  result.iterations = P->Fine->solve(x, terms, nullptr, settings, result.frozen);
  result.internalEnergy = internal.evaluate(x.data(), nullptr);
  result.positions = std::move(x);
}

bool Tracker::capsFineLevel() const
{
  return P->Graph && P->Fine->takesFewStepsAfterCoarseLevel() &&
         Options.graph.fineIterations < Options.maxIterations;
}

Tracker::Attempt Tracker::solveWithRetries(const FrameData& frame, FrameResult& result)
{
  // After the graph, a few fine steps (GraphOptions::fineIterations) unless the frame then
  // fails: there the graph may have missed, and the fine level solved on to convergence mends
  // what it can before other starts are tried.
  Attempt best = attempt(frame, Start::Predicted);
  const RecoveryPolicy& policy = P->Recovery;
  if (Options.recovery.enabled && policy.doubtful(best.quality) && capsFineLevel())
  {
    Attempt converged = attempt(frame, Start::Predicted, &best);
    if (converged.score() < best.score())
      best = std::move(converged);
  }
  int kept = 0;
  if (Options.recovery.enabled && policy.doubtful(best.quality) && !P->Predictor.empty())
  {
    // Held stiffer only where a limb tore: elsewhere (a collapse, a body whose skin stretches)
    // a stiffer coarse level fits the data worse.
    const bool torn = policy.torn(best.quality);
    for (Start retry :
         {Start::Stiff, Start::Regrown, Start::Still, Start::LastGood, Start::Template})
    {
      if ((!P->Graph && retry != Start::Still && retry != Start::LastGood) ||
          (retry == Start::Stiff && !torn) ||
          (retry == Start::LastGood && (!P->LastFailed || P->LastGood.empty())) ||
          (retry == Start::Regrown && !regrowable(frame, best)))
        continue;
      Attempt other = attempt(frame, retry);
      ++result.retries;
      if (policy.prefers(other.quality, best.quality, torn))
      {
        best = std::move(other);
        kept = retry == Start::Stiff ? 2 : 1;
      }
      if (!policy.doubtful(best.quality))
        break;
    }
  }
  result.failed = Options.recovery.enabled && policy.failed(best.quality);
  result.kept = kept;
  P->Recovery.frameKept(best.quality);
  return best;
}

bool Tracker::regrowable(const FrameData& frame, const Attempt& best)
{
  if (!Options.recovery.regrow)
    return false;
  const std::vector<double> moved = regrowLostPart(frame, Mesh, best.positions, best.quality.reach);
  if (moved.empty())
    return false;
  P->RegrownState = P->Graph->fit(moved.data());
  return true;
}

} // namespace dp
