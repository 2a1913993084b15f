// SPDX-License-Identifier: BSD-3-Clause
// compressSequence: the bit-rate search over the parts in dp/compress/ (the decomposition, the
// quantiser, the integer codec); the .dpz file is in dp/compress/DpzFormat.h.
#include "dp/compress/PcaCompression.h"
#include "dp/compress/Decomposition.h"
#include "dp/compress/IntegerCodec.h"
#include "dp/compress/ModelCoding.h"
#include "dp/compress/Quantiser.h"

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

namespace dp
{
namespace
{

using compress::Decomposition;
using Eigen::MatrixXd;

void validateInput(const double* positions, std::size_t vertices, std::size_t frames,
                   const PcaOptions& options, const std::vector<std::int64_t>& triangles,
                   const std::vector<double>& times)
{
  if (vertices == 0 || frames == 0)
    throw std::invalid_argument("the sequence has no " +
                                std::string(vertices == 0 ? "vertices" : "frames"));
  const bool kg = options.measure == PcaErrorMeasure::KarniGotsman;
  if (!(options.target > 0) || !std::isfinite(options.target) ||
      (kg && !(options.target >= MinimumKarniGotsmanTarget &&
               options.target <= MaximumKarniGotsmanTarget)) ||
      (options.measure == PcaErrorMeasure::MaxVertexError && options.target >= 1))
    throw std::invalid_argument("error target " + std::to_string(options.target) +
                                " is out of range (KG: [1e-4, 50] percent; max vertex error: "
                                "(0, 1) of the diagonal; RMS deviation: > 0)");
  if (!times.empty() && times.size() != frames)
    throw std::invalid_argument("times: " + std::to_string(times.size()) + " values for " +
                                std::to_string(frames) + " frames");
  for (std::int64_t index : triangles)
    if (index < 0 || static_cast<std::size_t>(index) >= vertices)
      throw std::invalid_argument("triangle index " + std::to_string(index) + " out of range");
  if (triangles.size() % 3)
    throw std::invalid_argument("triangles: not a multiple of 3 indices");
  const std::size_t n = 3 * vertices * frames;
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(positions[i]))
      throw std::invalid_argument("position " + std::to_string(i / 3) + " is not finite");
}

// The options as the search reads them: an RMS deviation becomes the KG target it equals (at
// most just under 100 %: a deviation as large as the motion keeps no component).
PcaOptions asSearched(const PcaOptions& options, const Eigen::Map<const MatrixXd>& A)
{
  if (options.measure != PcaErrorMeasure::RmsDeviation)
    return options;
  PcaOptions o = options;
  o.measure = PcaErrorMeasure::KarniGotsman;
  const double spread = centroidSpread(A);
  const double samples = static_cast<double>(A.size() / 3);
  o.target = spread > 0 ? std::min(99.9, 100 * options.target * std::sqrt(samples) / spread) : 99.9;
  return o;
}

// The largest step `passes` (step, trial model) accepts, as far as found: from `step` halved
// until one passes (or doubled while twice the passing one passes), then bisected geometrically
// between the passing and the failing step.
template <typename Passes>
double largestPassingStep(double step, const Passes& passes)
{
  double good = 0, bad = 0;
  QuantisedPca trial;
  for (int i = 0; i < 40 && good == 0; ++i, step *= 0.5)
    if (passes(step, trial))
      good = step;
    else
      bad = step;
  if (good == 0)
    throw std::runtime_error("cannot meet the error target by quantisation");
  if (bad == 0)
  {
    bad = good * 2;
    for (int i = 0; i < 10 && passes(bad, trial); ++i)
    {
      good = bad;
      bad *= 2;
    }
  }
  for (int i = 0; i < 6; ++i)
  {
    const double middle = std::sqrt(good * bad);
    if (passes(middle, trial))
      good = middle;
    else
      bad = middle;
  }
  return good;
}

/** One candidate component count, coded. */
struct Candidate
{
  QuantisedPca model;
  std::vector<std::uint8_t> payload; // the geometry section (empty for float PCA)
  double bits = 0;                   // what is stored
  double plainBits = 0;              // the same integers in fixed-width fields
};

/**
 * The search for the fewest bytes that meet the error target: which component counts to try,
 * and for each the largest quantisation step that meets the target.
 */
class RateSearch
{
public:
  RateSearch(const Eigen::Map<const MatrixXd>& a, const Decomposition& d, const PcaOptions& options)
      : A(a), D(d), Options(options), Rank(static_cast<std::size_t>(d.sigma.size())),
        SpreadNorm(centroidSpread(a))
  {
    const std::size_t n = static_cast<std::size_t>(A.size()) / 3;
    const Eigen::Vector3d lo = A.reshaped(3, n).rowwise().minCoeff();
    const Eigen::Vector3d hi = A.reshaped(3, n).rowwise().maxCoeff();
    Diagonal = (hi - lo).norm();
  }

