// SPDX-License-Identifier: BSD-3-Clause
// Benchmark: the tracker on ground-truth animated meshes, the way users meet it. Every sequence is
// brought to a height of 1.70 m (its largest extent; --height), and each frame's data are random
// surface samples (20 000 by default) without normals, clean or with noise and holes that move
// every frame. Templates of about --vertices vertices are decimated from the true frame 0 or
// reconstructed from frame 0's samples (what the filter does without a template), or frame 0
// itself (--vertices 0). The ground truth of a template vertex is the barycentric position of its
// closest point on the frame-0 mesh, carried through the frames.
//
// Printed per sequence, template and data condition, over all frames: vertex RMS and largest
// vertex error against the true trajectories (mm and % of the diagonal), RMS distance of the
// tracked vertices to the true surface, the share of the true surface farther than 3 cm from the
// tracked surface (lost parts: mean and worst frame), jitter (RMS acceleration of the tracked
// vertices over the true vertices'), ms per frame and per stage, and the coarse and fine steps a
// frame (deterministic, unlike the times); the mesh's shape in its worst frame (edges folded over
// 120 degrees, stretched beyond 2 and torn beyond 3 times their template length); frames flagged
// against frames that lost a part. With --rig, the same where the data see: the vertices whose
// truth lies within 15 mm of a data point (their RMS error: what one view can tell) and the parts
// lost of the true surface the data see. Also: the paper's Table 2 ablation, the
// scaling with the vertex count (the paper's Fig. 4), oracle starts for diagnosis.
#include "BenchmarkSequences.h"
#include "BenchmarkUtilities.h"
#include "CommandLine.h"
#include "FrameOutputs.h"
#include "OptionFlags.h"
#include "PerFrameMesh.h"
#include "ScalingTable.h"
#include "TakeFigures.h"
#include "TakeMeasures.h"
#include "TrackingTruth.h"

#include "dp/compress/ColourStream.h"
#include "dp/compress/PcaCompression.h"
#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/DepthRig.h"
#include "dp/geometry/MeshSurfaceSamples.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/io/PointCloudIO.h"
#include "dp/track/ColourTerm.h"
#include "dp/track/Tracker.h"

