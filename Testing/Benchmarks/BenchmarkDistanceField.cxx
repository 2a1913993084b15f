// SPDX-License-Identifier: BSD-3-Clause
// Benchmark: the distance field (engine, OpenVDB) against VTK's vtkUnsignedDistance on the same
// points and grid, in one run, for the paper's setup: 20k surface points of a 1.7 m figure at
// 12 mm voxels (a 200^3 box with the band), and for 1M points. Prints build time, memory,
// accuracy against exact nearest-point distances, and sampling throughput.
//
// The figure is frame 0 of ../shared/data/horse-gallop when present (scaled to 1.7 m), else the
// built-in tube scaled to 1.7 m. Medians of --repeats builds.
#include "BenchmarkUtilities.h"
#include "CommandLine.h"

#include "dp/field/DistanceField.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/io/FrameSequence.h"

#include "vtkDistanceFieldFilter.h"
#include "vtkFloatArray.h"
#include "vtkImageData.h"
#include "vtkKdTreePointLocator.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkSMPTools.h"
#include "vtkSmartPointer.h"
#include "vtkUnsignedDistance.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <unistd.h>
#include <vector>

namespace
{
using namespace dp::bench;

// The figure: an animated mesh's frame 0, scaled so its largest extent is `height` metres.
struct Figure
{
  std::string name;
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;
};

Figure loadFigure(const std::string& dataDir, double height)
{
  Figure f;
  std::unique_ptr<dp::AnimatedMesh> mesh;
  const std::string horse = dataDir + "/horse-gallop";
  if (std::filesystem::is_directory(horse))
  {
    mesh =
        std::make_unique<dp::MeshSequenceFiles>(dp::FrameSequence::fromDirectory(horse, "*.ply"));
    f.name = "horse-gallop frame 0";
  }
  else
  {
    mesh = std::make_unique<dp::BendingTube>();
    f.name = "built-in tube frame 0";
  }
  f.positions = mesh->positions(0);
  f.triangles = mesh->triangles();
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k)
  {
    lo[k] = hi[k] = f.positions[k];
    for (std::size_t i = k; i < f.positions.size(); i += 3)
    {
      lo[k] = std::min(lo[k], f.positions[i]);
      hi[k] = std::max(hi[k], f.positions[i]);
    }
  }
  const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  for (std::size_t i = 0; i < f.positions.size(); ++i)
    f.positions[i] = (f.positions[i] - lo[i % 3]) * height / extent;
  return f;
}

struct Errors
{
  double max = 0, rms = 0;
  std::size_t count = 0;
};

void accumulate(Errors& e, double err)
{
  e.max = std::max(e.max, std::abs(err));
  e.rms += err * err;
  ++e.count;
}

void finish(Errors& e)
{
  e.rms = e.count ? std::sqrt(e.rms / static_cast<double>(e.count)) : 0;
}

// The paper's dense box of boxVoxels^3 voxels around the points, at the voxel size
// (vtkUnsignedDistance fills all of it; ours only the band).
struct DenseBox
{
  double lo[3], hi[3], voxel;
  int dims[3];

  DenseBox(const std::vector<double>& points, double voxelSize, int boxVoxels) : voxel(voxelSize)
  {
    const std::size_t n = points.size() / 3;
    for (int k = 0; k < 3; ++k)
    {
      double a = points[k], b = points[k];
      for (std::size_t i = 0; i < n; ++i)
      {
        a = std::min(a, points[3 * i + k]);
        b = std::max(b, points[3 * i + k]);
      }
      const double centre = voxel * std::round(0.5 * (a + b) / voxel);
      lo[k] = centre - voxel * (boxVoxels / 2);
      hi[k] = lo[k] + voxel * (boxVoxels - 1);
      dims[k] = boxVoxels;
    }
  }
  double millionVoxels() const { return static_cast<double>(dims[0]) * dims[1] * dims[2] / 1e6; }
  vtkIdType index(const int ijk[3]) const
  {
    return ijk[0] +
           static_cast<vtkIdType>(dims[0]) * (ijk[1] + static_cast<vtkIdType>(dims[1]) * ijk[2]);
  }
};