  double diagonal() const { return Diagonal; }
  bool quantised() const { return Options.quantise; }

  /** The component counts worth coding: the one asked for, or a range by the target. */
  std::vector<std::size_t> candidates() const
  {
    std::vector<std::size_t> counts;
    if (Options.components > 0)
      counts.push_back(std::min(Options.components, Rank));
    else if (!Options.quantise)
      counts.push_back(smallestK(1.0));
    else
    {
      const std::size_t first = smallestK(0.97), last = std::max(first, smallestK(0.3));
      const std::size_t stepK = std::max<std::size_t>(1, (last - first) / 10);
      for (std::size_t k = first; k <= last; k += stepK)
        counts.push_back(k);
    }
    return counts;
  }

  /** k components coded: float PCA, or quantised at the largest step meeting the target. */
  Candidate code(std::size_t k, const compress::VertexTraversal& mesh,
                 compress::ModelEffort effort) const
  {
    MatrixXd basis, weights;
    D.factors(k, basis, weights);
    Candidate c;
    if (!Options.quantise)
    {
      c.model.model = PcaModel{D.layout, D.vertices, D.frames, D.mean, basis, weights};
      c.bits = 32.0 * static_cast<double>(D.mean.size() + basis.size() + weights.size());
      c.plainBits = c.bits;
      return c;
    }
    c.model = quantisedToTarget(k, basis, weights);
    const QuantisedPca& q = c.model;
    c.payload = compress::encodeModel(q, mesh, effort);
    c.bits = 8.0 * static_cast<double>(c.payload.size());
    c.plainBits = compress::fixedWidthBits(q.meanIntegers.data(), q.meanIntegers.size());
    for (std::size_t j = 0; j < k; ++j)
      c.plainBits += compress::fixedWidthBits(q.basisIntegers.data() + j * basis.rows(),
                                              static_cast<std::size_t>(basis.rows())) +
                     compress::fixedWidthBits(q.weightIntegers.data() + j * weights.rows(),
                                              static_cast<std::size_t>(weights.rows()));
    return c;
  }

private:
  // The truncation error alone, as the target measures it.
  double truncated(std::size_t k) const
  {
    if (Options.measure == PcaErrorMeasure::KarniGotsman)
      return SpreadNorm > 0 ? 100 * D.truncationError(k) / SpreadNorm : 0.0;
    MatrixXd basis, weights;
    D.factors(k, basis, weights);
    PcaModel m{D.layout, D.vertices, D.frames, D.mean, basis, weights};
    return compress::measured(compress::errorsOf(A, m), Options.measure, Diagonal);
  }

  // Smallest k whose truncation error is under `limit` (a fraction of the target).
  std::size_t smallestK(double limit) const
  {
    if (Options.measure == PcaErrorMeasure::KarniGotsman)
    {
      // From the singular values: KG_k = 100 ||C - C_k|| / ||A - E(A)||.
      const double allowed = limit * Options.target;
      std::size_t k = 0;
      if (!(SpreadNorm > 0))
        return k;
      while (k < Rank && 100 * D.truncationError(k) / SpreadNorm > allowed)
        ++k;
      return k;
    }
    // The max error has no closed form: bisect on reconstructions (k = rank is exact).
    std::size_t lo = 0, hi = Rank;
    while (lo < hi)
    {
      const std::size_t mid = (lo + hi) / 2;
      if (truncated(mid) <= limit * Options.target)
        hi = mid;
      else
        lo = mid + 1;
    }
    return lo;
  }

  // The first step to try: the error budget left by truncation spread over every stored number
  // (each adds about q^2/12).
  double budget(double goal, double truncation, double count) const
  {
    double step;
    if (Options.measure == PcaErrorMeasure::KarniGotsman)
    {
      const double e2 =
          std::pow(goal * SpreadNorm / 100, 2) - std::pow(truncation * SpreadNorm / 100, 2);
      step = std::sqrt(12 * std::max(e2, 0.0) / count);
    }
    else
      step = (goal - truncation) * Diagonal;
    return step > 0 ? step : 1e-6 * Diagonal;
  }