#include <Eigen/Dense>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <iostream>
#include <memory>
#include <numeric>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace
{
using namespace dp::bench;

struct Settings
{
  std::size_t points = 20000;
  std::uint64_t seed = 1;    // which random samples (and holes) the frames get
  double noise = 0.001;      // "noisy" condition: Gaussian noise per coordinate (m)
  std::size_t holes = 2;     // "noisy" condition: holes per frame, new places every frame
  double holeRadius = 0.05;  // m
  bool givenNormals = false; // pass the true normals to the tracker (else it estimates them)
  bool pipeline = true;      // prepare frame f + 1's data while frame f is tracked (main job)
  double uncoveredLimit = 0.03;
  std::size_t truthSamples = 20000; // samples of the true surface for the uncovered share
  bool verbose = false;
  std::string
      oracle; // "previous": start each frame at the true previous frame; "same": at the truth
  std::string dumpFolder; // write the tracked frames (PLY) here
  // The first frame tracked: the template (frame 0's shape) registered straight to it, as a
  // chunk of a long sequence tracked on its own would start (Documentation/MainJob.md).
  std::size_t startFrame = 0;
  std::string csvFile; // per-frame figures
  bool colour = false; // the samples carry a colour fixed to the material (the tracker gets it)
  int colourTolerance = dp::CompressionOptions{}.colourTolerance; // of the stored colour swim
  std::vector<double> colourRest; // the sequence's first frame: where the colour pattern lies
  bool compress = false;          // the compression of the take beside the true motion's
  dp::ReconstructionOptions reconstruction; // of reconstructed templates (count set per run)
  // Each frame given as a mesh of about this many vertices reconstructed from its points, with
  // a capture's defects in frame 0 (dynamicpoints-sample --per-frame-mesh); 0: the points.
  std::size_t perFrameMesh = 0;
  // Each frame given as its true mesh (the sequence's own connectivity): a capture without
  // error, to tell what reading a mesh costs from what a capture mesh's error costs.
  bool trueMeshes = false;
  // Each frame seen by this many simulated depth cameras (dynamicpoints-sample --rig): their
  // fused cloud, or with `depthMesh` camera 0's depth image as an open mesh (a single sensor).
  std::size_t rig = 0;
  std::string sensor = "kinect-v2";
  std::size_t rigPoints = 0; // the fused cloud thinned to about this many (0: all)
  bool depthMesh = false;
  double azimuth = 0;
  // A frame whose true surface is left uncovered more than this beyond the first frame's share
  // (farther than the uncovered limit from the tracked one) has lost a part: a flag there is
  // right, a flag elsewhere false.
  double lostShare = 0.01;
};
Settings S;

// The rig around a sequence (made once: its cameras stand where the whole take fills them).
const dp::DepthRig& rigFor(const dp::AnimatedMesh& mesh)
{
  static const dp::AnimatedMesh* made = nullptr;
  static std::unique_ptr<dp::DepthRig> rig;
  if (made != &mesh || !rig)
  {
    dp::RigOptions o;
    o.cameras = S.rig;
    o.sensor = S.sensor;
    o.seed = S.seed;
    o.azimuth = S.azimuth;
    o.points = S.rigPoints;
    // The sequences are in metres (--height): the subject's extent along y is its height.
    const std::vector<double> p = mesh.positions(0);
    double low = 1e300, high = -1e300;
    for (std::size_t v = 1; v < p.size(); v += 3)
      low = std::min(low, p[v]), high = std::max(high, p[v]);
    o.subjectHeight = high - low;
    rig = std::make_unique<dp::DepthRig>(mesh, o);
    made = &mesh;
  }
  return *rig;
}

struct Condition
{
  std::string name;
  bool noisy = false;
};

dp::SamplerOptions samplingFor(const Condition& c, std::size_t points)
{
  dp::SamplerOptions o;
  o.pointsPerFrame = points;
  o.seed = S.seed;
  o.normals = S.givenNormals;
  o.colours = S.colour;
  o.colourRest = &S.colourRest;
  if (c.noisy)
  {
    o.noiseStdDev = S.noise;
    o.holes = S.holes;
    o.holeRadius = S.holeRadius;
    o.holesMove = true;
  }
  return o;
}

// The data of frame f as the tracker is given it: the sampled points, or with --per-frame-mesh a
// mesh reconstructed from them as a capture studio publishes it (with defects in frame 0).
dp::PointCloud frameData(const dp::AnimatedMesh& mesh, const dp::SamplerOptions& sampling,
                         std::size_t f)
{
  if (S.trueMeshes)
  {
    dp::PointCloud truth;
    truth.points = mesh.positions(f);
    for (std::size_t t = 0; t < mesh.triangles().size(); t += 3)
      truth.addFace(&mesh.triangles()[t], 3);
    return truth;
  }
  if (S.rig > 0)
    return S.depthMesh ? rigFor(mesh).depthMesh(mesh.positions(f), 0, f)
                       : rigFor(mesh).fusedCloud(mesh.positions(f), f);
  dp::PointCloud cloud = dp::sampleSurface(mesh.positions(f), mesh.triangles(), sampling, f);
  return S.perFrameMesh ? dp::cli::perFrameMesh(cloud, S.perFrameMesh, f == 0) : cloud;
}

// Feeds a tracker its frames as the main job does (vtkDeformableTrackFilter): frame f + 1's data
// is prepared on another thread while frame f is tracked, and a frame's time is the wall time of
// that cycle (tracking it and preparing the next, whichever ends last). --no-pipeline: each frame
// prepared, then tracked.
class FramePipeline
{
public:
  explicit FramePipeline(dp::Tracker& tracker) : Tracker(tracker) {}

  // Tracks `cloud` (prepared already when it was the last call's `next`) while `next` (null:
  // none) is prepared; `seconds` gets the cycle's wall time.
  dp::FrameResult track(const dp::PointCloud& cloud, const dp::PointCloud* next, double& seconds)
  {
    const auto cycle = std::chrono::steady_clock::now();
    if (!Ready)
      Ready = prepare(cloud);
    std::future<dp::PreparedFrame> preparing;
    if (S.pipeline && next)
      preparing = std::async(std::launch::async, [this, next] { return prepare(*next); });
    const dp::FrameResult r = Tracker.track(std::move(*Ready));
    Ready.reset();
    if (preparing.valid())
      Ready = preparing.get();
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - cycle).count();
    return r;
  }

private:
  dp::PreparedFrame prepare(const dp::PointCloud& c) const
  {
    if (c.numberOfFaces() > 0)
    {
      const std::vector<std::int64_t> triangles = dp::triangleFans(c);
      return Tracker.prepare(dp::meshSurfaceOf(c, triangles));
    }
    return Tracker.prepare(c.points.data(), c.numberOfPoints(),
                           c.hasNormals() ? c.normals.data() : nullptr,
                           c.hasColors() ? c.colors.data() : nullptr, c.colorComponents);
  }

  dp::Tracker& Tracker;
  std::optional<dp::PreparedFrame> Ready;
};

