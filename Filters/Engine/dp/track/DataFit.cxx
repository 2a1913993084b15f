// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/DataFit.h"

#include "dp/geometry/SurfaceLocator.h"
#include "dp/detail/Parallel.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace dp
{
namespace
{
// Rounds of coding at most; after the first, the deviation asked is this share of the one that
// would give the allowed growth; a coding within Close of the allowed fit ends the search.
constexpr int MaxRounds = 5;
constexpr double Margin = 0.97;
constexpr double Close = 0.03;
// The codec's default target, for a take with no data to keep a fit to.
constexpr double DefaultKG = 0.2;
} // namespace

DataFit measureDataFit(const TriangleMesh& mesh, const double* positions,
                       const std::vector<const FrameSamples*>& samples, double reach,
                       std::vector<std::vector<bool>>* within)
{
  const std::size_t nv = mesh.numberOfVertices();
  const bool given = within && !within->empty();
  if (within && !given)
    within->assign(samples.size(), {});
  DataFit fit;
  double sum = 0;
  for (std::size_t t = 0; t < samples.size(); ++t)
  {
    const FrameSamples* s = samples[t];
    if (!s || s->empty())
      continue;
    const SurfaceLocator locator(mesh, positions + 3 * nv * t);
    std::vector<double> d2(s->size(), -1.0);
    const double limit = given ? HUGE_VAL : reach;
    forEachIndex(s->size(),
                 [&](std::size_t i)
                 {
                   if (given && !(*within)[t][i])
                     return;
                   const SurfaceLocator::Hit hit = locator.closest(&s->points[3 * i], limit);
                   if (hit.triangle >= 0)
                     d2[i] = hit.squaredDistance;
                 });
    if (within && !given)
      (*within)[t].assign(s->size(), false);
    for (std::size_t i = 0; i < d2.size(); ++i)
    {
      if (given && !(*within)[t][i])
        continue;
      if (d2[i] < 0)
      {
        ++fit.beyondReach;
        continue;
      }
      sum += d2[i];
      ++fit.samples;
      if (within && !given)
        (*within)[t][i] = true;
    }
  }
  fit.rms = fit.samples > 0 ? std::sqrt(sum / static_cast<double>(fit.samples)) : 0.0;
  return fit;
}

namespace
{
// The tracked take every coding of compressAgainstData codes and measures against.
struct Take
{
  const TriangleMesh& mesh;
  const double* positions;
  std::size_t frames;
  const std::vector<const FrameSamples*>& samples;
  double reach;
  const std::vector<double>& times;
  const std::function<bool(double)>& progress;
};

// The take coded with `options`.
CompressedSequence codeTake(const Take& take, const PcaOptions& options)
{
  return compressSequence(take.positions, take.mesh.numberOfVertices(), take.frames, options,
                          take.mesh.triangles(), take.times, take.progress);
}

// The rounds of coding that look for the fewest bits keeping the fit within `allowed`, into
// `out` (its tracked fit measured; `within`: the samples that fit counts).
void codeInRounds(const Take& take, PcaOptions options, double allowed,
                  std::vector<std::vector<bool>>& within, DataFitCompression& out)
{
  const std::size_t nv = take.mesh.numberOfVertices();
  // A deviation d of the vertices grows f^2 by about c d^2, c about 1/3 (deviations spread
  // evenly over the three directions, only the normal one counting). Each round measures c on
  // its coding and asks for the deviation that would give the allowed growth, a little less
  // (Margin); the fewest bits that kept the fit win (else the closest fit).
  const double f2 = out.tracked.rms * out.tracked.rms;
  const double grown2 = allowed * allowed - f2;
  double c = 1.0 / 3.0;
  std::vector<double> decoded(3 * nv * take.frames);
  bool kept = false;
  for (int round = 0; round < MaxRounds; ++round)
  {
    options.target = std::sqrt(grown2 / c) * (round == 0 ? 1.0 : Margin);
    CompressedSequence coded = codeTake(take, options);
    ++out.rounds;
    for (std::size_t t = 0; t < take.frames; ++t)
      coded.pca.model.frame(t, &decoded[3 * nv * t]);
    const DataFit fit =
        measureDataFit(take.mesh, decoded.data(), take.samples, take.reach, &within);
    const bool keeps = fit.rms <= allowed;
    const double deviation = coded.report.rmsError;
    const bool better =
        keeps ? !kept || coded.report.bitsPerVertexFrame < out.sequence.report.bitsPerVertexFrame
              : !kept && (out.rounds == 1 || fit.rms < out.decompressed.rms);
    if (better)
    {
      out.sequence = std::move(coded);
      out.decompressed = fit;
      out.deviationTarget = options.target;
      kept = keeps;
    }
    if (keeps && fit.rms >= (1 - Close) * allowed)
      break; // as close to the allowed growth as the search gets
    const double measured = fit.rms * fit.rms - f2;
    // No growth at all: the deviation costs the fit nothing yet, ask for twice as much.
    c = measured > 0 && deviation > 0 ? measured / (deviation * deviation) : c / 4;
  }
}
} // namespace

DataFitCompression compressAgainstData(const TriangleMesh& mesh, const double* positions,
                                       std::size_t frames,
                                       const std::vector<const FrameSamples*>& samples,
                                       double reach, double growth, PcaOptions options,
                                       const std::vector<double>& times,
                                       const std::function<bool(double)>& progress)
{
  if (!(growth > 0) || !std::isfinite(growth))
    throw std::invalid_argument("the allowed growth of the distance to the data (" +
                                std::to_string(growth) + ") must be > 0");
  std::vector<std::vector<bool>> within;
  DataFitCompression out;
  out.tracked = measureDataFit(mesh, positions, samples, reach, &within);
  const Take take{mesh, positions, frames, samples, reach, times, progress};
  if (out.tracked.samples == 0 || !(out.tracked.rms > 0))
  {
    options.measure = PcaErrorMeasure::KarniGotsman;
    options.target = DefaultKG;
    out.sequence = codeTake(take, options);
    out.rounds = 1;
    return out;
  }
  options.measure = PcaErrorMeasure::RmsDeviation;
  codeInRounds(take, options, (1 + growth) * out.tracked.rms, within, out);
  out.growth = out.decompressed.rms / out.tracked.rms - 1;
  return out;
}

} // namespace dp
