// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/TakeRefinement.h"

#include "dp/track/ColourTerm.h"
#include "dp/track/CoverageTerm.h"
#include "dp/track/InternalEnergyTerm.h"
#include "dp/track/Solvers.h"
#include "dp/track/TemporalTerm.h"
#include "dp/track/Tracker.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

namespace dp
{
namespace
{
// The points -> mesh term's robust scale and reach, in voxels (the forward fine level's).
constexpr double CoverageScale = 3.0;
constexpr double CoverageReach = 8.0;
// A step moving no vertex farther than this (voxels) ends a frame's solve.
constexpr double SettledStep = 0.05;
// The colour field's kernel in the first pass, this many times the fine one (colourKernel): it
// reaches farther, the later passes fit finer.
constexpr double CoarseKernel = 3.0;

void validate(const RefinementOptions& o)
{
  const auto check = [](bool ok, const char* what)
  {
    if (!ok)
      throw std::invalid_argument(std::string("refinement option out of range: ") + what);
  };
  check(o.passes >= 0 && o.passes <= 100, "passes (0 to 100)");
  check(o.iterations >= 1 && o.iterations <= 100, "iterations (1 to 100)");
  check(o.temporalWeight >= 0 && std::isfinite(o.temporalWeight), "temporal weight (>= 0)");
  check(o.coverageWeight >= 0 && std::isfinite(o.coverageWeight), "coverage weight (>= 0)");
  check(o.colourWeight >= 0 && std::isfinite(o.colourWeight), "colour weight (>= 0)");
  check(o.stiffness > 0 && std::isfinite(o.stiffness), "stiffness (> 0)");
}

ClothParameters scaled(ClothParameters k, double factor)
{
  k.stretch *= factor;
  k.shear *= factor;
  k.bend *= factor;
  return k;
}

// The tracker's cloth (its region stiffness included), stiffer or softer by `factor`, with the
// template as its rest state.
ClothEnergy templateCloth(const Tracker& tracker, double factor)
{
  ClothEnergy cloth(tracker.mesh(), tracker.templatePositions().data(),
                    scaled(tracker.clothEnergy().parameters(), factor));
  const ClothEnergy& source = tracker.clothEnergy();
  cloth.setStiffnessScales(source.stretchScales(), source.bendScales());
  return cloth;
}

// The acceleration term's pull on frame t with its neighbours held: the second differences that
// hold X_t, centred at t - 1, t and t + 1, are 1/2 |X_t - a|^2, 4/2 |X_t - b|^2 and 1/2 |X_t -
// d|^2 with a = 2 X[t-1] - X[t-2], b = (X[t-1] + X[t+1]) / 2, d = 2 X[t+1] - X[t+2]; their sum is
// W/2 |X_t - (a + 4 b + d) / W|^2 plus a constant. Returns W (0: no neighbour).
double accelerationPull(std::size_t t, const std::vector<std::vector<double>>& x,
                        std::vector<double>& target)
{
  const std::size_t frames = x.size();
  std::fill(target.begin(), target.end(), 0.0);
  double weight = 0;
  const auto add = [&](double w, double ca, const std::vector<double>& a, double cb,
                       const std::vector<double>& b)
  {
    for (std::size_t i = 0; i < target.size(); ++i)
      target[i] += w * (ca * a[i] + cb * b[i]);
    weight += w;
  };
  if (t >= 2)
    add(1, 2, x[t - 1], -1, x[t - 2]);
  if (t >= 1 && t + 1 < frames)
    add(4, 0.5, x[t - 1], 0.5, x[t + 1]);
  if (t + 2 < frames)
    add(1, 2, x[t + 1], -1, x[t + 2]);
  if (weight > 0)
    for (double& v : target)
      v /= weight;
  return weight;
}
} // namespace

TakeRefinement::TakeRefinement(const Tracker& tracker, const RefinementOptions& options)
    : Source(tracker), Options(options), Cloth(templateCloth(tracker, options.stiffness))
{
  validate(options);
}

TakeRefinement::~TakeRefinement() = default;

// The colour cue of a take whose points carry colour: each frame's colour field, and each
// vertex's reference colour (its colour in the first frame, where the template lies on its
// material) at the kernel width in use.
struct TakeRefinement::ColourCue
{
  std::vector<std::unique_ptr<ColourField>> fields; // per frame; null without colour
  double sigma = 0;
  std::vector<float> reference;

