// SPDX-License-Identifier: BSD-3-Clause
// Benchmark: reading a point sequence through vtkPointSequenceSource, against parsing the same
// files directly with the engine, and the process memory as the sequence plays.
//
// Default settings: 200 frames of 20k points (binary PLY with
// normals, made by the sampler on the built-in bending tube). Prints medians of --repeats runs.
#include "BenchmarkUtilities.h"
#include "CommandLine.h"

#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/io/FrameSequence.h"
#include "dp/io/PointCloudIO.h"

#include "vtkNew.h"
#include "vtkPointSequenceSource.h"
#include "vtkPolyData.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <sys/resource.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace
{
using namespace dp::bench;

const char* const Usage =
    R"(Usage: BenchmarkReadSequence [--frames N] [--points N] [--repeats N] [--dir DIR]

Times reading every frame of a binary PLY point sequence through vtkPointSequenceSource,
against parsing the same files with the engine (dp::readPLY), and reports memory.
The sequence is generated in DIR (default: /tmp/dynamicpoints-bench-read) if absent.
)";

struct Plan
{
  std::size_t frames = 200, points = 20000, repeats = 5;
  std::string dir = "/tmp/dynamicpoints-bench-read";
};

// Reads the command line into `plan`; an exit status when the benchmark should stop there.
std::optional<int> parseArguments(int argc, char** argv, Plan& plan)
{
  using namespace dp::cli;
  try
  {
    for (int i = 1; i < argc; ++i)
    {
      const std::string arg = argv[i];
      if (arg == "--frames")
        plan.frames = parseCount(arg, optionValue(argc, argv, i), 1, 100000);
      else if (arg == "--points")
        plan.points = parseCount(arg, optionValue(argc, argv, i), 1, 100000000);
      else if (arg == "--repeats")
        plan.repeats = parseCount(arg, optionValue(argc, argv, i), 1, 1000);
      else if (arg == "--dir")
        plan.dir = optionValue(argc, argv, i);
      else
      {
        std::cout << Usage;
        return arg == "-h" || arg == "--help" ? 0 : 2;
      }
    }
  }
  catch (const UsageError& e)
  {
    std::cerr << e.what() << "\n" << Usage;
    return 2;
  }
  return std::nullopt;
}

// The sequence's .series file, the sequence sampled on the bending tube first when absent.
std::string sampledSequence(const Plan& plan)
{
  const std::string dir =
      plan.dir + "/" + std::to_string(plan.frames) + "x" + std::to_string(plan.points);
  const std::string series = dir + "/points.series";
  if (!std::filesystem::exists(series))
  {
    std::cout << "generating " << plan.frames << " frames x " << plan.points << " points in " << dir
              << "\n";
    dp::BendingTube::Options tube;
    tube.frames = plan.frames;
    dp::SamplerOptions sampling;
    sampling.pointsPerFrame = plan.points;
    dp::writeSampledSequence(dp::BendingTube(tube), sampling, dir);
  }
  return series;
}

// Per-frame times of each run (seconds) and the resident memory the first run saw.
struct ReadTimes
{
  std::vector<double> parse, source, reverse;
  double rssBefore = 0, rssAfterFirstFrames = 0, rssAtEnd = 0;
};

// Times parsing every frame, then reading them through the source in order and in reverse;
// false (said on stderr) when the two ways count different points.
bool timeReads(const dp::FrameSequence& sequence, const std::string& series, std::size_t repeats,
               ReadTimes& t)
{
  const double frames = static_cast<double>(sequence.size());
  t.rssBefore = residentMiB();
  for (std::size_t r = 0; r < repeats; ++r)
  {
    double start = now();
    std::size_t total = 0;
    for (const auto& f : sequence.frames())
      total += dp::readPLY(f.path).numberOfPoints();
    t.parse.push_back((now() - start) / frames);

    vtkNew<vtkPointSequenceSource> source;
    source->SetFileName(series.c_str());
    source->UpdateInformation();
    start = now();
    std::size_t viaSource = 0;
    for (std::size_t f = 0; f < sequence.size(); ++f)
    {
      source->UpdateTimeStep(sequence[f].time);
      viaSource += static_cast<std::size_t>(source->GetOutput()->GetNumberOfPoints());
      if (r == 0 && f == std::min<std::size_t>(9, sequence.size() - 1))
        t.rssAfterFirstFrames = residentMiB();
    }
    t.source.push_back((now() - start) / frames);
    if (r == 0)
      t.rssAtEnd = residentMiB();

    start = now();
    for (std::size_t f = sequence.size(); f-- > 0;)
      source->UpdateTimeStep(sequence[f].time);
    t.reverse.push_back((now() - start) / frames);
    if (viaSource != total)
    {
      std::cerr << "point counts differ: " << viaSource << " via the source, " << total
                << " parsed directly\n";
      return false;
    }
  }
  return true;
}

void printTimes(const ReadTimes& t, std::size_t frames)
{
  const double parse = median(t.parse), source = median(t.source), reverse = median(t.reverse);
  std::printf("%-44s %10s %10s\n", "per frame", "ms", "frames/s");
  std::printf("%-44s %10.3f %10.1f\n", "engine parse only (dp::readPLY)", 1e3 * parse, 1 / parse);
  std::printf("%-44s %10.3f %10.1f\n", "vtkPointSequenceSource, frames in order", 1e3 * source,
              1 / source);
  std::printf("%-44s %10.3f %10.1f\n", "vtkPointSequenceSource, frames in reverse", 1e3 * reverse,
              1 / reverse);
  std::printf("\nsource / parse time ratio: %.2f (in order), %.2f (reverse)\n", source / parse,
              reverse / parse);
  std::printf("memory: resident %.1f MiB before, %.1f MiB after frame 10, %.1f MiB after frame "
              "%zu (growth over the sequence %.1f MiB); peak %.1f MiB\n",
              t.rssBefore, t.rssAfterFirstFrames, t.rssAtEnd, frames,
              t.rssAtEnd - t.rssAfterFirstFrames, peakMiB());
}

} // namespace

int main(int argc, char** argv)
{
  Plan plan;
  if (const std::optional<int> status = parseArguments(argc, argv, plan))
    return *status;
  const std::string series = sampledSequence(plan);
  const dp::FrameSequence sequence = dp::FrameSequence::fromSeriesFile(series);
  std::uintmax_t bytes = 0;
  for (const auto& f : sequence.frames())
    bytes += std::filesystem::file_size(f.path);
  std::printf("machine: %s, %u hardware threads; single-threaded reads\n", cpuModel().c_str(),
              std::thread::hardware_concurrency());
  std::printf("input: %zu frames x %zu points, binary little-endian PLY with normals, %.1f MiB "
              "(%.0f kB per frame)\n",
              sequence.size(), plan.points, static_cast<double>(bytes) / (1 << 20),
              static_cast<double>(bytes) / 1024.0 / static_cast<double>(sequence.size()));
  std::printf("repeats: %zu (medians shown; the files are in the page cache after the first)\n\n",
              plan.repeats);
  ReadTimes times;
  if (!timeReads(sequence, series, plan.repeats, times))
    return 1;
  printTimes(times, sequence.size());
  return 0;
}