// --verbose: one line a frame.
void printFrame(std::size_t f, const dp::FrameResult& r, const std::vector<double>& positions,
                const FrameFigures& figures, const std::vector<double>& truth)
{
  const double nv = static_cast<double>(truth.size() / 3);
  std::printf(
      "  frame %3zu: rigid-free %5.1f vertex RMS %6.1f mm (start %6.1f coarse %6.1f), largest "
      "%6.1f mm, surface RMS %5.1f mm, "
      "uncovered %5.2f%%, %3d+%d iterations, %6.1f ms, unexplained %.3f unsupported %.3f, "
      "retries %d (kept: %s)%s; seen RMS %.1f mm, uncovered seen %.2f%%, folded %.2f%% torn "
      "%.2f%%\n",
      f, rigidFreeRms(positions, truth), 1e3 * std::sqrt(figures.vertexSquaredSum / nv),
      rmsAgainst(r.startPositions, truth), rmsAgainst(r.coarsePositions, truth),
      1e3 * figures.largestVertexError, 1e3 * std::sqrt(figures.surfaceSquaredSum / nv),
      100 * figures.uncovered, r.coarseIterations, r.iterations, 1e3 * r.seconds, r.unexplained,
      r.unsupported, r.retries,
      r.kept == 0   ? "predicted"
      : r.kept == 1 ? "another start"
                    : "stiff",
      r.failed ? " FAILED" : "",
      figures.seenVertices
          ? 1e3 * std::sqrt(figures.seenSquaredSum / static_cast<double>(figures.seenVertices))
          : 0.0,
      100 * figures.uncoveredSeen, 100 * figures.folded, 100 * figures.torn);
}

// --colour: the colour each vertex carries (FrameResult::colours) against the true colour of its
// material point (the sampler's pattern at its truth's rest position); and the frame's colour
// field (as the tracker reads it) at the true positions, which shows what the field's blur
// leaves.
class ColourSwim
{
public:
  ColourSwim(const Template& t, const dp::AnimatedMesh& mesh, const Condition& condition,
             double area, double voxel)
      : Mesh(mesh), Sampled(condition), Area(area), Voxel(voxel)
  {
    if (!S.colour)
      return;
    const std::vector<double> rest = groundTruth(t, S.colourRest, mesh.triangles());
    const double diagonal = dp::boundingBoxDiagonal(S.colourRest);
    for (std::size_t v = 0; v < rest.size(); v += 3)
    {
      double rgb[3];
      dp::materialColour(&rest[v], diagonal, rgb);
      True.insert(True.end(), {rgb[0], rgb[1], rgb[2]});
    }
  }
  void add(const dp::FrameResult& r, const std::vector<double>& truth, std::size_t frame)
  {
    if (True.empty() || r.colours.size() != True.size())
      return;
    TrackedSum += squared(scaled(r.colours), TrackedCount);
    dp::holdColours(Held, r.colours, S.colourTolerance);
    StoredSum += squared(scaled(Held), StoredCount);
    const dp::PointCloud cloud = dp::sampleSurface(Mesh.positions(frame), Mesh.triangles(),
                                                   samplingFor(Sampled, S.points), frame);
    std::vector<float> colours(cloud.colors.begin(), cloud.colors.end());
    for (float& c : colours)
      c /= 255.0f;
    const std::size_t n = cloud.numberOfPoints();
    const dp::ColourField field(cloud.points.data(), colours.data(), n,
                                std::sqrt(Area / static_cast<double>(n)), Voxel);
    AtTruth = dp::vertexColours(field, truth.data(), truth.size() / 3, field.kernel(), &AtTruth);
    TruthSum += squared(AtTruth, TruthCount);
  }
  double tracked() const { return TrackedCount ? 255 * std::sqrt(TrackedSum / TrackedCount) : -1; }
  double truth() const { return TruthCount ? 255 * std::sqrt(TruthSum / TruthCount) : -1; }
  double stored() const { return StoredCount ? 255 * std::sqrt(StoredSum / StoredCount) : -1; }

private:
  static std::vector<float> scaled(const std::vector<std::uint8_t>& bytes)
  {
    std::vector<float> colours(bytes.begin(), bytes.end());
    for (float& c : colours)
      c /= 255.0f;
    return colours;
  }
  double squared(const std::vector<float>& colours, double& count) const
  {
    double sum = 0;
    for (std::size_t v = 0; v < colours.size(); v += 3)
    {
      if (colours[v] < 0)
        continue;
      for (int c = 0; c < 3; ++c)
        sum += (colours[v + c] - True[v + c]) * (colours[v + c] - True[v + c]);
      count += 1;
    }
    return sum;
  }
  const dp::AnimatedMesh& Mesh;
  Condition Sampled;
  double Area, Voxel;
  std::vector<double> True;
  std::vector<float> AtTruth;
  std::vector<std::uint8_t> Held; // the colours a .dpz stores (setColours' hold)
  double TrackedSum = 0, TruthSum = 0, TrackedCount = 0, TruthCount = 0;
  double StoredSum = 0, StoredCount = 0;
};

// A take tracked: each frame's result, and the wall time of its cycle.
struct TrackedTake
{
  std::size_t first = 0; // the first frame tracked (--start-frame)
  std::vector<dp::FrameResult> results;
  std::vector<double> cycleSeconds;
  // --per-frame-mesh: each input mesh's D1 mean squared error against the true surface.
  std::vector<double> inputMeshD1;