  // The largest step (bracketed, then bisected: the error grows with the step) whose model meets
  // the target. KG is searched on the estimate (no reconstruction) and the final step checked on
  // the actual reconstruction, stepped back until it holds (the estimate leaves out a noise term).
  QuantisedPca quantisedToTarget(std::size_t k, const MatrixXd& basis,
                                 const MatrixXd& weights) const
  {
    const double truncation = truncated(k);
    const double goal = truncation < Options.target ? Options.target : 1.01 * truncation;
    const double count = static_cast<double>(D.mean.size() + basis.size() + weights.size());
    auto passesActually = [&](double step, QuantisedPca& result)
    {
      result = compress::quantise(D, basis, weights, step);
      return compress::measured(compress::errorsOf(A, result.model), Options.measure, Diagonal) <=
             goal;
    };
    const double residual2 = std::pow(D.truncationError(k), 2);
    auto passes = [&](double step, QuantisedPca& result)
    {
      if (Options.measure != PcaErrorMeasure::KarniGotsman || !(SpreadNorm > 0))
        return passesActually(step, result);
      result = compress::quantise(D, basis, weights, step);
      const double e2 = compress::estimatedError2(basis, weights, D.mean, result.model, residual2);
      return 100 * std::sqrt(std::max(0.0, e2)) / SpreadNorm <= goal;
    };
    double good = largestPassingStep(budget(goal, truncation, count), passes);
    QuantisedPca q;
    bool met = false;
    for (int i = 0; i < 60 && !(met = passesActually(good, q)); ++i)
      good *= 0.98;
    if (!met)
      throw std::runtime_error("cannot meet the error target by quantisation");
    return q;
  }

  const Eigen::Map<const MatrixXd>& A;
  const Decomposition& D;
  const PcaOptions& Options;
  std::size_t Rank;
  double SpreadNorm; // KG's denominator
  double Diagonal = 0;
};

/** The figures of the kept candidate. */
PcaReport reportOf(const Eigen::Map<const MatrixXd>& A, const Candidate& kept, std::size_t k,
                   double diagonal)
{
  const double nt = static_cast<double>(A.cols()), nv = static_cast<double>(A.rows() / 3);
  PcaReport r;
  r.components = k;
  r.bitsPerVertexFrame = kept.bits / (nv * nt);
  r.quantisedPlainBits = kept.plainBits / (nv * nt);
  r.payloadBytes = kept.payload.size();
  const compress::Errors e = compress::errorsOf(A, kept.model.model);
  r.kgError = e.kg;
  r.rmsError = e.kg / 100 * centroidSpread(A) / std::sqrt(nv * nt);
  r.maxError = e.max;
  r.diagonal = diagonal;
  r.maxErrorRelative = diagonal > 0 ? e.max / diagonal : 0;
  const double ny = static_cast<double>(k);
  r.paperD0 = 3 * nt * nv;
  r.paperD1 = 3 * nt * ny + nv * ny;
  r.paperRatio = r.paperD1 > 0 ? r.paperD0 / r.paperD1 : 0;
  return r;
}

// How many candidates are coded at once: as many as fit in 1 GiB of working memory (each checks
// its step on a reconstruction, 3 Nv x Nt doubles, beside the estimate's blocks), at least one
// (a 100 000-vertex x 1 000-frame sequence is coded one at a time), and never more threads than
// the process allows (under a global_control of one thread, one).
int candidatesAtOnce(const Decomposition& d, const std::vector<std::size_t>& candidates)
{
  constexpr double WorkingMemoryBytes = 1024.0 * 1024.0 * 1024.0;
  const double largestK = static_cast<double>(
      candidates.empty() ? 0 : *std::max_element(candidates.begin(), candidates.end()));
  // The basis and the weights together: 3 Nv + Nt rows (shapes) or 3 Nt + Nv (trajectories);
  // the estimate holds 2k + 1 columns of each, beside the quantised copies.
  const double rows = static_cast<double>(
      d.layout == PcaLayout::Shapes ? 3 * d.vertices + d.frames : d.vertices + 3 * d.frames);
  const double bytes =
      8.0 * (3.0 * static_cast<double>(d.vertices * d.frames) + 2 * rows * (2 * largestK + 1));
  const double fit = std::floor(WorkingMemoryBytes / std::max(bytes, 1.0));
  const std::size_t allowed = std::min<std::size_t>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism),
      static_cast<std::size_t>(std::max(1, tbb::this_task_arena::max_concurrency())));
  return static_cast<int>(
      std::clamp(fit, 1.0, static_cast<double>(std::max<std::size_t>(allowed, 1))));
}

/** The `Keep` fewest bits so far among coded candidates; ties go to the earlier candidate (the
 *  smaller count), so the choice does not depend on the order they finish in. */
class BestCandidates
{
public:
  explicit BestCandidates(std::size_t keep) : Keep(keep) {}
  void offer(Candidate&& coded, std::size_t index)
  {
    const std::lock_guard<std::mutex> lock(Mutex);
    Kept.emplace_back(index, std::move(coded));
    std::sort(Kept.begin(), Kept.end(),
              [](const auto& a, const auto& b) {
                return a.second.bits < b.second.bits ||
                       (a.second.bits == b.second.bits && a.first < b.first);
              });
    if (Kept.size() > Keep)
      Kept.pop_back();
  }
  std::vector<std::pair<std::size_t, Candidate>> take() { return std::move(Kept); }

private:
  std::mutex Mutex;
  std::size_t Keep;
  std::vector<std::pair<std::size_t, Candidate>> Kept; // (candidate index, coded), best first
};