  bool active() const { return !fields.empty() && fields[0]; }
  // The kernel `scale` times the fine one; references from the first frame at `first`.
  void atScale(double scale, const std::vector<double>& first, std::size_t vertices)
  {
    sigma = colourKernel(fields[0]->samples(), scale);
    reference = vertexColours(*fields[0], first.data(), vertices, sigma);
  }
};

TakeRefinement::ColourCue
TakeRefinement::colourCue(const std::vector<const FrameSamples*>& samples,
                          const std::vector<std::vector<double>>& positions) const
{
  ColourCue cue;
  if (Options.colourWeight <= 0 || samples.empty() || !samples[0] || !samples[0]->hasColour() ||
      positions.empty())
    return cue;
  cue.fields.resize(samples.size());
  tbb::parallel_for(std::size_t{0}, samples.size(),
                    [&](std::size_t t)
                    {
                      if (samples[t] && samples[t]->hasColour())
                        cue.fields[t] = std::make_unique<ColourField>(*samples[t]);
                    });
  return cue;
}

// A frame's terms with its neighbours held.
struct TakeRefinement::FrameProblem
{
  ClothEnergy cloth;
  InternalEnergyTerm internal;
  std::unique_ptr<CoverageTerm> coverage;
  std::vector<double> target;
  std::unique_ptr<TemporalTerm> temporal;
  std::unique_ptr<ColourTerm> colour;
  std::vector<EnergyTerm*> terms;