  std::vector<const dp::FrameSamples*> samples() const
  {
    std::vector<const dp::FrameSamples*> all;
    for (const dp::FrameResult& r : results)
      all.push_back(&r.samples);
    return all;
  }
};

// The forward pass over frames first.. (the oracle's restarts included).
TrackedTake trackForward(dp::Tracker& tracker, const dp::AnimatedMesh& mesh, const Template& t,
                         const Condition& condition, std::size_t frames)
{
  const dp::SamplerOptions sampling = samplingFor(condition, S.points);
  FramePipeline pipeline(tracker);
  TrackedTake take;
  take.first = std::min(S.startFrame, frames - 1);
  dp::PointCloud cloud = frameData(mesh, sampling, take.first);
  for (std::size_t f = take.first; f < frames; ++f)
  {
    const dp::PointCloud next =
        f + 1 < frames ? frameData(mesh, sampling, f + 1) : dp::PointCloud{};
    if (S.oracle == "previous" && f > 0)
      tracker.restartFrom(groundTruth(t, mesh.positions(f - 1), mesh.triangles()));
    else if (S.oracle == "same")
      tracker.restartFrom(groundTruth(t, mesh.positions(f), mesh.triangles()));
    if (cloud.numberOfFaces() > 0)
      take.inputMeshD1.push_back(inputMeshError(mesh, f, cloud));
    double seconds = 0;
    take.results.push_back(pipeline.track(cloud, f + 1 < frames ? &next : nullptr, seconds));
    take.cycleSeconds.push_back(seconds);
    cloud = next;
  }
  return take;
}

// The take's figures against the truth; with `report`, the per-frame lines, CSV rows and dumps
// too.
Run evaluate(const dp::AnimatedMesh& mesh, const Template& t, const dp::Tracker& tracker,
             const Condition& condition, const TrackedTake& take, bool report, std::ostream* csv,
             const std::string& label)
{
  dp::SamplerOptions truthSampling;
  truthSampling.pointsPerFrame = S.truthSamples;
  truthSampling.seed = S.seed + 1000003; // other points than the data's
  truthSampling.normals = false;
  RunSums sums;
  const double area = std::pow(tracker.clothEnergy().lengthScale(), 2);
  ColourSwim swim(t, mesh, condition, area, tracker.voxelSize());
  for (std::size_t i = 0; i < take.results.size(); ++i)
  {
    const std::size_t f = take.first + i;
    const dp::FrameResult& r = take.results[i];
    const std::vector<double>& x = r.positions;
    const std::vector<double> truthMesh = mesh.positions(f);
    const std::vector<double> truth = groundTruth(t, truthMesh, mesh.triangles());
    const dp::PointCloud truthCloud =
        dp::sampleSurface(truthMesh, mesh.triangles(), truthSampling, f);
    FrameFigures figures =
        compareFrame(x, t.triangles, truth, groundTruthNormals(t, truthMesh, mesh.triangles()),
                     truthMesh, mesh.triangles(), truthCloud.points, S.uncoveredLimit);
    addMeshShape(x, t.positions, t.triangles, figures);
    // The frame's data again (a rig renders it), once, where the seen figures or a dump need it.
    const bool dump = report && !S.dumpFolder.empty();
    const dp::PointCloud data =
        S.rig > 0 || dump ? frameData(mesh, samplingFor(condition, S.points), f) : dp::PointCloud{};
    if (S.rig > 0)
      addSeenFigures(x, t.triangles, truth, truthCloud.points, data.points, S.uncoveredLimit / 2,
                     S.uncoveredLimit, figures);
    sums.add(f, r, x, figures, truth, take.cycleSeconds[i], S.lostShare);
    swim.add(r, truth, f);
    if (report && S.verbose)
      printFrame(f, r, x, figures, truth);
    if (report && csv)
      writeCsvRow(*csv, label, f, r, figures, static_cast<double>(t.vertices()));
    if (dump)
      dumpFrame(S.dumpFolder + "/" + label, f, x, truth, t.triangles, data);
  }
  Run run = sums.finish(t.vertices());
  run.colourSwim = swim.tracked();
  run.truthColourSwim = swim.truth();
  run.storedColourSwim = swim.stored();
  return run;
}

Run track(const dp::AnimatedMesh& mesh, const Template& t, const dp::TrackerOptions& options,
          const Condition& condition, std::size_t frames, std::ostream* csv,
          const std::string& label)
{
  dp::Tracker tracker(dp::TriangleMesh(t.triangles, t.vertices()), t.positions, options);
  return evaluate(mesh, t, tracker, condition, trackForward(tracker, mesh, t, condition, frames),
                  true, csv, label);
}

// For a two-valued option: false for `first`, true for `second`, a usage error otherwise.
bool oneOf(const std::string& option, const std::string& value, const char* first,
           const char* second)
{
  if (value != first && value != second)
    throw dp::cli::UsageError(option + " wants " + first + " or " + second + ", not '" + value +
                              "'");
  return value == second;
}