// Our sparse field built `repeats` times on all threads and on one (medians printed); the last
// build is kept.
dp::DistanceField timeOurBuild(const std::vector<double>& points, double voxel, double band,
                               std::size_t repeats, std::vector<double>& threaded,
                               std::vector<double>& oneThread)
{
  dp::DistanceFieldOptions options;
  options.voxelSize = voxel;
  options.bandWidth = band;
  const std::size_t n = points.size() / 3;
  double rssBefore = residentMiB(), rssAfter = 0;
  dp::DistanceField field;
  for (std::size_t r = 0; r < repeats; ++r)
  {
    dp::DistanceField f;
    double t = now();
    f.build(points.data(), n, options);
    threaded.push_back(now() - t);
    if (r == 0)
      rssAfter = residentMiB();
    {
      const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
      dp::DistanceField g;
      t = now();
      g.build(points.data(), n, options);
      oneThread.push_back(now() - t);
    }
    field = std::move(f);
  }
  std::printf("ours (OpenVDB band): build %.1f ms on 1 thread, %.1f ms on %u threads (medians of "
              "%zu); %zu active voxels; field memory %.1f MiB (resident +%.1f MiB)\n",
              1e3 * median(oneThread), 1e3 * median(threaded), std::thread::hardware_concurrency(),
              repeats, field.activeVoxelCount(),
              static_cast<double>(field.memoryBytes()) / (1 << 20), rssAfter - rssBefore);
  return field;
}

// Every second voxel centre of the box (each axis) within the band of the points.
std::vector<double> centresInBand(const dp::DistanceField& field, const DenseBox& box, double band)
{
  std::vector<double> centres;
  for (int k = 0; k < box.dims[2]; k += 2)
    for (int j = 0; j < box.dims[1]; j += 2)
      for (int i = 0; i < box.dims[0]; i += 2)
      {
        const double x[3] = {box.lo[0] + i * box.voxel, box.lo[1] + j * box.voxel,
                             box.lo[2] + k * box.voxel};
        double d2 = 0;
        field.nearestPoint(x, &d2);
        if (d2 <= band * band)
          centres.insert(centres.end(), x, x + 3);
      }
  return centres;
}

// A million random positions within the band (near random points); prints the field's sampling
// throughput there, serial and parallel, and returns the positions with their samples.
std::vector<double> timeSampling(const dp::DistanceField& field, const std::vector<double>& points,
                                 double band, std::vector<dp::DistanceSample>& out)
{
  const std::size_t n = points.size() / 3;
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<std::size_t> pick(0, n - 1);
  std::uniform_real_distribution<double> offset(-band / std::sqrt(3.0), band / std::sqrt(3.0));
  const std::size_t queries = 1000000;
  std::vector<double> q(3 * queries);
  for (std::size_t i = 0; i < queries; ++i)
  {
    const std::size_t p = pick(rng);
    for (int k = 0; k < 3; ++k)
      q[3 * i + k] = points[3 * p + k] + offset(rng);
  }
  out.assign(queries, {});
  double t = now();
  for (std::size_t i = 0; i < queries; ++i)
    out[i] = field.sample(&q[3 * i]);
  const double serial = now() - t;
  t = now();
  field.sampleMany(q.data(), queries, out.data());
  const double parallel = now() - t;
  std::size_t inBand = 0;
  for (const auto& s : out)
    inBand += s.inBand;
  std::printf("sampling: %.2f M queries/s on one thread, %.2f M/s with %u threads (%.0f%% of "
              "queries fully in the band)\n",
              queries / serial / 1e6, queries / parallel / 1e6, std::thread::hardware_concurrency(),
              100.0 * static_cast<double>(inBand) / queries);
  return q;
}