  FrameProblem(const TakeRefinement& r, std::size_t t,
               const std::vector<std::vector<double>>& positions, const FrameSamples* samples,
               const std::vector<double>* restShape, const ColourCue* cue = nullptr)
      : cloth(r.Cloth), internal(cloth), target(positions[t].size())
  {
    if (restShape)
      cloth.setRestState(cloth.restStateOf(restShape->data()));
    const Tracker& tracker = r.Source;
    const double voxel = tracker.voxelSize();
    const double L = r.Cloth.lengthScale();
    terms.push_back(&internal);
    if (samples && !samples->empty() && r.Options.coverageWeight > 0)
    {
      CoverageOptions c = tracker.options().coverage;
      c.weight = r.Options.coverageWeight;
      c.robustScale = CoverageScale * voxel;
      c.maxDistance = CoverageReach * voxel;
      c.followMatches = false;
      // Across the surface only: along it, the colour and the shape decide (a share of the
      // point-to-point distance pulled vertices toward where the subsample's points happen to be).
      c.pointToPoint = 0;
      coverage = std::make_unique<CoverageTerm>(samples->view(), tracker.mesh(), L, c);
      terms.push_back(coverage.get());
    }
    if (cue && cue->fields[t] && r.Options.colourWeight > 0)
    {
      colour = std::make_unique<ColourTerm>(*cue->fields[t], tracker.mesh(), cue->reference,
                                            r.Cloth.vertexMass(), r.Options.colourWeight, L, voxel,
                                            cue->sigma);
      terms.push_back(colour.get());
    }
    const double w = accelerationPull(t, positions, target);
    if (w > 0 && r.Options.temporalWeight > 0)
    {
      temporal = std::make_unique<TemporalTerm>(target, r.Cloth.vertexMass(),
                                                w * r.Options.temporalWeight, L, voxel);
      terms.push_back(temporal.get());
    }
  }
};

void TakeRefinement::solveFrame(std::size_t t, std::vector<std::vector<double>>& positions,
                                const std::vector<const FrameSamples*>& samples,
                                const std::vector<std::vector<double>>& forward,
                                const ColourCue* cue, GaussNewtonSolver& solver,
                                int iterations) const
{
  FrameProblem problem(*this, t, positions, samples[t],
                       Options.restFromForward ? &forward[t] : nullptr, cue);
  SolveSettings settings;
  settings.maxIterations = iterations;
  settings.tolerance = Source.options().tolerance;
  settings.settledStep = SettledStep * Source.voxelSize();
  settings.decisions = 0;
  std::vector<double> x = positions[t];
  solver.solve(x, problem.terms, nullptr, settings);
  positions[t].swap(x);
}

bool TakeRefinement::refine(std::vector<std::vector<double>>& positions,
                            const std::vector<const FrameSamples*>& samples,
                            const std::function<bool(double)>& progress) const
{
  const std::size_t frames = positions.size();
  const std::size_t nv = Source.mesh().numberOfVertices();
  if (samples.size() != frames)
    throw std::invalid_argument("take refinement: " + std::to_string(samples.size()) +
                                " frames of samples for " + std::to_string(frames) +
                                " frames of positions");
  for (std::size_t t = 0; t < frames; ++t)
    if (positions[t].size() != 3 * nv)
      throw std::invalid_argument("take refinement: frame " + std::to_string(t) + " has " +
                                  std::to_string(positions[t].size() / 3) +
                                  " vertices; the template has " + std::to_string(nv));
  if (frames == 0)
    return true;
  std::vector<std::array<std::int64_t, 2>> pairs;
  InternalEnergyTerm(Cloth).couplings(pairs);
  tbb::enumerable_thread_specific<std::unique_ptr<GaussNewtonSolver>> solvers;
  const std::vector<std::vector<double>> forward = positions;
  ColourCue cue = colourCue(samples, forward);
  const double steps = static_cast<double>(3 * Options.passes);
  for (int pass = 0; pass < Options.passes; ++pass)
    for (std::size_t set = 0; set < 3; ++set)
    {
      if (cue.active() && set == 0)
        cue.atScale(pass == 0 && Options.passes > 1 ? CoarseKernel : 1.0, forward[0],
                    Cloth.vertexMass().size());
      const std::size_t count = set < frames ? (frames - set + 2) / 3 : 0;
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1),
                        [&](const tbb::blocked_range<std::size_t>& range)
                        {
                          std::unique_ptr<GaussNewtonSolver>& solver = solvers.local();
                          if (!solver)
                            solver = std::make_unique<GaussNewtonSolver>(nv, pairs);
                          for (std::size_t k = range.begin(); k != range.end(); ++k)
                            solveFrame(set + 3 * k, positions, samples, forward,
                                       cue.active() ? &cue : nullptr, *solver, Options.iterations);
                        });
      if (progress && !progress((static_cast<double>(3 * pass) + set + 1) / steps))
        return false;
    }
  return true;
}

double TakeRefinement::energy(const std::vector<std::vector<double>>& positions,
                              const std::vector<const FrameSamples*>& samples) const
{
  double e = 0;
  const std::vector<double>& mass = Cloth.vertexMass();
  const double scale = Options.temporalWeight / (Cloth.lengthScale() * Source.voxelSize());
  for (std::size_t t = 0; t < positions.size(); ++t)
  {
    e += Cloth.value(positions[t].data());
    if (samples[t] && !samples[t]->empty() && Options.coverageWeight > 0)
    {
      FrameProblem problem(*this, t, positions, samples[t], nullptr);
      problem.coverage->linearise(positions[t].data());
      e += problem.coverage->evaluate(positions[t].data(), nullptr);
    }
    if (t == 0 || t + 1 >= positions.size())
      continue;
    for (std::size_t v = 0; v < mass.size(); ++v)
      for (int k = 0; k < 3; ++k)
      {
        const std::size_t i = 3 * v + static_cast<std::size_t>(k);
        const double a = positions[t + 1][i] - 2 * positions[t][i] + positions[t - 1][i];
        e += 0.5 * scale * mass[v] * a * a;
      }
  }
  return e;
}

} // namespace dp