const char* solverName(dp::TrackerSolver s)
{
  return s == dp::TrackerSolver::GaussNewton ? "Gauss-Newton"
         : s == dp::TrackerSolver::LBFGS     ? "L-BFGS"
                                             : "steepest descent";
}

const char* Usage =
    "Usage: BenchmarkTracker [--data DIR] [--sequence NAME[,NAME...]|tube] [--frames N]\n"
    "  data:      [--height M (0: as stored)] [--points N] [--seed S] [--condition clean,noisy]\n"
    "             [--noise MM] [--holes N] [--hole-radius MM] [--given-normals]\n"
    "             [--per-frame-mesh N (each frame a mesh of about N vertices reconstructed\n"
    "             from its points, with a capture's defects in frame 0)] [--true-meshes (each\n"
    "             frame its true mesh)] [--rig N (each frame seen by N simulated depth\n"
    "             cameras, fused)] [--sensor NAME] [--depth-mesh (camera 0's open mesh)]\n"
    "             [--rig-points N (the fused cloud thinned to about N)]\n"
    "             [--azimuth DEG (camera 0's side)] [--lost-share S (a frame leaving this\n"
    "             much more of its true surface uncovered than the first frame has lost a\n"
    "             part; default 0.01)]\n"
    "  templates: [--template decimated,reconstructed] [--vertices N[,N...] (0: full)]\n"
    "             [--reconstruction-voxel MM (0: 1.5 point spacings)] [--hole-reach SHARE]\n"
    "  tracker:   [--set NAME=VALUE (repeatable; every option of dp::TrackerOptionTable,\n"
    "             listed by dynamicpoints --describe-options markdown)] [--options FILE.json]\n"
    "             [--no-pipeline (frames prepared one after the other)]\n"
    "  output:    [--verbose] [--csv FILE] [--dump DIR] [--oracle previous|same]\n"
    "             [--start-frame K (track frames K.. from the template, as a chunk would)]\n"
    "  take:      [--colour (a colour fixed to the material; colour swim printed)]\n"
    "             [--colour-tolerance L (the stored colours' hold, as the codec's)]\n"
    "             [--compress (beside the true motion's)]\n"
    "  other:     [--ablation] [--scaling] [--scaling-sizes N,N,...]\n";

// What to run: the sequences, templates and conditions of the table, and the tracker's options.
struct Plan
{
  std::string data = "../shared/data";
  std::vector<std::string> sequences = {"jumping", "horse-gallop", "horse-collapse"};
  std::vector<std::size_t> sizes = {1000};
  std::vector<TemplateKind> kinds = {TemplateKind::Decimated, TemplateKind::Reconstructed};
  std::vector<Condition> conditions = {{"clean", false}, {"noisy", true}};
  std::size_t frames = 0; // 0: all
  double height = 1.70;
  bool ablation = false, scaling = false;
  dp::TrackerOptions options;
};

// The option parsers below each take the option at argv[i] when it is theirs (true), reading its
// value (i moves past it), and throw dp::cli::UsageError for a bad value.

// The data and the templates.
bool parseDataOption(const std::string& arg, int argc, char** argv, int& i, Plan& plan)
{
  using namespace dp::cli;
  if (arg == "--data")
    plan.data = optionValue(argc, argv, i);
  else if (arg == "--sequence")
    plan.sequences = splitList(optionValue(argc, argv, i));
  else if (arg == "--frames")
    plan.frames = parseCount(arg, optionValue(argc, argv, i), 1, 100000);
  else if (arg == "--height")
    plan.height = parseDouble(arg, optionValue(argc, argv, i), 0, 1e6);
  else if (arg == "--points")
    S.points = parseCount(arg, optionValue(argc, argv, i), 1, 10000000);
  else if (arg == "--seed")
    S.seed = parseCount(arg, optionValue(argc, argv, i), 0, 1000000000);
  else if (arg == "--condition")
  {
    plan.conditions.clear();
    for (const std::string& c : splitList(optionValue(argc, argv, i)))
      plan.conditions.push_back({c, oneOf(arg, c, "clean", "noisy")});
  }
  else if (arg == "--noise")
    S.noise = 1e-3 * parseDouble(arg, optionValue(argc, argv, i), 0, 1e6);
  else if (arg == "--holes")
    S.holes = parseCount(arg, optionValue(argc, argv, i), 0, 1000);
  else if (arg == "--hole-radius")
    S.holeRadius = 1e-3 * parseDouble(arg, optionValue(argc, argv, i), 0, 1e6);
  else if (arg == "--given-normals")
    S.givenNormals = true;
  else if (arg == "--per-frame-mesh")
    S.perFrameMesh = parseCount(arg, optionValue(argc, argv, i), 20, 10000000);
  else if (arg == "--true-meshes")
    S.trueMeshes = true;
  else if (arg == "--rig")
    S.rig = parseCount(arg, optionValue(argc, argv, i), 1, 64);
  else if (arg == "--sensor")
    S.sensor = optionValue(argc, argv, i);
  else if (arg == "--depth-mesh")
    S.depthMesh = true;
  else if (arg == "--rig-points")
    S.rigPoints = parseCount(arg, optionValue(argc, argv, i), 100, 100000000);
  else if (arg == "--azimuth")
    S.azimuth = parseDouble(arg, optionValue(argc, argv, i), -360, 360);
  else if (arg == "--lost-share")
    S.lostShare = parseDouble(arg, optionValue(argc, argv, i), 0, 1);
  else if (arg == "--template")
  {
    plan.kinds.clear();
    for (const std::string& k : splitList(optionValue(argc, argv, i)))
      plan.kinds.push_back(
          oneOf(arg, k == "simplified" ? "decimated" : k, "decimated", "reconstructed")
              ? TemplateKind::Reconstructed
              : TemplateKind::Decimated);
  }
  else if (arg == "--vertices")
  {
    plan.sizes.clear();
    for (const std::string& n : splitList(optionValue(argc, argv, i)))
      plan.sizes.push_back(parseCount(arg, n, 0, 10000000));
  }
  else if (arg == "--reconstruction-voxel")
    S.reconstruction.voxelSize = 1e-3 * parseDouble(arg, optionValue(argc, argv, i), 0, 1e6);
  else if (arg == "--hole-reach")
    S.reconstruction.holeReach = parseDouble(arg, optionValue(argc, argv, i), 0, 1);
  else
    return false;
  return true;
}

