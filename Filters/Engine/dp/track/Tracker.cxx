// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/Tracker.h"

#include "dp/geometry/MeshSurfaceSamples.h"

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/LocalThickness.h"
#include "dp/geometry/SurfaceLocator.h"
#include "dp/support/Parallel.h"
#include "dp/track/ClothRegions.h"
#include "dp/track/ColourTerm.h"
#include "dp/track/CoverageTerm.h"
#include "dp/track/DeformationGraph.h"
#include "dp/track/DistanceTerm.h"
#include "dp/track/FineSolver.h"
#include "dp/track/FrameData.h"
#include "dp/track/FrameOrientation.h"
#include "dp/track/FrameQuality.h"
#include "dp/track/GraphRegistration.h"
#include "dp/track/InternalEnergyTerm.h"
#include "dp/track/MotionPredictor.h"
#include "dp/track/PartRegrowth.h"
#include "dp/track/RecoveryPolicy.h"
#include "dp/track/RigidAlignment.h"
#include "dp/track/Solvers.h"
#include "dp/track/TemporalTerm.h"
#include "dp/track/TrackerOptionTable.h"

#include <Eigen/LU>
#include <Eigen/SVD>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

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

double elapsed(std::chrono::steady_clock::time_point since)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

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
} // namespace

// What the tracker keeps besides the energy: the coarse level, the fine solver (its matrix
// pattern and symbolic analysis live as long as the tracker), the motion history.
struct Tracker::Parts
{
  explicit Parts(const RecoveryOptions& recovery) : Recovery(recovery) {}
  std::unique_ptr<DeformationGraph> Graph;
  std::unique_ptr<GraphRegistration> Registration;
  std::unique_ptr<FineSolver> Fine;
  MotionPredictor Predictor;
  // The take's usual quality and whether the last frame is in doubt: a frame in doubt sets no
  // baseline, no reference and no retry's start, whether or not it was flagged.
  RecoveryPolicy Recovery;
  // The last frame that did not fail, while the frames after it fail: a retry starts there.
  std::vector<double> LastGood;
  DeformationGraph::State LastGoodState;
  bool LastFailed = false;
  DeformationGraph::State RegrownState; // Start::Regrown's, set before its try

  // Each vertex's colour in the first frame with colour (where the template lies on its
  // material), read at the colour term's fine and coarse kernels; empty until then.
  std::vector<float> ColourFine, ColourCoarse;
  std::vector<float> LastColours; // the vertices' colours in the last frame (a hole keeps them)
};

// One way of solving a frame, and how well it did.
struct Tracker::Attempt
{
  std::vector<double> positions, startPositions, coarsePositions;
  DeformationGraph::State state;
  FrameQuality quality;
  int iterations = 0, coarseIterations = 0;
  bool solvedOn = false; // the fine level went on from a capped try that failed
  std::vector<std::uint8_t> frozen, rejected;
  std::vector<double> residual;
  double internalEnergy = 0, distanceEnergy = 0;
  FrameTimings timings;
  double score() const { return RecoveryPolicy::score(quality); }
};

namespace
{
// Checked before E_int measures the template (a NaN would only say "no area").
std::vector<double> finiteTemplate(std::vector<double> positions)
{
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (!std::isfinite(positions[i]))
      throw std::invalid_argument("the template mesh's vertex " + std::to_string(i / 3) +
                                  " has a NaN or infinite coordinate");
  return positions;
}

// Too little data to say where a surface is: fewer than a handful of points, or all of them
// within a couple of voxels. (NaN coordinates are left for FrameData's error.)
bool tooLittleData(const double* points, std::size_t count, double voxel)
{
  return count < 10 || boundingBoxDiagonal(points, count) < 2 * voxel;
}
} // namespace

Tracker::Tracker(TriangleMesh mesh, std::vector<double> templatePositions,
                 const TrackerOptions& options)
    : Mesh(std::move(mesh)), Template(finiteTemplate(std::move(templatePositions))),
      Options(options), Cloth(Mesh, Template.data(), options.cloth),
      P(std::make_unique<Parts>(options.recovery))
{
  checkTrackerOptions(options);
  TemplateRest = Cloth.restState();
  softenByRegion(Cloth, Mesh, Template.data(), options.softening, options.creases);
  Voxel = options.voxelSize > 0 ? options.voxelSize : boundingBoxDiagonal(Template) / 200.0;
  P->Fine = FineSolver::make(options, Mesh, Cloth.lengthScale());
  if (options.graph.enabled)
  {
    const std::size_t nodes = options.graph.nodes > 0
                                  ? options.graph.nodes
                                  : std::clamp<std::size_t>(Mesh.numberOfVertices() / 5, 30, 600);
    P->Graph = std::make_unique<DeformationGraph>(
        Mesh, Template.data(), nodes, std::max<std::size_t>(1, options.graph.influences));
    P->Registration = std::make_unique<GraphRegistration>(*P->Graph, Cloth.lengthScale(), Voxel);
    P->Registration->setAcceleration(options.graph.acceleration);
  }
}

