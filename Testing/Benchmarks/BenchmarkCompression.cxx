// SPDX-License-Identifier: BSD-3-Clause
// Benchmark: PCA compression of ground-truth animated meshes (../shared/data) or the built-in
// bending tube. For each KG error target it prints, per layout: components, bits per vertex per
// frame (raw float32 = 96) and the ratio against raw, for float PCA (the paper), quantised plain
// PCA (the codec's integers in fixed-width fields) and the full codec (prediction + zstd);
// compression time (median of --repeats runs), the codec's time on one thread (interleaved; it
// codes its candidate component counts side by side) and peak memory. --tube-size builds a bigger
// tube for the memory figure; --glb writes the full codec's shape-layout export of every run (for
// Blender or a web viewer).
#include "BenchmarkSequences.h"
#include "BenchmarkUtilities.h"
#include "CommandLine.h"

#include "dp/compress/PcaCompression.h"
#include "dp/export/GltfExport.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/io/FrameSequence.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace
{
using namespace dp::bench;

// What to run.
struct Plan
{
  std::string data = "../shared/data";
  std::vector<std::string> sequences = {"horse-collapse", "horse-gallop"};
  std::vector<double> targets = {0.5, 0.2, 0.1};
  std::size_t repeats = 3;
  std::size_t tubeVertices = 0, tubeFrames = 0; // --tube-size (0: the sequences)
  std::vector<dp::PcaLayout> layouts = {dp::PcaLayout::Trajectories, dp::PcaLayout::Shapes};
  std::string glbFolder;
  std::vector<std::size_t> segments; // --segments: also code the take cut into this many parts
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
      if (arg == "--data")
        plan.data = optionValue(argc, argv, i);
      else if (arg == "--sequence")
        plan.sequences = {optionValue(argc, argv, i)};
      else if (arg == "--target")
        plan.targets = {parseDouble(arg, optionValue(argc, argv, i), 1e-6, 99.0)};
      else if (arg == "--repeats")
        plan.repeats = parseCount(arg, optionValue(argc, argv, i), 1, 100);
      else if (arg == "--tube-size")
      {
        const std::string value = optionValue(argc, argv, i);
        const std::size_t comma = value.find(',');
        if (comma == std::string::npos)
          throw UsageError("--tube-size wants VERTICES,FRAMES");
        plan.tubeVertices = parseCount(arg, value.substr(0, comma), 100, 10000000);
        plan.tubeFrames = parseCount(arg, value.substr(comma + 1), 2, 100000);
        plan.sequences = {"tube"};
      }
      else if (arg == "--layout")
      {
        const std::string value = optionValue(argc, argv, i);
        if (value != "shapes" && value != "trajectories")
          throw UsageError("--layout is shapes or trajectories, not '" + value + "'");
        plan.layouts = {value == "shapes" ? dp::PcaLayout::Shapes : dp::PcaLayout::Trajectories};
      }
      else if (arg == "--glb")
        plan.glbFolder = optionValue(argc, argv, i);
      else if (arg == "--segments")
        for (const std::string& n : splitList(optionValue(argc, argv, i)))
          plan.segments.push_back(parseCount(arg, n, 2, 1000));
      else
      {
        std::cerr << "Usage: BenchmarkCompression [--data DIR] [--sequence NAME|tube] "
                     "[--tube-size VERTICES,FRAMES] [--layout shapes|trajectories] "
                     "[--target KG_PERCENT] [--repeats N] [--glb FOLDER] "
                     "[--segments N[,N...] (also each take cut in N parts of equal length, "
                     "each part coded on its own at the whole's RMS error)]\n";
        return arg == "-h" || arg == "--help" ? 0 : 2;
      }
    }
  }
  catch (const std::exception& e)
  {
    std::cerr << e.what() << "\n";
    return 2;
  }
  return std::nullopt;
}

// The sequence to compress: --tube-size's tube (about that many vertices, rings of 48 around the
// axis), else the named sequence.
std::unique_ptr<dp::AnimatedMesh> loadSequence(const Plan& plan, const std::string& name)
{
  if (!plan.tubeVertices)
    return loadAnimation(plan.data, name);
  dp::BendingTube::Options tube;
  tube.segments = 48;
  tube.rings = std::max<std::size_t>(2, plan.tubeVertices / tube.segments);
  tube.frames = plan.tubeFrames;
  return std::make_unique<dp::BendingTube>(tube);
}

