// SPDX-License-Identifier: BSD-3-Clause
// BenchmarkTracker's take-level figures: what a tracked take costs to compress beside the true
// motion of the same template, and how far each decompressed take lies from the data.
#pragma once

#include "dp/compress/DataFitCompression.h"
#include "dp/compress/PcaCompression.h"
#include "dp/geometry/TriangleMesh.h"
#include "dp/track/Tracker.h"

#include <cmath>
#include <cstdio>
#include <vector>

namespace dp::bench
{

/** One take compressed: its size and its distance to the data before and after (the codec's own
 *  figures are dp::CompressionFigures; these are the benchmark's, beside the truth). */
struct TakeCompression
{
  std::size_t components = 0;
  double bitsPerVertexFrame = 0;
  std::size_t bytes = 0;   // the .dpz file
  double rmsDeviation = 0; // of the decompressed vertices (world units)
  DataFit before, after;   // the samples' distance to the take and to the decompressed take
  int rounds = 1;
  // Given the true motion: the take's RMS vertex error against it, and the decompressed take's.
  double truthErrorBefore = std::nan(""), truthErrorAfter = std::nan("");
};

/** Frame-major positions of a take given frame by frame. */
inline std::vector<double> frameMajor(const std::vector<std::vector<double>>& frames)
{
  std::vector<double> all;
  for (const std::vector<double>& f : frames)
    all.insert(all.end(), f.begin(), f.end());
  return all;
}

/** The take compressed at a KG target (shapes, as the main job stores it). */
inline TakeCompression compressAtKG(const TriangleMesh& mesh, const std::vector<double>& take,
                                    const std::vector<const FrameSamples*>& samples, double reach,
                                    double kg)
{
  const std::size_t nv = mesh.numberOfVertices(), frames = take.size() / (3 * nv);
  PcaOptions options;
  options.layout = PcaLayout::Shapes; // the table's KG column: the shape layout
  options.target = kg;
  const CompressedSequence c = compressSequence(take.data(), nv, frames, options, mesh.triangles());
  std::vector<double> decoded(take.size());
  for (std::size_t t = 0; t < frames; ++t)
    c.pca.model.frame(t, &decoded[3 * nv * t]);
  TakeCompression f;
  f.components = c.report.components;
  f.bitsPerVertexFrame = c.report.bitsPerVertexFrame;
  f.bytes = encodeCompressedSequence(c).size();
  f.rmsDeviation = c.report.rmsError;
  std::vector<std::vector<bool>> within;
  f.before = measureDataFit(mesh, take.data(), samples, reach, &within);
  f.after = measureDataFit(mesh, decoded.data(), samples, reach, &within);
  return f;
}

/** The take compressed against its data (dp::compressAgainstData, the main job's default). */
inline TakeCompression compressForData(const TriangleMesh& mesh, const std::vector<double>& take,
                                       const std::vector<const FrameSamples*>& samples,
                                       double reach, double growth,
                                       PcaLayout layout = PcaLayout::Shapes,
                                       const std::vector<double>* truth = nullptr,
                                       bool slide = true)
{
  const std::size_t nv = mesh.numberOfVertices(), frames = take.size() / (3 * nv);
  PcaOptions options;
  options.layout = layout;
  const DataFitCompression c =
      compressAgainstData(mesh, take.data(), frames, samples, reach, growth, options, slide);
  TakeCompression f;
  f.components = c.sequence.report.components;
  f.bitsPerVertexFrame = c.sequence.report.bitsPerVertexFrame;
  f.bytes = encodeCompressedSequence(c.sequence).size();
  f.rmsDeviation = c.sequence.report.rmsError;
  f.before = c.tracked;
  f.after = c.decompressed;
  f.rounds = c.rounds;
  if (truth)
  {
    std::vector<double> decoded(take.size());
    for (std::size_t t = 0; t < frames; ++t)
      c.sequence.pca.model.frame(t, &decoded[3 * nv * t]);
    double before = 0, after = 0;
    for (std::size_t i = 0; i < take.size(); i += 3)
    {
      double b = 0, a = 0;
      for (int k = 0; k < 3; ++k)
      {
        b += std::pow(take[i + k] - (*truth)[i + k], 2);
        a += std::pow(decoded[i + k] - (*truth)[i + k], 2);
      }
      before += b;
      after += a;
    }
    f.truthErrorBefore = std::sqrt(before / (take.size() / 3.0));
    f.truthErrorAfter = std::sqrt(after / (take.size() / 3.0));
  }
  return f;
}

inline void printCompression(const char* what, const TakeCompression& f, double rawBytes)
{
  std::printf("%14s %-22s %4zu comp. %6.2f bpvf, deviation %5.2f mm, data %5.2f -> %5.2f mm "
              "(%+5.1f %%), raw points / file %6.0fx\n",
              "", what, f.components, f.bitsPerVertexFrame, 1e3 * f.rmsDeviation,
              1e3 * f.before.rms, 1e3 * f.after.rms,
              f.before.rms > 0 ? 100 * (f.after.rms / f.before.rms - 1) : 0.0,
              rawBytes / static_cast<double>(f.bytes));
  if (std::isfinite(f.truthErrorBefore))
    std::printf("%14s %-22s vertex error against the truth %5.2f -> %5.2f mm\n", "", "",
                1e3 * f.truthErrorBefore, 1e3 * f.truthErrorAfter);
}

} // namespace dp::bench