// What the benchmark runs besides the table, and what it writes.
bool parseOutputOption(const std::string& arg, int argc, char** argv, int& i, Plan& plan)
{
  using namespace dp::cli;
  if (arg == "--no-pipeline")
    S.pipeline = false;
  else if (arg == "--verbose")
    S.verbose = true;
  else if (arg == "--csv")
    S.csvFile = optionValue(argc, argv, i);
  else if (arg == "--dump")
    S.dumpFolder = optionValue(argc, argv, i);
  else if (arg == "--oracle")
    S.oracle = oneOf(arg, optionValue(argc, argv, i), "same", "previous") ? "previous" : "same";
  else if (arg == "--start-frame")
    S.startFrame = parseCount(arg, optionValue(argc, argv, i), 0, 100000);
  else if (arg == "--ablation")
    plan.ablation = true;
  else if (arg == "--colour")
    S.colour = true;
  else if (arg == "--colour-tolerance")
    S.colourTolerance = static_cast<int>(
        parseCount(arg, optionValue(argc, argv, i), 0, dp::MaximumColourTolerance));
  else if (arg == "--compress")
    S.compress = true;
  else if (arg == "--scaling")
    plan.scaling = true;
  else if (arg == "--scaling-sizes")
  {
    ScalingSizes.clear();
    for (const std::string& n : splitList(optionValue(argc, argv, i)))
      ScalingSizes.push_back(parseCount(arg, n, 3, 10000000));
  }
  else
    return false;
  return true;
}

// Reads the command line into `plan`; an exit status when the benchmark should stop there
// (--help, an unknown option, a bad value).
std::optional<int> parseArguments(int argc, char** argv, Plan& plan)
{
  try
  {
    for (int i = 1; i < argc; ++i)
    {
      const std::string arg = argv[i];
      if (!parseDataOption(arg, argc, argv, i, plan) &&
          !dp::cli::parseTableOptionFlag(arg, argc, argv, i, {&plan.options, nullptr}) &&
          !parseOutputOption(arg, argc, argv, i, plan))
      {
        std::cout << Usage;
        return arg == "-h" || arg == "--help" ? 0 : 2;
      }
    }
  }
  catch (const dp::cli::UsageError& e)
  {
    std::cerr << e.what() << "\n";
    return 2;
  }
  return std::nullopt;
}

void printMachine(double height)
{
  std::printf("machine: %s, %u hardware threads; %zu samples per frame, %s normals; figures at "
              "%s; ms/frame %s\n",
              cpuModel().c_str(), std::thread::hardware_concurrency(), S.points,
              S.givenNormals ? "true" : "estimated",
              height > 0 ? (std::to_string(height) + " m height").c_str() : "stored units",
              S.pipeline ? "with each frame's data prepared beside the frame before (the main "
                           "job's pipeline; the data stage's time overlaps)"
                         : "with each frame prepared, then tracked (--no-pipeline)");
}