// Every frame's positions, one after another.
std::vector<double> allPositions(const dp::AnimatedMesh& mesh)
{
  std::vector<double> positions;
  positions.reserve(3 * mesh.numberOfVertices() * mesh.numberOfFrames());
  for (std::size_t t = 0; t < mesh.numberOfFrames(); ++t)
  {
    const std::vector<double> p = mesh.positions(t);
    positions.insert(positions.end(), p.begin(), p.end());
  }
  return positions;
}

// One coding of the sequence, timed over the runs: the result and its times. Quantised, the
// codec also runs on one thread, interleaved with the runs on all threads (it codes its candidate
// component counts side by side): the ratio, and the same bytes.
struct TimedCoding
{
  dp::CompressedSequence sequence, oneThread;
  std::vector<double> ms, oneThreadMs;
};

TimedCoding timeCoding(const dp::AnimatedMesh& mesh, const std::vector<double>& positions,
                       const dp::PcaOptions& o, std::size_t repeats)
{
  const std::size_t nv = mesh.numberOfVertices(), nt = mesh.numberOfFrames();
  TimedCoding c;
  for (std::size_t r = 0; r < repeats; ++r)
  {
    double start = now();
    c.sequence = dp::compressSequence(positions.data(), nv, nt, o, mesh.triangles());
    c.ms.push_back(1000 * (now() - start));
    if (!o.quantise)
      continue;
    const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    start = now();
    c.oneThread = dp::compressSequence(positions.data(), nv, nt, o, mesh.triangles());
    c.oneThreadMs.push_back(1000 * (now() - start));
  }
  return c;
}

void printRow(double target, const char* layoutName, const char* coding, double bits,
              const dp::PcaReport& report, const std::vector<double>& ms)
{
  std::printf("%6.2f %-12s %-14s %5zu %9.3f %7.1fx %9.4f %10.1f %9.1f\n", target, layoutName,
              coding, report.components, bits, 96.0 / bits, report.kgError, median(ms), peakMiB());
}

// What a player pays: the file's bytes decoded (checked, range-decoded, dequantised) and every
// frame reconstructed, per frame (median of the runs, one thread).
void printDecoding(const dp::CompressedSequence& sequence, std::size_t repeats)
{
  const std::vector<std::uint8_t> bytes = dp::encodeCompressedSequence(sequence);
  const dp::PcaModel& m = sequence.pca.model;
  const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
  std::vector<double> ms;
  std::vector<double> frame(3 * m.vertices);
  for (std::size_t r = 0; r < std::max<std::size_t>(repeats, 3); ++r)
  {
    const double start = now();
    const dp::CompressedSequence back =
        dp::decodeCompressedSequence(bytes.data(), bytes.size(), "benchmark");
    for (std::size_t t = 0; t < m.frames; ++t)
      back.pca.model.frame(t, frame.data());
    ms.push_back(1000 * (now() - start) / static_cast<double>(m.frames));
  }
  std::printf("%6s %-12s decoding: %.3f ms a frame (the file's %zu bytes, then every frame; one "
              "thread)\n",
              "", "", median(ms), bytes.size());
}

// --segments: the take cut into `parts` runs of frames, each coded on its own at the RMS error
// the whole take's coding reached; their bits against the whole's (components chosen per
// segment pay where the motion changes character within a take).
void runSegments(const dp::AnimatedMesh& mesh, const std::vector<double>& positions,
                 dp::PcaLayout layout, const dp::PcaReport& whole, std::size_t parts)
{
  const std::size_t nv = mesh.numberOfVertices(), nt = mesh.numberOfFrames();
  if (parts > nt / 2)
    return;
  dp::PcaOptions o;
  o.layout = layout;
  o.measure = dp::PcaErrorMeasure::RmsDeviation;
  o.target = whole.rmsError;
  double bits = 0, squares = 0;
  std::string components;
  for (std::size_t p = 0; p < parts; ++p)
  {
    const std::size_t first = nt * p / parts, end = nt * (p + 1) / parts;
    const dp::CompressedSequence part = dp::compressSequence(positions.data() + 3 * nv * first, nv,
                                                             end - first, o, mesh.triangles());
    bits += part.report.bitsPerVertexFrame * static_cast<double>(end - first);
    squares += part.report.rmsError * part.report.rmsError * static_cast<double>(end - first);
    components += (p ? "+" : "") + std::to_string(part.report.components);
  }
  bits /= static_cast<double>(nt);
  std::printf("%6s %-12s %zu segments: %s components, %.3f bpvf (%.2fx the whole take's), RMS "
              "error %.3g (the whole's %.3g)\n",
              "", "", parts, components.c_str(), bits, bits / whole.bitsPerVertexFrame,
              std::sqrt(squares / static_cast<double>(nt)), whole.rmsError);
}

