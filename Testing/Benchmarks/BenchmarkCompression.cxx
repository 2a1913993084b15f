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
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

int main(int argc, char** argv)
{
  using namespace dp::cli;
  using namespace dp::bench;
  std::string data = "../shared/data";
  std::vector<std::string> sequences = {"horse-collapse", "horse-gallop"};
  std::vector<double> targets = {0.5, 0.2, 0.1};
  std::size_t repeats = 3;
  std::size_t tubeVertices = 0, tubeFrames = 0;
  std::vector<dp::PcaLayout> layouts = {dp::PcaLayout::Trajectories, dp::PcaLayout::Shapes};
  std::string glbFolder;
  try
  {
    for (int i = 1; i < argc; ++i)
    {
      const std::string arg = argv[i];
      if (arg == "--data")
        data = optionValue(argc, argv, i);
      else if (arg == "--sequence")
        sequences = {optionValue(argc, argv, i)};
      else if (arg == "--target")
        targets = {parseDouble(arg, optionValue(argc, argv, i), 1e-6, 99.0)};
      else if (arg == "--repeats")
        repeats = parseCount(arg, optionValue(argc, argv, i), 1, 100);
      else if (arg == "--tube-size")
      {
        const std::string value = optionValue(argc, argv, i);
        const std::size_t comma = value.find(',');
        if (comma == std::string::npos)
          throw UsageError("--tube-size wants VERTICES,FRAMES");
        tubeVertices = parseCount(arg, value.substr(0, comma), 100, 10000000);
        tubeFrames = parseCount(arg, value.substr(comma + 1), 2, 100000);
        sequences = {"tube"};
      }
      else if (arg == "--layout")
      {
        const std::string value = optionValue(argc, argv, i);
        if (value != "shapes" && value != "trajectories")
          throw UsageError("--layout is shapes or trajectories, not '" + value + "'");
        layouts = {value == "shapes" ? dp::PcaLayout::Shapes : dp::PcaLayout::Trajectories};
      }
      else if (arg == "--glb")
        glbFolder = optionValue(argc, argv, i);
      else
      {
        std::cerr << "Usage: BenchmarkCompression [--data DIR] [--sequence NAME|tube] "
                     "[--tube-size VERTICES,FRAMES] [--layout shapes|trajectories] "
                     "[--target KG_PERCENT] [--repeats N] [--glb FOLDER]\n";
        return arg == "-h" || arg == "--help" ? 0 : 2;
      }
    }
  }
  catch (const std::exception& e)
  {
    std::cerr << e.what() << "\n";
    return 2;
  }
  std::printf("machine: %s, %u hardware threads; Release build; median of %zu runs\n",
              cpuModel().c_str(), std::thread::hardware_concurrency(), repeats);
  for (const std::string& name : sequences)
  {
    std::unique_ptr<dp::AnimatedMesh> mesh;
    if (tubeVertices)
    {
      // About tubeVertices vertices: rings of 48 around the axis.
      dp::BendingTube::Options tube;
      tube.segments = 48;
      tube.rings = std::max<std::size_t>(2, tubeVertices / tube.segments);
      tube.frames = tubeFrames;
      mesh = std::make_unique<dp::BendingTube>(tube);
    }
    else
      mesh = loadAnimation(data, name);
    if (!mesh)
      continue;
    const std::size_t nv = mesh->numberOfVertices(), nt = mesh->numberOfFrames();
    std::vector<double> positions;
    positions.reserve(3 * nv * nt);
    for (std::size_t t = 0; t < nt; ++t)
    {
      const std::vector<double> p = mesh->positions(t);
      positions.insert(positions.end(), p.begin(), p.end());
    }
    std::printf("\n== %s: %zu vertices, %zu frames (raw float32: 96 bits per vertex per frame)\n",
                name.c_str(), nv, nt);
    std::printf("%6s %-12s %-14s %5s %9s %8s %9s %10s %9s\n", "KG %", "layout", "coding", "comp",
                "bpvf", "vs raw", "KG got", "ms", "peak MiB");
    for (double target : targets)
      for (dp::PcaLayout layout : layouts)
      {
        const char* layoutName = layout == dp::PcaLayout::Shapes ? "shapes" : "trajectories";
        dp::PcaOptions o;
        o.layout = layout;
        o.target = target;
        double floatBits = 0;
        for (bool quantise : {false, true})
        {
          o.quantise = quantise;
          // The codec also on one thread, interleaved with the runs on all threads (it codes
          // its candidate component counts side by side): the ratio, and the same bytes.
          std::vector<double> ms, oneThreadMs;
          dp::CompressedSequence s, oneThread;
          for (std::size_t r = 0; r < repeats; ++r)
          {
            double start = now();
            s = dp::compressSequence(positions.data(), nv, nt, o, mesh->triangles());
            ms.push_back(1000 * (now() - start));
            if (!quantise)
              continue;
            const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
            start = now();
            oneThread = dp::compressSequence(positions.data(), nv, nt, o, mesh->triangles());
            oneThreadMs.push_back(1000 * (now() - start));
          }
          const dp::PcaReport& report = s.report;
          auto row = [&](const char* coding, double bits)
          {
            std::printf("%6.2f %-12s %-14s %5zu %9.3f %7.1fx %9.4f %10.1f %9.1f\n", target,
                        layoutName, coding, report.components, bits, 96.0 / bits, report.kgError,
                        median(ms), peakMiB());
          };
          if (!quantise)
          {
            floatBits = report.bitsPerVertexFrame;
            row("float PCA", floatBits);
          }
          else
          {
            row("quantised", report.quantisedPlainBits);
            row("full codec", report.bitsPerVertexFrame);
            std::printf("%6s %-12s full codec: %.2fx fewer bits than quantised plain PCA, %.2fx "
                        "fewer than float PCA\n",
                        "", "", report.quantisedPlainBits / report.bitsPerVertexFrame,
                        floatBits / report.bitsPerVertexFrame);
            std::printf("%6s %-12s codec on one thread: %.1f ms (%.2fx the time on all "
                        "threads), the same bytes: %s\n",
                        "", "", median(oneThreadMs), median(oneThreadMs) / median(ms),
                        dp::encodeCompressedSequence(s) == dp::encodeCompressedSequence(oneThread)
                            ? "yes"
                            : "NO");
            if (!glbFolder.empty() && layout == dp::PcaLayout::Shapes)
            {
              std::filesystem::create_directories(glbFolder);
              char file[64];
              std::snprintf(file, sizeof(file), "-kg%.2f.glb", target);
              const std::string path = (std::filesystem::path(glbFolder) / (name + file)).string();
              dp::writeGlb(path, s);
              std::printf("%6s %-12s wrote %s\n", "", "", path.c_str());
            }
          }
        }
      }
  }
  return 0;
}