Tracker::~Tracker() = default;

void Tracker::readColourReference(const FrameData& frame, const std::vector<double>& positions)
{
  if (!P->ColourFine.empty() || !frame.colourField() || Options.colourWeight <= 0)
    return;
  const ColourField& field = *frame.colourField();
  const std::size_t nv = Mesh.numberOfVertices();
  P->ColourFine = vertexColours(field, positions.data(), nv, field.kernel());
  P->ColourCoarse =
      vertexColours(field, positions.data(), nv, field.kernel(Options.colourCoarseKernel));
}

void Tracker::readVertexColours(const FrameData* frame, FrameResult& result)
{
  if (frame && frame->colourField())
  {
    const ColourField& field = *frame->colourField();
    P->LastColours = vertexColours(field, result.positions.data(), Mesh.numberOfVertices(),
                                   field.kernel(), &P->LastColours);
  }
  result.colours.clear();
  for (float c : P->LastColours)
    result.colours.push_back(
        static_cast<std::uint8_t>(std::lround(255 * std::clamp(c < 0 ? 0.5f : c, 0.0f, 1.0f))));
}

void Tracker::reset()
{
  P->ColourFine.clear();
  P->ColourCoarse.clear();
  P->LastColours.clear();
  P->Predictor.clear();
  P->Recovery.reset();
  P->LastGood.clear();
  P->LastFailed = false;
  if (P->Registration)
    P->Registration->resetReference();
}

void Tracker::restartFrom(const std::vector<double>& positions)
{
  if (P->Graph)
  {
    const DeformationGraph::State state = P->Graph->fit(positions.data());
    P->Predictor.restartFrom(positions, &state);
  }
  else
    P->Predictor.restartFrom(positions);
}

void Tracker::orientData(FrameData& frame) const
{
  orientToShape(frame, Mesh, P->Predictor.empty() ? Template : P->Predictor.last(), Voxel);
}

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
  std::unique_ptr<CoverageTerm> coverage;
  if (Options.coverage.weight > 0 && !frame.spread().empty())
    coverage = std::make_unique<CoverageTerm>(frame.spreadSamples(), Mesh, L, Options.coverage);
  std::unique_ptr<ColourTerm> colour;
  if (Options.colourWeight > 0 && frame.colourField() && !P->ColourCoarse.empty())
    colour = std::make_unique<ColourTerm>(*frame.colourField(), Mesh, P->ColourCoarse,
                                          Cloth.vertexMass(), Options.colourWeight, L, Voxel,
                                          frame.colourField()->kernel(Options.colourCoarseKernel));
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
  a.quality = assessFrame(frame, Mesh, x.data(), Cloth.vertexMass(), Options.recovery.reach * Voxel,
                          a.startPositions.empty() ? nullptr : a.startPositions.data());
  a.quality.tear = largestEdgeGrowth(Mesh, Template, x, Cloth.stretchScales());
  a.timings.quality = elapsed(clock);
  a.positions = std::move(x);
  return a;
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

void Tracker::keep(Attempt&& best, FrameResult& result)
{
  result.startPositions = best.startPositions;
  result.coarsePositions = best.coarsePositions;
  result.positions = std::move(best.positions);
  result.residual = std::move(best.residual);
  result.rejected = std::move(best.rejected);
  result.frozen = std::move(best.frozen);
  result.iterations = best.iterations;
  result.solvedOn = best.solvedOn;
  result.coarseIterations = best.coarseIterations;
  result.internalEnergy = best.internalEnergy;
  result.distanceEnergy = best.distanceEnergy;
  result.unexplained = best.quality.unexplained;
  result.unsupported = best.quality.unsupported;
  result.tear = best.quality.tear;
  result.noise = best.quality.noise;
  result.timings.prediction = best.timings.prediction;
  result.timings.coarse = best.timings.coarse;
  result.timings.fine = best.timings.fine;
  result.timings.quality = best.timings.quality;
}

void Tracker::remember(const FrameResult& result)
{
  if (P->Graph)
  {
    const DeformationGraph::State state = P->Graph->fit(result.positions.data());
    // After a retry from another start, the motion before it says nothing about the motion after.
    if (result.kept == 1)
      P->Predictor.restartFrom(result.positions, &state);
    else
      P->Predictor.push(result.positions, &state);
    // A failed frame's shape may be garbage (a frame a thousand times too large): the graph's
    // reference gives way to it only once failures persist, when the take itself has changed
    // (as the quality's baseline does).
    if (Options.graph.yieldRate > 0 && P->Recovery.referencesFollow())
      P->Registration->yield(state, Options.graph.yieldRate, Options.graph.yieldLimit * Voxel);
    if (!P->Recovery.inDoubt())
      P->LastGoodState = state;
  }
  else if (result.kept == 1)
    P->Predictor.restartFrom(result.positions);
  else
    P->Predictor.push(result.positions);
  if (!P->Recovery.inDoubt())
    P->LastGood = result.positions;
  P->LastFailed = P->Recovery.inDoubt();
}