// One row of the table and, under it, its stages' times and steps.
void printRun(const Run& r, TemplateKind kind, std::size_t vertices, const Condition& condition,
              double diagonal)
{
  std::printf("%-14s %6zu %-6s %8.1f (%5.2f%%) %9.1f %8.1f %9.2f %7.2f (%3zu) %8.2fx "
              "%8.1f\n",
              templateName(kind), vertices, condition.name.c_str(), 1e3 * r.vertexRms,
              100 * r.vertexRms / diagonal, 1e3 * r.largestVertexError, 1e3 * r.surfaceRms,
              100 * r.uncoveredMean, 100 * r.uncoveredWorst, r.worstFrame, r.jitter, r.msPerFrame);
  const double perFrame = 1e3 / static_cast<double>(r.frames);
  std::printf("%14s vertex error %.1f mm along the true normals, %.1f mm along the surface\n", "",
              1e3 * r.normalRms,
              1e3 *
                  std::sqrt(std::max(0.0, r.vertexRms * r.vertexRms - r.normalRms * r.normalRms)));
  if (r.colourSwim >= 0)
    std::printf("%14s colour swim: %.1f of 255 RMS (stored within %d levels: %.1f; at the true "
                "positions: %.1f)\n",
                "", r.colourSwim, S.colourTolerance, r.storedColourSwim, r.truthColourSwim);
  std::printf("%14s ms/frame: data %.1f, prediction %.1f, coarse %.1f, fine %.1f, quality "
              "%.1f (kept attempts; retries on %zu frames), %zu frames flagged\n",
              "", perFrame * r.time.data, perFrame * r.time.prediction, perFrame * r.time.coarse,
              perFrame * r.time.fine, perFrame * r.time.quality, r.retried, r.flagged);
  if (S.rig > 0)
    std::printf("%14s seen by the data (truth within %.0f mm of a point): %.1f %% of the vertices, "
                "vertex RMS %.1f mm\n",
                "", 1e3 * S.uncoveredLimit / 2, 100 * r.seenShare, 1e3 * r.seenRms);
  std::printf("%14s shape, worst frames: %.2f %% of edges folded (over 120 degrees), %.2f %% "
              "stretched and %.2f %% torn (over 2 and 3 times their template length and its "
              "mean edge); %zu frames with a torn edge\n",
              "", 100 * r.foldedWorst, 100 * r.stretchedWorst, 100 * r.tornWorst, r.tornFrames);
  std::printf("%14s flags against the truth: %zu frames lost a part (over %.1f %% more of the "
              "true surface uncovered than at the first frame), %zu false flags, %zu missed "
              "failures\n",
              "", r.lost, 100 * S.lostShare, r.falseFlags, r.missed);
  if (S.rig > 0)
    std::printf("%14s flags against the true surface the data see: %zu frames lost a part, %zu "
                "false flags, %zu missed failures\n",
                "", r.lostSeen, r.falseSeen, r.missedSeen);
  std::printf("%14s steps/frame: coarse %.2f, fine %.2f (kept attempts)\n", "",
              static_cast<double>(r.coarseSteps) / static_cast<double>(r.frames),
              static_cast<double>(r.fineSteps) / static_cast<double>(r.frames));
  std::fflush(stdout);
}

// The take compressed beside the true motion of the same template: at KG 0.2 % (the codec's
// default) and against the data (the main job's default), with the distance of each to the
// frames' samples before and after.
void printCompressionRows(const dp::Tracker& tracker, const dp::AnimatedMesh& mesh,
                          const Template& t, const TrackedTake& take)
{
  const dp::TriangleMesh& triangles = tracker.mesh();
  std::vector<std::vector<double>> tracked, truth;
  double rawBytes = 0;
  for (std::size_t i = 0; i < take.results.size(); ++i)
  {
    tracked.push_back(take.results[i].positions);
    truth.push_back(groundTruth(t, mesh.positions(take.first + i), mesh.triangles()));
    rawBytes += 12.0 * static_cast<double>(take.results[i].pointsGiven);
  }
  const std::vector<const dp::FrameSamples*> samples = take.samples();
  const double reach = tracker.options().recovery.reach * tracker.voxelSize();
  const std::vector<double> trackedTake = frameMajor(tracked), trueTake = frameMajor(truth);
  printCompression("tracked, KG 0.2 %", compressAtKG(triangles, trackedTake, samples, reach, 0.2),
                   rawBytes);
  printCompression("truth, KG 0.2 %", compressAtKG(triangles, trueTake, samples, reach, 0.2),
                   rawBytes);
  printCompression("tracked, data +10 %",
                   compressForData(triangles, trackedTake, samples, reach, 0.1), rawBytes);
  printCompression("truth, data +10 %", compressForData(triangles, trueTake, samples, reach, 0.1),
                   rawBytes);
  printCompression("tracked, data +10 %, traj.",
                   compressForData(triangles, trackedTake, samples, reach, 0.1,
                                   dp::PcaLayout::Trajectories, &trueTake),
                   rawBytes);
  printCompression(
      "truth, data +10 %, traj.",
      compressForData(triangles, trueTake, samples, reach, 0.1, dp::PcaLayout::Trajectories),
      rawBytes);
  std::fflush(stdout);
}

