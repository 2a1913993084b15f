// SPDX-License-Identifier: BSD-3-Clause
#include "dp/compress/DataFitCompression.h"

#include "dp/compress/Decomposition.h"
#include "dp/support/Parallel.h"

#include <Eigen/Core>

#include <algorithm>
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
// The slide along the surface: toward models of these shares of the components the take kept
// coded as tracked (the best share varies from take to take), in this many steps, each vertex
// moving at most this share of its mean edge length a step (larger steps bend the surface
// between the vertices, which costs fit; more small steps gain little more).
constexpr double SlideRanks[] = {0.55, 0.8};
constexpr int SlideSteps = 6;
constexpr double SlideStep = 0.15;
} // namespace

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

// Each vertex's mean edge length in the take's first frame.
std::vector<double> meanEdgeLengths(const TriangleMesh& mesh, const double* positions)
{
  std::vector<double> lengths(mesh.numberOfVertices(), 0.0);
  for (std::size_t v = 0; v < lengths.size(); ++v)
  {
    const auto& ring = mesh.neighbours(v);
    for (std::int64_t w : ring)
    {
      double d2 = 0;
      for (int c = 0; c < 3; ++c)
        d2 += std::pow(positions[3 * v + c] - positions[3 * w + c], 2);
      lengths[v] += std::sqrt(d2);
    }
    if (!ring.empty())
      lengths[v] /= static_cast<double>(ring.size());
  }
  return lengths;
}

// One step of the slide on frame `x`: each vertex moved by the part of (model - x) across its
// normal, at most `limit[v]`.
void slideFrame(const TriangleMesh& mesh, const double* model, const std::vector<double>& limit,
                double* x)
{
  const std::size_t nv = mesh.numberOfVertices();
  std::vector<double> normals(3 * nv);
  mesh.vertexNormals(x, normals.data());
  for (std::size_t v = 0; v < nv; ++v)
  {
    const double* n = &normals[3 * v];
    double move[3], across = 0, length2 = 0;
    for (int c = 0; c < 3; ++c)
      move[c] = model[3 * v + c] - x[3 * v + c];
    for (int c = 0; c < 3; ++c)
      across += move[c] * n[c];
    for (int c = 0; c < 3; ++c)
    {
      move[c] -= across * n[c];
      length2 += move[c] * move[c];
    }
    const double scale = length2 > limit[v] * limit[v] ? limit[v] / std::sqrt(length2) : 1.0;
    for (int c = 0; c < 3; ++c)
      x[3 * v + c] += scale * move[c];
  }
}

// The errors `sequence` reports, measured against the take as given (not the slid take it coded).
void measureAgainstTake(const Take& take, CompressedSequence& sequence)
{
  const std::size_t nv = take.mesh.numberOfVertices();
  const Eigen::Map<const Eigen::MatrixXd> A(take.positions, 3 * static_cast<Eigen::Index>(nv),
                                            static_cast<Eigen::Index>(take.frames));
  const Eigen::MatrixXd decoded = sequence.pca.model.reconstruct();
  PcaReport& r = sequence.report;
  r.kgError = karniGotsmanError(A, decoded);
  r.maxError = maxVertexError(A, decoded);
  r.maxErrorRelative = r.diagonal > 0 ? r.maxError / r.diagonal : 0.0;
  r.rmsError = std::sqrt((A - decoded).squaredNorm() / static_cast<double>(nv * take.frames));
}

// The coding of the take as tracked (`out`), against codings of the take slid along its surface
// toward models of fewer components (slideAlongSurface); the fewest bits that keep the fit win.
void codeSlid(const Take& take, const PcaOptions& options, double allowed,
              std::vector<std::vector<bool>>& within, DataFitCompression& out)
{
  const std::size_t kept = out.sequence.report.components;
  const PcaLayout layout = out.sequence.pca.model.layout;
  for (double rank : SlideRanks)
  {
    const auto k = static_cast<std::size_t>(std::lround(rank * static_cast<double>(kept)));
    if (k < 1)
      continue;
    const std::vector<double> slid =
        slideAlongSurface(take.mesh, take.positions, take.frames, k, layout);
    // A slide toward fewer components than the motion has moves the motion itself: the slid
    // take strays from the data before any coding, cannot keep the fit, and its coding rounds
    // would chase a target the quantiser cannot meet.
    if (measureDataFit(take.mesh, slid.data(), take.samples, take.reach, &within).rms > allowed)
      continue;
    const Take slidTake{take.mesh,  slid.data(), take.frames,  take.samples,
                        take.reach, take.times,  take.progress};
    DataFitCompression other;
    other.tracked = out.tracked;
    codeInRounds(slidTake, options, allowed, within, other);
    out.rounds += other.rounds;
    const bool keeps = other.decompressed.rms <= allowed;
    if (keeps && (out.decompressed.rms > allowed || other.sequence.report.bitsPerVertexFrame <
                                                        out.sequence.report.bitsPerVertexFrame))
    {
      out.sequence = std::move(other.sequence);
      measureAgainstTake(take, out.sequence);
      out.decompressed = other.decompressed;
      out.deviationTarget = other.deviationTarget;
      out.slid = true;
    }
  }
}
} // namespace

std::vector<double> slideAlongSurface(const TriangleMesh& mesh, const double* positions,
                                      std::size_t frames, std::size_t components, PcaLayout layout)
{
  const std::size_t nv = mesh.numberOfVertices();
  std::vector<double> slid(positions, positions + 3 * nv * frames);
  std::vector<double> limit = meanEdgeLengths(mesh, positions);
  for (double& l : limit)
    l *= SlideStep;
  for (int step = 0; step < SlideSteps; ++step)
  {
    const Eigen::Map<const Eigen::MatrixXd> A(slid.data(), 3 * static_cast<Eigen::Index>(nv),
                                              static_cast<Eigen::Index>(frames));
    const compress::Decomposition d = compress::decompose(A, layout);
    PcaModel model;
    model.layout = layout;
    model.vertices = nv;
    model.frames = frames;
    model.mean = d.mean;
    d.factors(std::min<std::size_t>(components, static_cast<std::size_t>(d.sigma.size())),
              model.basis, model.weights);
    forEachIndex(frames,
                 [&](std::size_t t)
                 {
                   std::vector<double> target(3 * nv);
                   model.frame(t, target.data());
                   slideFrame(mesh, target.data(), limit, &slid[3 * nv * t]);
                 });
  }
  return slid;
}

DataFitCompression compressAgainstData(const TriangleMesh& mesh, const double* positions,
                                       std::size_t frames,
                                       const std::vector<const FrameSamples*>& samples,
                                       double reach, double growth, PcaOptions options, bool slide,
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
  const double allowed = (1 + growth) * out.tracked.rms;
  codeInRounds(take, options, allowed, within, out);
  if (slide)
    codeSlid(take, options, allowed, within, out);
  out.growth = out.decompressed.rms / out.tracked.rms - 1;
  return out;
}

} // namespace dp