// vtkUnsignedDistance over the whole box, `repeats` times (the times in `seconds`).
vtkSmartPointer<vtkImageData> timeVtkUnsignedDistance(const std::vector<double>& points,
                                                      const DenseBox& box, double band,
                                                      std::size_t repeats,
                                                      std::vector<double>& seconds)
{
  const std::size_t n = points.size() / 3;
  vtkNew<vtkPoints> vtkPts;
  vtkPts->SetDataTypeToDouble();
  vtkPts->SetNumberOfPoints(static_cast<vtkIdType>(n));
  for (std::size_t i = 0; i < n; ++i)
    vtkPts->SetPoint(static_cast<vtkIdType>(i), &points[3 * i]);
  vtkNew<vtkPolyData> cloud;
  cloud->SetPoints(vtkPts);
  vtkNew<vtkUnsignedDistance> reference;
  for (std::size_t r = 0; r < repeats; ++r)
  {
    reference->SetInputData(cloud);
    reference->SetDimensions(box.dims);
    reference->SetBounds(box.lo[0], box.hi[0], box.lo[1], box.hi[1], box.lo[2], box.hi[2]);
    reference->SetAdjustBounds(false);
    reference->SetRadius(band);
    reference->CappingOn();
    reference->SetOutputScalarTypeToFloat();
    reference->Modified();
    const double start = now();
    reference->Update();
    seconds.push_back(now() - start);
  }
  return reference->GetOutput();
}

// VTK's image against the exact distances at the voxel centres in the band.
Errors vtkErrorsAtCentres(vtkImageData* image, const DenseBox& box, const dp::DistanceField& field,
                          const std::vector<double>& centres)
{
  vtkDataArray* values = image->GetPointData()->GetScalars();
  Errors e;
  for (std::size_t c = 0; c < centres.size(); c += 3)
  {
    int ijk[3];
    for (int k = 0; k < 3; ++k)
      ijk[k] = static_cast<int>(std::lround((centres[c + k] - box.lo[k]) / box.voxel));
    double d2 = 0;
    field.nearestPoint(&centres[c], &d2);
    accumulate(e, values->GetTuple1(box.index(ijk)) - std::sqrt(d2));
  }
  finish(e);
  return e;
}

// Off the grid VTK's image must be interpolated (trilinear), as any user of it would: its errors
// at the first 20 000 positions q whose eight voxels are all within VTK's radius.
Errors vtkTrilinearErrors(vtkImageData* image, const DenseBox& box, const dp::DistanceField& field,
                          const std::vector<double>& q, double band)
{
  vtkDataArray* values = image->GetPointData()->GetScalars();
  Errors e;
  for (std::size_t i = 0; i < 20000; ++i)
  {
    const double* x = &q[3 * i];
    double g[3];
    int b[3];
    for (int k = 0; k < 3; ++k)
    {
      g[k] = (x[k] - box.lo[k]) / box.voxel;
      b[k] = std::clamp(static_cast<int>(std::floor(g[k])), 0, box.dims[k] - 2);
      g[k] -= b[k];
    }
    double value = 0;
    bool capped = false;
    for (int corner = 0; corner < 8; ++corner)
    {
      const int o[3] = {corner & 1, (corner >> 1) & 1, (corner >> 2) & 1};
      const double w =
          (o[0] ? g[0] : 1 - g[0]) * (o[1] ? g[1] : 1 - g[1]) * (o[2] ? g[2] : 1 - g[2]);
      const int ijk[3] = {b[0] + o[0], b[1] + o[1], b[2] + o[2]};
      const double cornerValue = values->GetTuple1(box.index(ijk));
      capped = capped || cornerValue > band;
      value += w * cornerValue;
    }
    if (capped)
      continue; // beyond VTK's radius the image holds only the cap value
    double d2 = 0;
    field.nearestPoint(x, &d2);
    accumulate(e, value - std::sqrt(d2));
  }
  finish(e);
  return e;
}

// Our field's errors at the voxel centres (3 coordinates each) against the exact nearest-point
// distance.
Errors errorsAtCentres(const dp::DistanceField& field, const std::vector<double>& centres)
{
  Errors e;
  for (std::size_t c = 0; c < centres.size(); c += 3)
  {
    double d2 = 0;
    field.nearestPoint(&centres[c], &d2);
    accumulate(e, field.sample(&centres[c]).distance - std::sqrt(d2));
  }
  finish(e);
  return e;
}