// The rows of one error target and layout: float PCA (the paper), then quantised plain PCA and
// the full codec, with the codec's gain, its time on one thread and, with --glb, its export.
void runLayout(const std::string& name, const dp::AnimatedMesh& mesh,
               const std::vector<double>& positions, double target, dp::PcaLayout layout,
               const Plan& plan)
{
  const char* layoutName = layout == dp::PcaLayout::Shapes ? "shapes" : "trajectories";
  dp::PcaOptions o;
  o.layout = layout;
  o.target = target;
  o.quantise = false;
  const TimedCoding plain = timeCoding(mesh, positions, o, plan.repeats);
  const double floatBits = plain.sequence.report.bitsPerVertexFrame;
  printRow(target, layoutName, "float PCA", floatBits, plain.sequence.report, plain.ms);
  o.quantise = true;
  const TimedCoding coded = timeCoding(mesh, positions, o, plan.repeats);
  const dp::PcaReport& report = coded.sequence.report;
  printRow(target, layoutName, "quantised", report.quantisedPlainBits, report, coded.ms);
  printRow(target, layoutName, "full codec", report.bitsPerVertexFrame, report, coded.ms);
  std::printf("%6s %-12s full codec: %.2fx fewer bits than quantised plain PCA, %.2fx "
              "fewer than float PCA\n",
              "", "", report.quantisedPlainBits / report.bitsPerVertexFrame,
              floatBits / report.bitsPerVertexFrame);
  std::printf("%6s %-12s codec on one thread: %.1f ms (%.2fx the time on all "
              "threads), the same bytes: %s\n",
              "", "", median(coded.oneThreadMs), median(coded.oneThreadMs) / median(coded.ms),
              dp::encodeCompressedSequence(coded.sequence) ==
                      dp::encodeCompressedSequence(coded.oneThread)
                  ? "yes"
                  : "NO");
  printDecoding(coded.sequence, plan.repeats);
  for (std::size_t parts : plan.segments)
    runSegments(mesh, positions, layout, report, parts);
  if (plan.glbFolder.empty() || layout != dp::PcaLayout::Shapes)
    return;
  std::filesystem::create_directories(plan.glbFolder);
  char file[64];
  std::snprintf(file, sizeof(file), "-kg%.2f.glb", target);
  const std::string path = (std::filesystem::path(plan.glbFolder) / (name + file)).string();
  dp::writeGlb(path, coded.sequence);
  std::printf("%6s %-12s wrote %s\n", "", "", path.c_str());
}

} // namespace

int main(int argc, char** argv)
{
  Plan plan;
  if (const std::optional<int> status = parseArguments(argc, argv, plan))
    return *status;
  std::printf("machine: %s, %u hardware threads; Release build; median of %zu runs\n",
              cpuModel().c_str(), std::thread::hardware_concurrency(), plan.repeats);
  for (const std::string& name : plan.sequences)
  {
    const std::unique_ptr<dp::AnimatedMesh> mesh = loadSequence(plan, name);
    if (!mesh)
      continue;
    const std::vector<double> positions = allPositions(*mesh);
    std::printf("\n== %s: %zu vertices, %zu frames (raw float32: 96 bits per vertex per frame)\n",
                name.c_str(), mesh->numberOfVertices(), mesh->numberOfFrames());
    std::printf("%6s %-12s %-14s %5s %9s %8s %9s %10s %9s\n", "KG %", "layout", "coding", "comp",
                "bpvf", "vs raw", "KG got", "ms", "peak MiB");
    for (double target : plan.targets)
      for (dp::PcaLayout layout : plan.layouts)
        runLayout(name, *mesh, positions, target, layout, plan);
  }
  return 0;
}
