// SPDX-License-Identifier: BSD-3-Clause
#include "JobSummary.h"

#include "Console.h"

#include "dp/compress/CompressionFigures.h"

#include "vtkPolyData.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>

namespace dp::cli
{

namespace
{
namespace fs = std::filesystem;

// The codec's figures in report.json's "compression": each of dp::CompressionFigures the
// filter's output carries, by its name.
void recordCompression(vtkPolyData* result, const JobPaths& paths, JobState& job)
{
  for (const dp::CompressionFigures::Field& field : dp::CompressionFigures::fields())
  {
    const double value = fieldValue(result, field.name);
    if (!std::isnan(value))
      job.compression[field.name] =
          field.count ? nlohmann::json(std::llround(value)) : nlohmann::json(value);
  }
  // The input as raw points: float32 x y z, and r g b bytes where the file keeps colour.
  const double bytesPerPoint = job.compression.contains("ColourBytes") ? 15.0 : 12.0;
  double rawBytes = 0;
  for (const FrameRecord& r : job.records)
    rawBytes += bytesPerPoint * r.figures.points;
  job.compression["Bytes"] = fs::file_size(paths.dpz);
  job.compression["InputPointBytes"] = rawBytes;
  job.compression["InputPointsOverFile"] = rawBytes / static_cast<double>(fs::file_size(paths.dpz));
}

// The detail layer's share of the file and what it costs in fit.
void sayDetail(vtkPolyData* result, const dp::CompressedSequence& sequence, const JobPaths& paths,
               JobState& job)
{
  nlohmann::json d = {{"levels", job.detailLevels},
                      {"bytes", sequence.report.detailBytes},
                      {"step", sequence.detail.step},
                      {"fineVertices", job.fineVertices}};
  const double before = fieldValue(result, "DetailDistanceToDataInput");
  const double after = fieldValue(result, "DetailDistanceToDataDecompressed");
  if (std::isfinite(before))
  {
    d["distanceToPointsFitted"] = before;
    d["distanceToPointsDecompressed"] = after;
    d["fitGrowthPercent"] = fieldValue(result, "DetailDistanceToDataGrowth");
  }
  job.compression["detail"] = d;
  std::printf("Detail layer: %zu of the file's %lld bytes (%d level(s), %lld vertices, step %.3g)",
              sequence.report.detailBytes, static_cast<long long>(fs::file_size(paths.dpz)),
              job.detailLevels, job.fineVertices, sequence.detail.step);
  if (std::isfinite(before))
    std::printf("; the decompressed fine mesh lies %.3g from the points (RMS), the fitted one "
                "%.3g (%+.1f %%)",
                after, before, d["fitGrowthPercent"].get<double>());
  std::printf("\n");
}

// The compressed file's name for the "Compressed:" line, with its colour's share when it has
// colour.
std::string dpzSaid(const dp::CompressionOptions& options, const JobPaths& paths,
                    const nlohmann::json& compression)
{
  if (!compression.contains("ColourBytes"))
    return paths.dpz.string();
  return paths.dpz.string() +
         " (with colour: " + std::to_string(compression["ColourBytes"].get<long long>()) +
         " of its " + std::to_string(compression["Bytes"].get<long long>()) + " bytes, " +
         (options.colourTolerance > 0
              ? "within " + std::to_string(options.colourTolerance) + " levels"
              : std::string("lossless")) +
         ")";
}

// The "Compressed:" line judged against the data: the decompressed mesh's distance to the points
// beside the tracked mesh's.
void sayDataFit(vtkPolyData* result, const dp::CompressionOptions& options, const JobPaths& paths,
                JobState& job)
{
  const double before = fieldValue(result, "DistanceToDataInput");
  const double after = fieldValue(result, "DistanceToDataDecompressed");
  const double growth = fieldValue(result, "DistanceToDataGrowth");
  job.compression["Target"] = dp::targetSaid(options);
  job.compression["FitGrowthAllowedPercent"] = options.fitGrowth;
  job.compression["DistanceToPointsTracked"] = before;
  job.compression["DistanceToPointsDecompressed"] = after;
  job.compression["FitGrowthPercent"] = growth;
  std::printf("Compressed: %s, %.0f components, %.3g bits per vertex per frame, %.0fx smaller "
              "than the input points (float32 x y z%s); the decompressed mesh lies %.3g from "
              "the points (RMS), the tracked one %.3g (%+.1f %%, at most %g %%)\n",
              dpzSaid(options, paths, job.compression).c_str(),
              job.compression["Components"].get<double>(),
              job.compression["BitsPerVertexFrame"].get<double>(),
              job.compression["InputPointsOverFile"].get<double>(),
              job.compression.contains("ColourBytes") ? ", r g b bytes" : "", after, before, growth,
              options.fitGrowth);
}

// The "Compressed:" line judged against the motion (KG error), and what a weak compression means.
void sayMotionFit(const dp::CompressedSequence& sequence, const dp::CompressionOptions& options,
                  const JobPaths& paths, JobState& job)
{
  const bool weak =
      job.written.size() >= 8 && job.compression["ComponentsPerFrame"].get<double>() > 0.5;
  job.compression["weak"] = weak;
  if (weak)
    job.compression["note"] = "most of the frames' worth of components were kept: the motion is "
                              "not low-rank, the tracking shakes, or the KG target asks for more "
                              "than the data's noise (the default target is the data's)";
  job.compression["Target"] = dp::targetSaid(options);
  std::printf("Compressed: %s, %zu components, %.3g bits per vertex per frame (%.1fx "
              "smaller than float32), KG error %.3g%%\n",
              dpzSaid(options, paths, job.compression).c_str(), sequence.report.components,
              sequence.report.bitsPerVertexFrame, 96.0 / sequence.report.bitsPerVertexFrame,
              sequence.report.kgError);
  if (weak)
    std::printf("Compression is weak: %zu components for %zu frames (the motion is not "
                "low-rank, the tracking shakes, or %s asks for more than the data's noise: "
                "without --error-target the target is the data's)\n",
                sequence.report.components, job.written.size(), dp::targetSaid(options).c_str());
}

} // namespace

void summariseTracking(const JobPaths& paths, const JobState& job)
{
  if (Interrupted)
    std::cerr << "interrupted: " << job.written.size() << " of " << job.frames
              << " frame(s) tracked, in " << paths.pvd.string() << "; nothing compressed\n";
  else if (job.detailLevels > 0)
    std::cout << job.written.size() << " of " << job.frames
              << " frame(s) tracked: " << paths.pvd.string() << " (" << job.fineVertices
              << " vertices: " << job.detailLevels << " level(s) of detail over the tracked mesh's "
              << job.meshVertices << ")\n";
  else
    std::cout << job.written.size() << " of " << job.frames
              << " frame(s) tracked: " << paths.pvd.string() << " (" << job.meshVertices
              << " vertices, " << job.meshTriangles << " triangles)\n";
  std::string failed;
  for (const FrameRecord& r : job.records)
    if (r.failed())
      failed += (failed.empty() ? "" : ", ") + std::to_string(r.frame);
  if (!failed.empty())
    std::cerr << "warning: frame(s) " << failed
              << " failed after retries (mesh and points do not match there): do not trust "
                 "them; report.json and report.png mark them\n";
}

void sayCompression(vtkPolyData* result, const dp::CompressedSequence& sequence,
                    const dp::CompressionOptions& options, const JobPaths& paths, JobState& job)
{
  recordCompression(result, paths, job);
  if (job.detailLevels > 0)
    sayDetail(result, sequence, paths, job);
  if (options.measure == dp::CompressionMeasure::DistanceToData)
    sayDataFit(result, options, paths, job);
  else
    sayMotionFit(sequence, options, paths, job);
}

void sayGlb(const JobPaths& paths, const JobState& job)
{
  if (job.glbWritten.level == 0)
    std::printf("glTF: %s (the tracked mesh, %zu morph targets)\n", paths.glb.string().c_str(),
                job.glbWritten.shapes);
  else
    std::printf("glTF: %s (detail level %d of %d: %zu vertices, %zu morph targets, %.1f MB)\n",
                paths.glb.string().c_str(), job.glbWritten.level, job.detailLevels,
                job.glbWritten.vertices, job.glbWritten.shapes,
                static_cast<double>(fs::file_size(paths.glb)) / 1e6);
}

} // namespace dp::cli