// The paper's Table 2: motion prediction (MP) and provisional determination (PD) on and off.
void runAblation(const dp::AnimatedMesh& mesh, const Template& t, const dp::TrackerOptions& options,
                 const Condition& condition, std::size_t frames, const std::string& label)
{
  std::printf("ablation (%zu-vertex template): %8s %8s %14s %12s\n", t.vertices(), "MP", "PD",
              "vertex RMS mm", "ms/frame");
  for (int mode = 0; mode < 4; ++mode)
  {
    dp::TrackerOptions o = options;
    o.motionPrediction = mode & 1;
    o.provisionalDetermination = mode & 2;
    const Run a = track(mesh, t, o, condition, frames, nullptr, label);
    std::printf("%31s %8s %8s %14.1f %12.1f\n", "", o.motionPrediction ? "on" : "off",
                o.provisionalDetermination ? "on" : "off", 1e3 * a.vertexRms, a.msPerFrame);
  }
}

// The table's rows of one sequence: every template size and kind under every condition.
void runSequence(const std::string& name, const Plan& plan, std::ostream* csv)
{
  std::unique_ptr<dp::AnimatedMesh> stored = loadAnimation(plan.data, name);
  if (!stored)
    return;
  const double factor = plan.height > 0 ? plan.height / largestExtent(stored->positions(0)) : 1.0;
  const ScaledAnimation mesh(std::move(stored), factor);
  const std::size_t n =
      plan.frames ? std::min(plan.frames, mesh.numberOfFrames()) : mesh.numberOfFrames();
  const double diagonal = dp::boundingBoxDiagonal(mesh.positions(0));
  S.colourRest = mesh.positions(0);
  std::printf("\n== %s: %zu of %zu frames, %zu vertices, diagonal %.3f m, solver %s\n",
              name.c_str(), n, mesh.numberOfFrames(), mesh.numberOfVertices(), diagonal,
              solverName(plan.options.solver));
  std::printf("%-14s %6s %-6s %17s %9s %8s %17s %7s %9s %8s\n", "template", "verts", "data",
              "vertex RMS mm (%)", "largest", "surface", "uncovered% mean", "worst", "jitter",
              "ms/frame");
  for (std::size_t size : plan.sizes)
    for (TemplateKind kind : plan.kinds)
      for (const Condition& condition : plan.conditions)
      {
        const TemplateKind k = size == 0 ? TemplateKind::Full : kind;
        const dp::PointCloud frame0 = frameData(mesh, samplingFor(condition, S.points), 0);
        const Template t = makeTemplate(mesh, k, size, frame0, S.reconstruction);
        const std::string label = name + "-" + templateName(k) + "-" +
                                  std::to_string(t.vertices()) + "-" + condition.name;
        if (S.verbose)
          std::printf("  %s: template %zu vertices, %.1f%% of its triangles poorly shaped\n",
                      label.c_str(), t.vertices(),
                      100 * dp::TriangleMesh(t.triangles, t.vertices())
                                .poorlyShapedShare(t.positions.data()));
        dp::Tracker tracker(dp::TriangleMesh(t.triangles, t.vertices()), t.positions, plan.options);
        const TrackedTake take = trackForward(tracker, mesh, t, condition, n);
        printRun(evaluate(mesh, t, tracker, condition, take, true, csv, label), k, t.vertices(),
                 condition, diagonal);
        if (!take.inputMeshD1.empty())
          std::printf(
              "               the input meshes lie %.1f mm RMS from the true surface "
              "(D1, the worse direction; worst frame %.1f mm)\n",
              1e3 *
                  std::sqrt(std::accumulate(take.inputMeshD1.begin(), take.inputMeshD1.end(), 0.0) /
                            static_cast<double>(take.inputMeshD1.size())),
              1e3 * std::sqrt(*std::max_element(take.inputMeshD1.begin(), take.inputMeshD1.end())));
        if (S.compress)
          printCompressionRows(tracker, mesh, t, take);
        if (plan.ablation)
          runAblation(mesh, t, plan.options, condition, n, label);
      }
}

} // namespace

int main(int argc, char** argv)
{
  Plan plan;
  if (const std::optional<int> status = parseArguments(argc, argv, plan))
    return *status;
  printMachine(plan.height);
  if (plan.scaling)
  {
    scalingTable(plan.options, plan.frames ? plan.frames : 4, S.points, S.givenNormals);
    return 0;
  }
  std::unique_ptr<std::ofstream> csv;
  if (!S.csvFile.empty())
  {
    csv = std::make_unique<std::ofstream>(S.csvFile);
    *csv << "run,frame,vertex_rms_mm,largest_mm,surface_rms_mm,uncovered_percent,iterations,ms\n";
  }
  for (const std::string& name : plan.sequences)
    runSequence(name, plan, csv.get());
  return 0;
}