PreparedFrame::PreparedFrame() = default;
PreparedFrame::PreparedFrame(PreparedFrame&&) noexcept = default;
PreparedFrame& PreparedFrame::operator=(PreparedFrame&&) noexcept = default;
PreparedFrame::~PreparedFrame() = default;

PreparedFrame Tracker::prepare(const double* points, std::size_t count, const float* normals,
                               const std::uint8_t* colours, int colourComponents) const
{
  const auto start = std::chrono::steady_clock::now();
  FrameDataOptions dataOptions;
  dataOptions.voxelSize = Voxel;
  dataOptions.bandWidth = Options.bandWidth;
  dataOptions.surfaceArea = Cloth.lengthScale() * Cloth.lengthScale();
  const std::size_t nv = Mesh.numberOfVertices();
  dataOptions.spreadCount = Options.coverage.weight > 0 || Options.recovery.enabled
                                ? (Options.coverage.points > 0 ? Options.coverage.points : 4 * nv)
                                : 0;
  dataOptions.maxPoints = Options.maxFramePoints;
  // Point indices are 32-bit: beyond that a frame must be thinned.
  if (Options.maxFramePoints == 0 && count > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("a frame of " + std::to_string(count) +
                                " points is more than the tracker can index (2^32 - 1): set a "
                                "frame point limit (maxFramePoints) to thin it");
  PreparedFrame frame;
  frame.Count = count;
  frame.Owner = this;
  // A frame with too little data is kept like an empty one (the motion continued) and flagged:
  // fitting the mesh to a point or two would crush it.
  if (count == 0 || !tooLittleData(points, count, Voxel))
    frame.Data =
        std::make_unique<FrameData>(points, count, normals, colours, colourComponents, dataOptions);
  frame.Seconds = elapsed(start);
  return frame;
}

PreparedFrame Tracker::prepare(const MeshSurface& frame) const
{
  if (Options.meshFrameSamples == 0 || frame.triangleCount == 0)
    return prepare(frame.positions, frame.vertices, nullptr,
                   frame.colourComponents ? frame.colours : nullptr, frame.colourComponents);
  const auto start = std::chrono::steady_clock::now();
  const PointCloud samples =
      sampleMeshSurface(frame, std::max(Options.meshFrameSamples, frame.vertices));
  const double sampling = elapsed(start);
  PreparedFrame prepared = prepare(samples.points.data(), samples.numberOfPoints(),
                                   samples.normals.empty() ? nullptr : samples.normals.data(),
                                   samples.hasColors() ? samples.colors.data() : nullptr, 3);
  prepared.Seconds += sampling;
  prepared.Count = frame.vertices; // what the frame gave; pointsUsed counts the samples read
  return prepared;
}

FrameResult Tracker::track(const double* points, std::size_t count, const float* normals)
{
  return track(prepare(points, count, normals));
}

FrameResult Tracker::track(PreparedFrame prepared)
{
  // Its field's voxel and subsample are this tracker's settings.
  if (prepared.Owner != this)
    throw std::invalid_argument("a frame prepared by another tracker, or by none (use this "
                                "tracker's prepare())");
  const auto start = std::chrono::steady_clock::now();
  const std::size_t nv = Mesh.numberOfVertices();
  FrameResult result;
  result.frozen.assign(nv, 0);
  result.rejected.assign(nv, 0);
  result.residual.assign(nv, -1.0);
  P->Recovery.frameBegins();

  if (Options.restUpdate > 0)
    Cloth.setRestState(P->Predictor.empty()
                           ? TemplateRest
                           : ClothRestState::blend(TemplateRest,
                                                   Cloth.restStateOf(P->Predictor.last().data()),
                                                   Options.restUpdate));

  result.pointsGiven = prepared.Count;
  if (!prepared.Data)
  {
    trackEmptyFrame(result);
    result.failed = true;
    P->Recovery.frameWithoutData();
    readVertexColours(nullptr, result);
  }
  else
  {
    auto clock = std::chrono::steady_clock::now();
    FrameData& frame = *prepared.Data;
    result.pointsUsed = frame.size();
    result.thinned = frame.size() < frame.originalSize();
    orientData(frame);
    result.timings.data = prepared.Seconds + elapsed(clock);
    if (frame.empty())
      trackEmptyFrame(result);
    else
    {
      keep(solveWithRetries(frame, result), result);
      result.samples = frame.copySamples();
      readColourReference(frame, result.positions);
    }
    readVertexColours(&frame, result);
  }
  remember(result);
  result.seconds = prepared.Seconds + elapsed(start);
  return result;
}

} // namespace dp