// The errors of the first 20000 samples (taken at q, 3 coordinates each) against the exact
// nearest-point distance.
Errors errorsOfSamples(const dp::DistanceField& field, const std::vector<double>& q,
                       const std::vector<dp::DistanceSample>& samples)
{
  Errors e;
  for (std::size_t i = 0; i < 20000; ++i)
  {
    double d2 = 0;
    field.nearestPoint(&q[3 * i], &d2);
    accumulate(e, samples[i].distance - std::sqrt(d2));
  }
  finish(e);
  return e;
}

// The sparse field against vtkUnsignedDistance on the dense box: build times, memory, sampling
// throughput and accuracy against exact nearest-point distances.
void runCase(const Figure& figure, std::size_t pointCount, double voxel, double band, int boxVoxels,
             std::size_t repeats, bool withVTK)
{
  dp::SamplerOptions sampling;
  sampling.pointsPerFrame = pointCount;
  sampling.normals = false;
  const std::vector<double> points =
      dp::sampleSurface(figure.positions, figure.triangles, sampling, 0).points;
  const DenseBox box(points, voxel, boxVoxels);
  std::printf("\n== %zu points on %s (1.7 m), voxel %.0f mm, band %.0f mm; box %d x %d x %d "
              "= %.1f M voxels\n",
              points.size() / 3, figure.name.c_str(), voxel * 1e3, band * 1e3, box.dims[0],
              box.dims[1], box.dims[2], box.millionVoxels());
  std::vector<double> ours, oursOneThread;
  const dp::DistanceField field = timeOurBuild(points, voxel, band, repeats, ours, oursOneThread);

  // Accuracy at the grid's voxel centres within the band, against the exact nearest point.
  const std::vector<double> centres = centresInBand(field, box, band);
  const Errors oursGrid = errorsAtCentres(field, centres);
  std::vector<dp::DistanceSample> samples;
  const std::vector<double> q = timeSampling(field, points, band, samples);
  const Errors oursRandom = errorsOfSamples(field, q, samples);

  if (!withVTK)
  {
    std::printf("accuracy vs exact nearest-point distance (max / RMS, in voxels): at voxel "
                "centres %.3f / %.4f; at random positions %.3f / %.4f\n",
                oursGrid.max / voxel, oursGrid.rms / voxel, oursRandom.max / voxel,
                oursRandom.rms / voxel);
    return;
  }
  std::vector<double> theirs;
  const vtkSmartPointer<vtkImageData> image =
      timeVtkUnsignedDistance(points, box, band, repeats, theirs);
  const Errors vtkGrid = vtkErrorsAtCentres(image, box, field, centres);
  const Errors vtkRandom = vtkTrilinearErrors(image, box, field, q, band);
  std::printf("vtkUnsignedDistance (dense %d^3 box, radius = band, %d SMP thread(s)): %.1f ms "
              "(median of %zu)\n",
              box.dims[0], vtkSMPTools::GetEstimatedNumberOfThreads(), 1e3 * median(theirs),
              repeats);
  std::printf("build speed-up, ours vs vtkUnsignedDistance: %.1fx (both on 1 thread), %.1fx (ours "
              "threaded)\n",
              median(theirs) / median(oursOneThread), median(theirs) / median(ours));
  std::printf("%-34s %12s %12s %12s %12s\n", "accuracy (in voxels)", "ours max", "ours RMS",
              "VTK max", "VTK RMS");
  std::printf("%-34s %12.3f %12.4f %12.3f %12.4f\n", "at voxel centres in the band",
              oursGrid.max / voxel, oursGrid.rms / voxel, vtkGrid.max / voxel, vtkGrid.rms / voxel);
  std::printf("%-34s %12.3f %12.4f %12.3f %12.4f\n", "at random positions (VTK trilinear)",
              oursRandom.max / voxel, oursRandom.rms / voxel, vtkRandom.max / voxel,
              vtkRandom.rms / voxel);
}

