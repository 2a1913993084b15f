// SPDX-License-Identifier: BSD-3-Clause
#include "dp/detail/DetailCompression.h"

#include "dp/compress/DetailCoding.h"
#include "dp/geometry/TriangleMesh.h"
#include "dp/support/Parallel.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace dp
{
namespace
{

constexpr int MaxRounds = 5;
// The search's rounds measure the fit on about this many frames spread over the take; the step
// found is checked on every frame.
constexpr std::size_t SearchFrames = 30;
constexpr double Margin = 0.97;
constexpr double Close = 0.03;
// Below this cosine between the two normals the carried displacement is a plain projection.
constexpr double CarryCosine = 0.5;

double dot(const double* a, const double* b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// The fine meshes of a frame: the fitted one on the tracked base, and the decoded base's
// subdivided positions and normals.
struct FrameMeshes
{
  std::vector<double> fitted, fittedNormals, decoded, decodedNormals;
};

void fittedFrame(const FittedDetail& d, std::size_t t, std::vector<double>& fine,
                 std::vector<double>& normals)
{
  const std::size_t n = d.map.fineVertices();
  std::vector<double> smooth(3 * n);
  fine.resize(3 * n);
  normals.resize(3 * n);
  d.map.subdivide(d.base + 3 * d.map.baseVertices() * t, smooth.data(), normals.data());
  displaceAlongNormals(smooth.data(), normals.data(), d.displacements + n * t, n, fine.data());
}

// The take's fit to its samples with frame t's fine positions given by `frame`, on every
// `stride`-th frame; the samples `within` marks (empty: all within reach, recorded).
DataFit fineFit(const FittedDetail& d, const TriangleMesh& mesh,
                const std::vector<const FrameSamples*>& samples, double reach,
                std::vector<std::vector<bool>>& within,
                const std::function<void(std::size_t, std::vector<double>&)>& frame,
                std::size_t stride = 1)
{
  const bool first = within.empty();
  if (first)
    within.resize(d.frames);
  double sum = 0;
  DataFit total;
  std::vector<double> positions;
  for (std::size_t t = 0; t < d.frames; t += stride)
  {
    if (!samples[t] || samples[t]->empty())
      continue;
    frame(t, positions);
    std::vector<std::vector<bool>> mask;
    if (!first)
      mask.push_back(within[t]);
    const DataFit f = measureDataFit(mesh, positions.data(), {samples[t]}, reach, &mask);
    if (first)
      within[t] = mask[0];
    sum += f.rms * f.rms * static_cast<double>(f.samples);
    total.samples += f.samples;
    total.beyondReach += f.beyondReach;
  }
  total.rms = total.samples > 0 ? std::sqrt(sum / static_cast<double>(total.samples)) : 0.0;
  return total;
}

void checkFrames(const FittedDetail& d, const CompressedSequence& s)
{
  if (d.frames != s.pca.model.frames || d.map.baseVertices() != s.pca.model.vertices)
    throw std::invalid_argument("the detail layer has " + std::to_string(d.frames) +
                                " frames of a " + std::to_string(d.map.baseVertices()) +
                                "-vertex base; the sequence " + std::to_string(s.pca.model.frames) +
                                " of " + std::to_string(s.pca.model.vertices));
}

// Throws std::runtime_error("aborted") where `progress` asks to stop at `fraction` done.
void reportProgress(const std::function<bool(double)>& progress, double fraction)
{
  if (progress && !progress(fraction))
    throw std::runtime_error("aborted");
}

// Refuses a growth that is not a positive number and samples of another frame count.
void checkSearch(const FittedDetail& detail, const std::vector<const FrameSamples*>& samples,
                 double growth)
{
  if (!(growth > 0) || !std::isfinite(growth))
    throw std::invalid_argument("the allowed growth of the distance to the data (" +
                                std::to_string(growth) + ") must be > 0");
  if (samples.size() != detail.frames)
    throw std::invalid_argument("samples for " + std::to_string(samples.size()) +
                                " frames; the detail layer has " + std::to_string(detail.frames));
}

/**
 * The fits to a take's samples that the step search measures: the fitted fine mesh's, and the
 * decoded base's subdivided and displaced by given values; on every stride-th frame. The samples
 * within reach are those of the first fit measured, for every fit after it.
 */
class FineFits
{
public:
  FineFits(const CompressedSequence& sequence, const FittedDetail& detail, const TriangleMesh& mesh,
           const std::vector<const FrameSamples*>& samples, double reach)
      : Sequence(sequence), Detail(detail), Mesh(mesh), Samples(samples), Reach(reach),
        Base(3 * detail.map.baseVertices()), Smooth(3 * detail.map.fineVertices()),
        Normals(3 * detail.map.fineVertices())
  {
  }

  const FittedDetail& detail() const { return Detail; }

  // The fitted fine meshes' fit.
  DataFit fitted(std::size_t stride)
  {
    return fineFit(
        Detail, Mesh, Samples, Reach, Within,
        [&](std::size_t t, std::vector<double>& x) { fittedFrame(Detail, t, x, Scratch); }, stride);
  }

  // The decoded fine meshes' fit for displacements `values` (per fine vertex and frame).
  DataFit decoded(const std::vector<double>& values, std::size_t stride)
  {
    const SubdivisionMap& map = Detail.map;
    const std::size_t n = map.fineVertices();
    return fineFit(
        Detail, Mesh, Samples, Reach, Within,
        [&](std::size_t t, std::vector<double>& x)
        {
          Sequence.pca.model.frame(t, Base.data());
          map.subdivide(Base.data(), Smooth.data(), Normals.data());
          x.resize(3 * n);
          displaceAlongNormals(Smooth.data(), Normals.data(), &values[n * t], n, x.data());
        },
        stride);
  }

private:
  const CompressedSequence& Sequence;
  const FittedDetail& Detail;
  const TriangleMesh& Mesh;
  const std::vector<const FrameSamples*>& Samples;
  double Reach;
  std::vector<std::vector<bool>> Within;
  std::vector<double> Scratch, Base, Smooth, Normals;
};

// The search's rounds on every stride-th frame: each step from the deviation the allowed growth
// over `searched` (the fitted mesh's fit on those frames) leaves, over the cost of a step measured
// the round before. Returns the largest step that kept the fit, else the closest one found, else
// (a take without samples) a thousandth of the reach; counts the rounds in `out`.
double searchStep(FineFits& fits, const std::vector<double>& carried, const DataFit& searched,
                  std::size_t stride, double growth, double reach,
                  const std::function<bool(double)>& progress, DetailCompression& out)
{
  const FittedDetail& detail = fits.detail();
  const double f2 = searched.rms * searched.rms;
  const double allowed = (1 + growth) * searched.rms;
  double c = 1, best = 0, closest = HUGE_VAL, closestStep = 0;
  for (int round = 0; round < MaxRounds && searched.samples > 0; ++round)
  {
    const double deviation2 = (allowed * allowed - f2) / c * (round == 0 ? 1.0 : Margin * Margin);
    const double step = std::sqrt(12 * deviation2);
    const DataFit fit =
        fits.decoded(quantiseDetail(detail.map, carried.data(), detail.frames, step), stride);
    ++out.rounds;
    reportProgress(progress, 0.2 + 0.7 * (round + 1) / MaxRounds);
    if (fit.rms <= allowed && step > best)
    {
      best = step;
      out.decompressed = fit;
    }
    if (fit.rms < closest)
    {
      closest = fit.rms;
      closestStep = step;
    }
    if (fit.rms <= allowed && fit.rms >= (1 - Close) * allowed)
      break;
    const double measured = fit.rms * fit.rms - f2;
    c = measured > 0 ? measured / (step * step / 12) : c / 4;
  }
  // No step kept the fit (the carrying over alone grew it): the closest one found, or for a take
  // without samples a step of a thousandth of the reach.
  if (best == 0)
    best = closestStep > 0 ? closestStep : 1e-3 * reach;
  return best;
}

// The step checked on every frame; where the frames the search measured were kinder than the
// take, it is made smaller until the take keeps the fit. Sets out.decompressed.
double checkedOnEveryFrame(FineFits& fits, const std::vector<double>& carried, double step,
                           double growth, DetailCompression& out)
{
  const FittedDetail& detail = fits.detail();
  for (int check = 0;; ++check)
  {
    const std::vector<double> decoded =
        quantiseDetail(detail.map, carried.data(), detail.frames, step);
    out.decompressed = fits.decoded(decoded, 1);
    if (out.decompressed.rms <= (1 + growth) * out.fitted.rms || check == MaxRounds)
      break;
    step *= Margin * Margin;
  }
  return step;
}

} // namespace

std::vector<double> carriedToDecodedBase(const FittedDetail& d, const CompressedSequence& s)
{
  checkFrames(d, s);
  const std::size_t n = d.map.fineVertices();
  std::vector<double> carried(n * d.frames);
  std::vector<double> base(3 * d.map.baseVertices()), fitted, fittedNormals(3 * n), smooth(3 * n),
      normals(3 * n);
  for (std::size_t t = 0; t < d.frames; ++t)
  {
    fittedFrame(d, t, fitted, normals);
    vertexNormalsOf(d.map.fineTriangles(), fitted.data(), n, fittedNormals.data());
    s.pca.model.frame(t, base.data());
    d.map.subdivide(base.data(), smooth.data(), normals.data());
    double* out = &carried[n * t];
    forEachIndex(n,
                 [&](std::size_t i)
                 {
                   const double e[3] = {fitted[3 * i] - smooth[3 * i],
                                        fitted[3 * i + 1] - smooth[3 * i + 1],
                                        fitted[3 * i + 2] - smooth[3 * i + 2]};
                   const double* m = &fittedNormals[3 * i];
                   const double* nn = &normals[3 * i];
                   const double c = dot(nn, m);
                   out[i] = c > CarryCosine ? dot(e, m) / c : dot(e, nn);
                 });
  }
  return carried;
}

DetailCompression compressDetailAgainstData(CompressedSequence& sequence,
                                            const FittedDetail& detail,
                                            const std::vector<const FrameSamples*>& samples,
                                            double reach, double growth,
                                            const std::function<bool(double)>& progress)
{
  checkSearch(detail, samples, growth);
  const std::vector<double> carried = carriedToDecodedBase(detail, sequence);
  const SubdivisionMap& map = detail.map;
  const TriangleMesh mesh(map.fineTriangles(), map.fineVertices());
  FineFits fits(sequence, detail, mesh, samples, reach);
  DetailCompression out;
  out.fitted = fits.fitted(1);
  reportProgress(progress, 0.2);
  // The search measures every stride-th frame, against the fitted mesh's fit on the same frames.
  const std::size_t stride = std::max<std::size_t>(1, detail.frames / SearchFrames);
  const DataFit searched = stride == 1 ? out.fitted : fits.fitted(stride);
  double best = searchStep(fits, carried, searched, stride, growth, reach, progress, out);
  best = checkedOnEveryFrame(fits, carried, best, growth, out);
  setDetail(sequence, map.levels(), carried, best);
  out.growth = out.fitted.rms > 0 ? out.decompressed.rms / out.fitted.rms - 1 : 0;
  reportProgress(progress, 1.0);
  return out;
}

void compressDetailAtDeviation(CompressedSequence& sequence, const FittedDetail& detail,
                               double rmsDeviation)
{
  if (!(rmsDeviation > 0) || !std::isfinite(rmsDeviation))
    throw std::invalid_argument("the detail layer's RMS deviation must be > 0, not " +
                                std::to_string(rmsDeviation));
  setDetail(sequence, detail.map.levels(), carriedToDecodedBase(detail, sequence),
            std::sqrt(12.0) * rmsDeviation);
}

} // namespace dp
