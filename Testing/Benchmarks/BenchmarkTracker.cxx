// SPDX-License-Identifier: BSD-3-Clause
// Benchmark: the paper's experiments on ground-truth animated meshes. Per frame, random surface
// samples (20k by default) are the data; the template is frame 0 at full resolution, or one of
// about a given vertex count: reconstructed from frame 0's samples (the default, what the filter
// does without a template) or frame 0 simplified (vtkQuadricDecimation). The ground truth of a
// template vertex is the barycentric position of its closest point on the frame-0 mesh,
// carried through the frames. Prints vertex
// RMS against the ground truth (the paper's measure) and RMS distance to the true surface,
// both also in % of the bounding-box diagonal, ms per frame and peak memory; optionally the
// paper's Table 2 ablation (none / MP / PD / both) for a solver.
#include "BenchmarkSequences.h"
#include "BenchmarkUtilities.h"
#include "CommandLine.h"

#include "dp/AnimatedMesh.h"
#include "dp/FrameSequence.h"
#include "dp/SurfaceReconstruction.h"
#include "dp/SurfaceSampler.h"
#include "dp/Tracker.h"

#include "vtkCellArray.h"
#include "vtkCellArrayIterator.h"
#include "vtkCellLocator.h"
#include "vtkGenericCell.h"
#include "vtkNew.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkQuadricDecimation.h"
#include "vtkSmartPointer.h"
#include "vtkTriangle.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace
{
using namespace dp::bench;

bool Verbose = false;          // --verbose: one line per frame
std::uint64_t SamplerSeed = 1; // --seed: which random samples the frames get
double NoiseFraction = 0;      // --noise: Gaussian noise on the samples, as a share of the diagonal
std::size_t Holes = 0;         // --holes: holes cut in every frame (radius 5% of the diagonal)
// --oracle: diagnostics that start each frame from the ground truth: "previous" (one-step error
// from the true previous frame), "same" (how far the energy's minimum lies from the truth).
std::string Oracle;

vtkSmartPointer<vtkPolyData> toPolyData(const std::vector<double>& positions,
                                        const std::vector<std::int64_t>& triangles)
{
  auto pd = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  for (std::size_t i = 0; i < positions.size(); i += 3)
    points->InsertNextPoint(&positions[i]);
  vtkNew<vtkCellArray> polys;
  for (std::size_t t = 0; t < triangles.size(); t += 3)
  {
    const vtkIdType ids[3] = {triangles[t], triangles[t + 1], triangles[t + 2]};
    polys->InsertNextCell(3, ids);
  }
  pd->SetPoints(points);
  pd->SetPolys(polys);
  return pd;
}

// A template and, for each of its vertices, where it sits on the full-resolution mesh.
struct Template
{
  std::vector<std::int64_t> triangles;
  std::vector<double> positions;
  std::vector<std::int64_t> onTriangle; // index into the full mesh's triangles
  std::vector<double> barycentric;      // 3 per vertex
};

// How the template is made: frame 0 simplified (vtkQuadricDecimation), or a surface
// reconstructed from frame 0's random samples (dp::reconstructSurface, the path for data
// without a template).
bool Reconstruct = true; // --template reconstructed|simplified

Template makeTemplate(const dp::AnimatedMesh& mesh, std::size_t targetVertices)
{
  Template t;
  const std::vector<double> frame0 = mesh.positions(0);
  const auto& full = mesh.triangles();
  auto input = toPolyData(frame0, full);
  vtkSmartPointer<vtkPolyData> coarse;
  if (targetVertices == 0 || (!Reconstruct && targetVertices >= mesh.numberOfVertices()))
  {
    t.triangles = full;
    t.positions = frame0;
    return t; // full resolution: the vertices are the ground truth's own
  }
  if (Reconstruct)
  {
    dp::SamplerOptions sampling;
    sampling.seed = SamplerSeed;
    const dp::PointCloud cloud = dp::sampleSurface(frame0, full, sampling, 0);
    dp::ReconstructionOptions o;
    o.targetVertices = targetVertices;
    const dp::ReconstructedMesh r = dp::reconstructSurface(
        cloud.points.data(), cloud.normals.data(), cloud.numberOfPoints(), o);
    coarse = toPolyData(r.positions, r.triangles);
  }
  else
  {
    vtkNew<vtkQuadricDecimation> decimate;
    decimate->SetInputData(input);
    decimate->SetTargetReduction(1.0 - static_cast<double>(targetVertices) /
                                           static_cast<double>(mesh.numberOfVertices()));
    decimate->VolumePreservationOn();
    // Flat regions make the quadrics singular; VTK then warns once per vertex and falls back
    // to the edge's midpoint, which is fine here.
    const int warnings = vtkObject::GetGlobalWarningDisplay();
    vtkObject::GlobalWarningDisplayOff();
    decimate->Update();
    vtkObject::SetGlobalWarningDisplay(warnings);
    coarse = decimate->GetOutput();
  }
  // Each template vertex sits at the closest point of the frame-0 mesh: its barycentric
  // position there, carried through the frames, is its ground truth.
  vtkNew<vtkCellLocator> locator;
  locator->SetDataSet(input);
  locator->BuildLocator();
  vtkNew<vtkGenericCell> cell;
  for (vtkIdType i = 0; i < coarse->GetNumberOfPoints(); ++i)
  {
    double p[3], closest[3], d2 = 0;
    coarse->GetPoint(i, p);
    vtkIdType cellId = -1;
    int subId = 0;
    locator->FindClosestPoint(p, closest, cell, cellId, subId, d2);
    const std::int64_t* v = &full[3 * cellId];
    double a[3], b[3], c[3], w[3];
    for (int k = 0; k < 3; ++k)
    {
      a[k] = frame0[3 * v[0] + k];
      b[k] = frame0[3 * v[1] + k];
      c[k] = frame0[3 * v[2] + k];
    }
    vtkTriangle::BarycentricCoords(closest, a, b, c, w);
    // A simplified vertex sits on the surface; a reconstructed one up to half a voxel off it,
    // where it stays (projecting it could fold thin triangles flat): its error at frame 0 is
    // then that offset.
    const double* at = Reconstruct ? p : closest;
    t.positions.insert(t.positions.end(), at, at + 3);
    t.onTriangle.push_back(cellId);
    t.barycentric.insert(t.barycentric.end(), w, w + 3);
  }
  const vtkIdType* ids = nullptr;
  vtkIdType count = 0;
  auto polys = vtk::TakeSmartPointer(coarse->GetPolys()->NewIterator());
  for (polys->GoToFirstCell(); !polys->IsDoneWithTraversal(); polys->GoToNextCell())
  {
    polys->GetCurrentCell(count, ids);
    if (count == 3)
      t.triangles.insert(t.triangles.end(), {ids[0], ids[1], ids[2]});
  }
  return t;
}

std::vector<double> groundTruth(const Template& t, const std::vector<double>& frame,
                                const std::vector<std::int64_t>& full)
{
  if (t.onTriangle.empty())
    return frame;
  std::vector<double> out(t.positions.size());
  for (std::size_t i = 0; i < t.onTriangle.size(); ++i)
    for (int k = 0; k < 3; ++k)
    {
      double value = 0;
      for (int c = 0; c < 3; ++c)
        value += t.barycentric[3 * i + c] * frame[3 * full[3 * t.onTriangle[i] + c] + k];
      out[3 * i + k] = value;
    }
  return out;
}

struct Run
{
  double vertexRms = 0, surfaceRms = 0, msPerFrame = 0;
  std::size_t frames = 0;
};

Run track(const dp::AnimatedMesh& mesh, const Template& t, const dp::TrackerOptions& options,
          std::size_t frames, std::size_t points)
{
  dp::Tracker tracker(dp::TriangleMesh(t.triangles, t.positions.size() / 3), t.positions, options);
  dp::SamplerOptions sampling;
  sampling.pointsPerFrame = points;
  sampling.seed = SamplerSeed;
  const double diagonal = dp::boundingBoxDiagonal(mesh.positions(0));
  sampling.noiseStdDev = NoiseFraction * diagonal;
  sampling.holes = Holes;
  sampling.holeRadius = 0.05 * diagonal;
  Run run;
  double vertexSum = 0, surfaceSum = 0, seconds = 0;
  std::size_t vertexCount = 0;
  for (std::size_t f = 0; f < frames; ++f)
  {
    const std::vector<double> truthMesh = mesh.positions(f);
    const dp::PointCloud cloud = dp::sampleSurface(truthMesh, mesh.triangles(), sampling, f);
    if (Oracle == "previous" && f > 0)
      tracker.restartFrom(groundTruth(t, mesh.positions(f - 1), mesh.triangles()));
    else if (Oracle == "same")
      tracker.restartFrom(groundTruth(t, truthMesh, mesh.triangles()));
    const dp::FrameResult r =
        tracker.track(cloud.points.data(), cloud.numberOfPoints(), cloud.normals.data());
    seconds += r.seconds;
    const std::vector<double> truth = groundTruth(t, truthMesh, mesh.triangles());
    double frameSum = 0;
    for (std::size_t i = 0; i < truth.size(); ++i)
      frameSum += (truth[i] - r.positions[i]) * (truth[i] - r.positions[i]);
    vertexSum += frameSum;
    vertexCount += truth.size() / 3;
    double frameSurface = 0;
    // Distance from each tracked vertex to the true surface of the frame.
    auto surface = toPolyData(truthMesh, mesh.triangles());
    vtkNew<vtkCellLocator> locator;
    locator->SetDataSet(surface);
    locator->BuildLocator();
    vtkNew<vtkGenericCell> cell;
    for (std::size_t i = 0; i < r.positions.size(); i += 3)
    {
      double closest[3], d2 = 0;
      vtkIdType cellId = -1;
      int subId = 0;
      double x[3] = {r.positions[i], r.positions[i + 1], r.positions[i + 2]};
      locator->FindClosestPoint(x, closest, cell, cellId, subId, d2);
      frameSurface += d2;
    }
    surfaceSum += frameSurface;
    if (Verbose)
    {
      int rejected = 0;
      for (auto flag : r.rejected)
        rejected += flag;
      std::printf("  frame %3zu: vertex RMS %.5f, surface RMS %.5f, %d iterations, %d rejected, "
                  "%.1f ms, E %.6g\n",
                  f, std::sqrt(frameSum / static_cast<double>(truth.size() / 3)),
                  std::sqrt(frameSurface / static_cast<double>(truth.size() / 3)), r.iterations,
                  rejected, 1e3 * r.seconds, r.internalEnergy + r.distanceEnergy);
    }
  }
  run.frames = frames;
  run.vertexRms = std::sqrt(vertexSum / static_cast<double>(vertexCount));
  run.surfaceRms = std::sqrt(surfaceSum / static_cast<double>(vertexCount));
  run.msPerFrame = 1e3 * seconds / static_cast<double>(frames);
  return run;
}

// The paper's Fig. 4: time per frame against the vertex count, on the procedural bending tube
// at resolutions from 500 to 50k vertices (same shape, same 20k points per frame).
std::vector<std::size_t> ScalingSizes = {500, 1000, 2000, 5000, 10000, 20000, 50000};

void scalingTable(const dp::TrackerOptions& options, std::size_t frames, std::size_t points)
{
  std::printf("\n== scaling (bending tube, %zu frames after the first, %zu points per frame)\n",
              frames, points);
  std::printf("%10s %12s %14s %12s %14s\n", "vertices", "ms/frame", "ms/1k vertices", "iterations",
              "vertex RMS %");
  for (std::size_t target : ScalingSizes)
  {
    dp::BendingTube::Options shape;
    shape.segments = static_cast<std::size_t>(std::lround(std::sqrt(target / 1.67)));
    shape.rings = (target + shape.segments - 1) / shape.segments;
    const dp::BendingTube tube(shape);
    dp::Tracker tracker(dp::TriangleMesh(tube.triangles(), tube.numberOfVertices()),
                        tube.positions(0), options);
    dp::SamplerOptions sampling;
    sampling.pointsPerFrame = points;
    std::vector<double> ms;
    double iterations = 0, sum = 0;
    const double diagonal = dp::boundingBoxDiagonal(tube.positions(0));
    for (std::size_t f = 0; f <= frames; ++f)
    {
      const dp::PointCloud cloud =
          dp::sampleSurface(tube.positions(f), tube.triangles(), sampling, f);
      const dp::FrameResult r =
          tracker.track(cloud.points.data(), cloud.numberOfPoints(), cloud.normals.data());
      if (f == 0)
        continue; // the first frame starts at the data
      ms.push_back(1e3 * r.seconds);
      iterations += r.iterations;
      const std::vector<double> truth = tube.positions(f);
      double e = 0;
      for (std::size_t i = 0; i < truth.size(); ++i)
        e += (truth[i] - r.positions[i]) * (truth[i] - r.positions[i]);
      sum += e / static_cast<double>(truth.size() / 3);
    }
    const double median = dp::bench::median(ms);
    std::printf("%10zu %12.1f %14.2f %12.1f %13.3f%%\n", tube.numberOfVertices(), median,
                1e3 * median / static_cast<double>(tube.numberOfVertices()),
                iterations / static_cast<double>(frames),
                100 * std::sqrt(sum / static_cast<double>(frames)) / diagonal);
    std::fflush(stdout);
  }
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

} // namespace

int main(int argc, char** argv)
{
  using namespace dp::cli;
  std::string data = "../shared/data";
  std::vector<std::string> sequences = {"horse-collapse", "horse-gallop"};
  std::vector<std::size_t> sizes = {450, 1000, 0};
  std::size_t frames = 0, points = 20000;
  bool ablation = false, scaling = false;
  dp::TrackerOptions options;
  try
  {
    for (int i = 1; i < argc; ++i)
    {
      const std::string arg = argv[i];
      if (arg == "--data")
        data = optionValue(argc, argv, i);
      else if (arg == "--sequence")
        sequences = {optionValue(argc, argv, i)};
      else if (arg == "--vertices")
        sizes = {parseCount(arg, optionValue(argc, argv, i), 0, 10000000)};
      else if (arg == "--frames")
        frames = parseCount(arg, optionValue(argc, argv, i), 1, 100000);
      else if (arg == "--points")
        points = parseCount(arg, optionValue(argc, argv, i), 1, 10000000);
      else if (arg == "--solver")
      {
        const std::string s = optionValue(argc, argv, i);
        options.solver = s == "lbfgs" ? dp::TrackerSolver::LBFGS
                         : s == "sd"  ? dp::TrackerSolver::SteepestDescent
                                      : dp::TrackerSolver::GaussNewton;
      }
      else if (arg == "--noise")
        NoiseFraction = parseDouble(arg, optionValue(argc, argv, i), 0, 1);
      else if (arg == "--holes")
        Holes = parseCount(arg, optionValue(argc, argv, i), 0, 1000);
      else if (arg == "--seed")
        SamplerSeed = parseCount(arg, optionValue(argc, argv, i), 0, 1000000000);
      else if (arg == "--template")
        Reconstruct = oneOf(arg, optionValue(argc, argv, i), "simplified", "reconstructed");
      else if (arg == "--ablation")
        ablation = true;
      else if (arg == "--scaling")
        scaling = true;
      else if (arg == "--scaling-sizes")
      {
        // comma-separated vertex counts
        ScalingSizes.clear();
        std::string list = optionValue(argc, argv, i);
        for (std::size_t start = 0; start <= list.size();)
        {
          const std::size_t comma = std::min(list.find(',', start), list.size());
          ScalingSizes.push_back(parseCount(arg, list.substr(start, comma - start), 3, 10000000));
          start = comma + 1;
        }
      }
      else if (arg == "--rest-update")
        options.restUpdate = parseDouble(arg, optionValue(argc, argv, i), 0, 1);
      else if (arg == "--measure")
        options.distanceMeasure = oneOf(arg, optionValue(argc, argv, i), "planes", "points")
                                      ? dp::DistanceMeasure::Points
                                      : dp::DistanceMeasure::Planes;
      else if (arg == "--no-mp")
        options.motionPrediction = false;
      else if (arg == "--no-rigid")
        options.rigidAlignment = false;
      else if (arg == "--penalty")
        options.squaredDistance = !oneOf(arg, optionValue(argc, argv, i), "squared", "linear");
      else if (arg == "--oracle")
        Oracle = oneOf(arg, optionValue(argc, argv, i), "same", "previous") ? "previous" : "same";
      else if (arg == "--verbose")
        Verbose = true;
      else if (arg == "--distance-weight")
        options.distanceWeight = parseDouble(arg, optionValue(argc, argv, i), 0, 1e12);
      else if (arg == "--tolerance")
        options.tolerance = parseDouble(arg, optionValue(argc, argv, i), 1e-15, 1);
      else if (arg == "--max-iterations")
        options.maxIterations =
            static_cast<int>(parseCount(arg, optionValue(argc, argv, i), 1, 1000000));
      else if (arg == "--normal-test")
        options.normalTestDegrees = parseDouble(arg, optionValue(argc, argv, i), 0, 180);
      else if (arg == "--stiffness")
      {
        // stretch,shear,bend
        const std::string v = optionValue(argc, argv, i);
        if (std::sscanf(v.c_str(), "%lf,%lf,%lf", &options.cloth.stretch, &options.cloth.shear,
                        &options.cloth.bend) != 3)
          throw UsageError("--stiffness wants stretch,shear,bend");
      }
      else
      {
        std::cout
            << "Usage: BenchmarkTracker [--data DIR] [--sequence NAME|tube] [--vertices N "
               "(0: full)] [--frames N] [--points N] [--seed S] [--noise FRACTION] [--holes N] "
               "[--solver gn|lbfgs|sd] [--ablation] "
               "[--verbose]\n"
               "       [--distance-weight W] [--normal-test DEGREES] [--stiffness ST,SH,BE] "
               "[--tolerance T] [--max-iterations N]\n"
               "       [--measure planes|points] [--penalty squared|linear] [--rest-update B] "
               "[--no-mp] [--no-rigid] [--oracle previous|same] [--scaling] [--scaling-sizes "
               "N,N,...]\n";
        return arg == "-h" || arg == "--help" ? 0 : 2;
      }
    }
  }
  catch (const UsageError& e)
  {
    std::cerr << e.what() << "\n";
    return 2;
  }
  std::printf("machine: %s, %u hardware threads; Release build; %zu samples per frame\n",
              cpuModel().c_str(), std::thread::hardware_concurrency(), points);
  if (scaling)
  {
    scalingTable(options, frames ? frames : 4, points);
    return 0;
  }
  for (const std::string& name : sequences)
  {
    const std::unique_ptr<dp::AnimatedMesh> mesh = loadAnimation(data, name);
    if (!mesh)
      continue;
    const std::size_t n =
        frames ? std::min(frames, mesh->numberOfFrames()) : mesh->numberOfFrames();
    const double diagonal = dp::boundingBoxDiagonal(mesh->positions(0));
    std::printf("\n== %s: %zu of %zu frames, %zu vertices, diagonal %.3f, solver %s, "
                "%s templates\n",
                name.c_str(), n, mesh->numberOfFrames(), mesh->numberOfVertices(), diagonal,
                solverName(options.solver), Reconstruct ? "reconstructed" : "simplified");
    std::printf("%10s %14s %16s %12s %12s\n", "template", "vertex RMS", "surface RMS", "ms/frame",
                "peak MiB");
    for (std::size_t size : sizes)
    {
      const Template t = makeTemplate(*mesh, size);
      if (Verbose)
        std::printf("  template: %zu vertices, %.1f%% of its triangles poorly shaped\n",
                    t.positions.size() / 3,
                    100 * dp::TriangleMesh(t.triangles, t.positions.size() / 3)
                              .poorlyShapedShare(t.positions.data()));
      const Run r = track(*mesh, t, options, n, points);
      std::printf("%10zu %8.5f %5.2f%% %10.5f %5.2f%% %12.1f %12.1f\n", t.positions.size() / 3,
                  r.vertexRms, 100 * r.vertexRms / diagonal, r.surfaceRms,
                  100 * r.surfaceRms / diagonal, r.msPerFrame, peakMiB());
    }
    if (ablation)
    {
      const Template t = makeTemplate(*mesh, sizes.front());
      std::printf("ablation (%zu-vertex template): %8s %8s %14s %12s\n", t.positions.size() / 3,
                  "MP", "PD", "vertex RMS %", "ms/frame");
      for (int mode = 0; mode < 4; ++mode)
      {
        dp::TrackerOptions o = options;
        o.motionPrediction = mode & 1;
        o.provisionalDetermination = mode & 2;
        const Run r = track(*mesh, t, o, n, points);
        std::printf("%31s %8s %8s %13.3f%% %12.1f\n", "", o.motionPrediction ? "on" : "off",
                    o.provisionalDetermination ? "on" : "off", 100 * r.vertexRms / diagonal,
                    r.msPerFrame);
      }
    }
  }
  return 0;
}