// `count` points spread at random over a sphere of radius 0.5 about the origin.
vtkSmartPointer<vtkPolyData> pointsOnASphere(std::size_t count)
{
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss;
  vtkNew<vtkPoints> xyz;
  xyz->SetDataTypeToDouble();
  xyz->SetNumberOfPoints(static_cast<vtkIdType>(count));
  for (std::size_t i = 0; i < count; ++i)
  {
    double p[3] = {gauss(rng), gauss(rng), gauss(rng)};
    const double r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (double& c : p)
      c *= 0.5 / r;
    xyz->SetPoint(static_cast<vtkIdType>(i), p);
  }
  auto cloud = vtkSmartPointer<vtkPolyData>::New();
  cloud->SetPoints(xyz);
  return cloud;
}

// The median wall time of `repeats` updates of an algorithm.
double medianUpdateSeconds(vtkAlgorithm* algorithm, std::size_t repeats)
{
  std::vector<double> t;
  for (std::size_t r = 0; r < repeats; ++r)
  {
    algorithm->Modified();
    const double start = now();
    algorithm->Update();
    t.push_back(now() - start);
  }
  return median(t);
}

// The image's distances against exact nearest-point distances at about 100 000 voxels spread
// over it (the exact search is the slow part): the errors within the band and beyond it, and how
// far any value lies below the exact distance (`below`).
void imageErrors(vtkImageData* image, vtkPolyData* cloud, double band, Errors& inBand,
                 Errors& beyond, double& below)
{
  vtkNew<vtkKdTreePointLocator> locator; // exact, and quick far from the points too
  locator->SetDataSet(cloud);
  locator->BuildLocator();
  vtkDataArray* distance = image->GetPointData()->GetArray("Distance");
  below = 0;
  const vtkIdType voxels = image->GetNumberOfPoints();
  const vtkIdType stride = std::max<vtkIdType>(7, voxels / 100000) | 1;
  for (vtkIdType id = 0; id < voxels; id += stride)
  {
    double x[3], p[3];
    image->GetPoint(id, x);
    cloud->GetPoint(locator->FindClosestPoint(x), p);
    const double exact = std::sqrt(vtkMath::Distance2BetweenPoints(x, p));
    const double error = distance->GetTuple1(id) - exact;
    below = std::max(below, -error);
    accumulate(exact <= band ? inBand : beyond, error);
  }
  finish(inBand);
  finish(beyond);
}

// The filter as users call it: vtkDistanceFieldFilter and vtkUnsignedDistance (radius 3 voxels)
// on the same points and the same image (points on a sphere of radius 0.5, the image over
// [-0.6, 0.6]^3), medians of `repeats` runs each, in one run; then ours against exact
// nearest-point distances at a sample of the image's voxels, within the band and beyond it.
void runImageCase(std::size_t pointCount, int size, std::size_t repeats, bool withVTK)
{
  const vtkSmartPointer<vtkPolyData> cloud = pointsOnASphere(pointCount);
  const double voxel = 1.2 / (size - 1), band = 3 * voxel;
  vtkNew<vtkDistanceFieldFilter> ours;
  ours->SetInputData(cloud);
  ours->SetDimensions(size, size, size);
  ours->AdjustBoundsOff();
  ours->SetBounds(-0.6, 0.6, -0.6, 0.6, -0.6, 0.6);
  ours->SetBandWidth(band);
  ours->ComputeNormalsOff();
  const double oursTime = medianUpdateSeconds(ours, repeats);
  // As a user gets it by default: with the NearestNormal array (normals estimated).
  ours->ComputeNormalsOn();
  const double withNormalsTime = medianUpdateSeconds(ours, repeats);
  double theirsTime = 0;
  if (withVTK)
  {
    vtkNew<vtkUnsignedDistance> theirs;
    theirs->SetInputData(cloud);
    theirs->SetDimensions(size, size, size);
    theirs->AdjustBoundsOff();
    theirs->SetBounds(-0.6, 0.6, -0.6, 0.6, -0.6, 0.6);
    theirs->SetRadius(band);
    theirs->CappingOn();
    theirs->SetOutputScalarTypeToFloat();
    theirsTime = medianUpdateSeconds(theirs, repeats);
  }
  Errors inBand, beyond;
  double below = 0;
  imageErrors(ours->GetOutput(), cloud, band, inBand, beyond, below);
  std::printf("%8zu points %4d^3: vtkDistanceFieldFilter %8.1f ms (%.1f ms with normals)",
              pointCount, size, 1e3 * oursTime, 1e3 * withNormalsTime);
  if (withVTK)
    std::printf(", vtkUnsignedDistance %9.1f ms, ratio %5.1fx", 1e3 * theirsTime,
                theirsTime / oursTime);
  std::printf("\n    ours vs exact, in voxels: band (<= 3 voxels) max %.2g; beyond max %.3f RMS "
              "%.4f; never below exact by more than %.2g\n",
              inBand.max / voxel, beyond.max / voxel, beyond.rms / voxel, below / voxel);
}