// How many of the candidates ranked at ModelEffort::Quick are coded in full: the bits against the
// component count are flat near the best, and the regressions gain about alike on neighbours.
constexpr std::size_t FullyCoded = 3;

/**
 * Codes every candidate count side by side (each searches its step over 8-10 quantisations and
 * is ranked by its quick coding), then codes the best FullyCoded in full and keeps the fewest
 * bits: the same choice, and the same bytes, for any thread count. `report` (which may throw to
 * abort) is called on the caller's thread only.
 */
Candidate codeCandidates(const RateSearch& search, const std::vector<std::size_t>& candidates,
                         const compress::VertexTraversal& mesh, const Decomposition& d,
                         const std::function<void(double)>& report, std::size_t& bestK)
{
  BestCandidates ranked(FullyCoded);
  std::atomic<std::size_t> done{0};
  const std::thread::id caller = std::this_thread::get_id();
  auto codeOne = [&](std::size_t c)
  {
    ranked.offer(search.code(candidates[c], mesh, compress::ModelEffort::Quick), c);
    const std::size_t finished = ++done;
    if (std::this_thread::get_id() == caller)
      report(0.3 + 0.5 * static_cast<double>(finished) / static_cast<double>(candidates.size()));
  };
  tbb::task_arena arena(candidatesAtOnce(d, candidates));
  arena.execute([&] { tbb::parallel_for(std::size_t{0}, candidates.size(), codeOne); });
  std::vector<std::pair<std::size_t, Candidate>> finalists = ranked.take();
  if (search.quantised())
    arena.execute(
        [&]
        {
          tbb::parallel_for(std::size_t{0}, finalists.size(),
                            [&](std::size_t f)
                            {
                              Candidate& c = finalists[f].second;
                              c.payload = compress::encodeModel(c.model, mesh);
                              c.bits = 8.0 * static_cast<double>(c.payload.size());
                            });
        });
  report(0.95);
  BestCandidates best(1);
  for (auto& [index, coded] : finalists)
    best.offer(std::move(coded), index);
  std::vector<std::pair<std::size_t, Candidate>> winner = best.take();
  bestK = winner.empty() ? 0 : candidates[winner.front().first];
  return winner.empty() ? Candidate{} : std::move(winner.front().second);
}

} // namespace

CompressedSequence compressSequence(const double* positions, std::size_t vertices,
                                    std::size_t frames, const PcaOptions& options,
                                    const std::vector<std::int64_t>& triangles,
                                    const std::vector<double>& times,
                                    const std::function<bool(double)>& progress)
{
  if (options.layout == PcaLayout::Automatic)
  {
    // Each layout in turn, each with half of the progress.
    PcaOptions o = options;
    CompressedSequence kept;
    for (PcaLayout layout : {PcaLayout::Shapes, PcaLayout::Trajectories})
    {
      o.layout = layout;
      const double from = layout == PcaLayout::Shapes ? 0.0 : 0.5;
      CompressedSequence coded =
          compressSequence(positions, vertices, frames, o, triangles, times,
                           [&](double f) { return !progress || progress(from + 0.5 * f); });
      if (layout == PcaLayout::Shapes ||
          coded.report.bitsPerVertexFrame < kept.report.bitsPerVertexFrame)
        kept = std::move(coded);
    }
    return kept;
  }
  validateInput(positions, vertices, frames, options, triangles, times);
  auto report = [&](double fraction)
  {
    if (progress && !progress(fraction))
      throw std::runtime_error("aborted");
  };
  const compress::VertexTraversal mesh(triangles, vertices);
  const Eigen::Map<const MatrixXd> A(positions, 3 * vertices, frames);
  const Decomposition d = compress::decompose(A, options.layout);
  report(0.3);
  const PcaOptions searched = asSearched(options, A);
  const RateSearch search(A, d, searched);

  std::size_t bestK = 0;
  Candidate best = codeCandidates(search, search.candidates(), mesh, d, report, bestK);

  CompressedSequence out;
  out.triangles = triangles;
  out.times = times;
  if (out.times.empty())
    for (std::size_t t = 0; t < frames; ++t)
      out.times.push_back(static_cast<double>(t));
  out.report = reportOf(A, best, bestK, search.diagonal());
  out.pca = std::move(best.model);
  report(1.0);
  return out;
}

} // namespace dp