// The command line's settings.
struct Settings
{
  std::size_t repeats = 5, points = 20000, largePoints = 1000000;
  std::string data = "../shared/data";
  bool vtkLarge = true;
  std::vector<int> imageSizes{100, 200};
};

// Reads the command line into `settings`; returns -1 to go on, else the exit code (after the
// usage or the error is printed).
int parseArguments(int argc, char** argv, Settings& settings)
{
  using namespace dp::cli;
  try
  {
    for (int i = 1; i < argc; ++i)
    {
      const std::string arg = argv[i];
      if (arg == "--repeats")
        settings.repeats = parseCount(arg, optionValue(argc, argv, i), 1, 100);
      else if (arg == "--points")
        settings.points = parseCount(arg, optionValue(argc, argv, i), 1, 100000000);
      else if (arg == "--large-points")
        settings.largePoints = parseCount(arg, optionValue(argc, argv, i), 0, 100000000);
      else if (arg == "--data")
        settings.data = optionValue(argc, argv, i);
      else if (arg == "--image-sizes")
      {
        settings.imageSizes.clear();
        for (const std::string& v : splitList(optionValue(argc, argv, i)))
          settings.imageSizes.push_back(static_cast<int>(parseCount(arg, v, 2, 2000)));
      }
      else if (arg == "--no-vtk-large")
        settings.vtkLarge = false;
      else
      {
        std::cout << "Usage: BenchmarkDistanceField [--repeats N] [--points N] [--large-points N]"
                     " [--data DIR] [--no-vtk-large]\n"
                     "                              [--image-sizes N,N...]\n";
        return arg == "-h" || arg == "--help" ? 0 : 2;
      }
    }
  }
  catch (const UsageError& e)
  {
    std::cerr << e.what() << "\n";
    return 2;
  }
  return -1;
}

} // namespace

int main(int argc, char** argv)
{
  std::setvbuf(stdout, nullptr, _IOLBF, 0); // figures as they come, also through a pipe
  Settings settings;
  if (const int exitCode = parseArguments(argc, argv, settings); exitCode >= 0)
    return exitCode;
  const std::size_t repeats = settings.repeats, small = settings.points,
                    large = settings.largePoints;
  std::printf("machine: %s, %u hardware threads; Release build\n", cpuModel().c_str(),
              std::thread::hardware_concurrency());
  std::printf("vtkDistanceFieldFilter against vtkUnsignedDistance on the same image "
              "(sphere, radius 0.5; image [-0.6, 0.6]^3; band = radius = 3 voxels; medians of %zu; "
              "%d SMP thread(s)):\n",
              repeats, vtkSMPTools::GetEstimatedNumberOfThreads());
  for (int size : settings.imageSizes)
  {
    runImageCase(small, size, repeats, true);
    if (large > 0)
      runImageCase(large, size, std::max<std::size_t>(1, repeats / 2), settings.vtkLarge);
  }
  const Figure figure = loadFigure(settings.data, 1.7);
  const double voxel = 0.012, band = 3 * voxel;
  const int boxVoxels = 200;
  runCase(figure, small, voxel, band, boxVoxels, repeats, true);
  if (large > 0)
    runCase(figure, large, voxel, band, boxVoxels, std::max<std::size_t>(1, repeats / 2),
            settings.vtkLarge);
  return 0;
}
