// SPDX-License-Identifier: BSD-3-Clause
#include "dp/detail/DisplacementFit.h"

#include "dp/support/Parallel.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace dp
{
namespace
{

constexpr double Mu = 1e-6;
// The robust rounds' scale: residuals beyond this many robust standard deviations lose weight.
constexpr double RobustWidth = 3;
constexpr double RobustFloor = 0.25;
constexpr double Pi = 3.14159265358979323846;

// A sum over [0, n) in fixed blocks, added in order: the same bits for any thread count.
template <typename Term>
double orderedSum(std::size_t n, const Term& term)
{
  constexpr std::size_t Block = 4096;
  const std::size_t blocks = (n + Block - 1) / Block;
  std::vector<double> partial(blocks, 0.0);
  forEachIndex(blocks,
               [&](std::size_t b)
               {
                 double s = 0;
                 for (std::size_t i = b * Block; i < std::min(n, (b + 1) * Block); ++i)
                   s += term(i);
                 partial[b] = s;
               });
  double sum = 0;
  for (double s : partial)
    sum += s;
  return sum;
}

// The median of |values| (values is reordered).
double medianMagnitude(std::vector<double> values)
{
  if (values.empty())
    return 0;
  for (double& v : values)
    v = std::abs(v);
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

// The membrane's system (W + Mu I + lambda L) over the fine mesh's edges: L the graph Laplacian,
// W the data weights; row i's neighbours are neighbours[start[i] .. start[i + 1]).
struct MembraneSystem
{
  const std::vector<std::size_t>& start;
  const std::vector<std::int64_t>& neighbours;
  const std::vector<double>& w;
  double lambda;
  std::size_t n;

  // y = the system times x.
  void multiply(const std::vector<double>& x, std::vector<double>& y) const
  {
    forEachIndex(n,
                 [&](std::size_t i)
                 {
                   double laplacian = 0;
                   for (std::size_t k = start[i]; k < start[i + 1]; ++k)
                     laplacian += x[i] - x[static_cast<std::size_t>(neighbours[k])];
                   y[i] = (w[i] + Mu) * x[i] + lambda * laplacian;
                 });
  }

  // The inverse of the system's diagonal: the conjugate gradients' Jacobi preconditioner.
  std::vector<double> inverseDiagonal() const
  {
    std::vector<double> inverse(n);
    forEachIndex(n,
                 [&](std::size_t i)
                 {
                   const auto degree = static_cast<double>(start[i + 1] - start[i]);
                   inverse[i] = 1.0 / (w[i] + Mu + lambda * degree);
                 });
    return inverse;
  }
};

// Where each fine vertex's normal line meets the data: its distance there into `observation`
// and the data's weight into `weight` (both left 0 where it meets none).
void crossData(const double* finePositions, const double* fineNormals, const FrameSurface& data,
               const DisplacementFitOptions& options, std::vector<double>& observation,
               std::vector<double>& weight)
{
  const double minimumCosine = std::cos(options.normalAngle * Pi / 180);
  const double radius = options.radius > 0 ? options.radius : options.reach / 4;
  forEachIndex(observation.size(),
               [&](std::size_t i)
               {
                 const FrameSurface::Crossing c =
                     data.cross(finePositions + 3 * i, fineNormals + 3 * i, options.reach,
                                minimumCosine, radius);
                 if (c.found)
                 {
                   observation[i] = c.distance;
                   weight[i] = c.weight;
                 }
               });
}

// A robust round's weights `w`: each observation's `weight` lowered by its residual from the
// displacements `d` over a width of the residuals' robust spread (at least a share of the reach).
void reweight(const std::vector<double>& observation, const std::vector<double>& weight,
              const std::vector<double>& d, std::size_t observed, double reach,
              std::vector<double>& w)
{
  const std::size_t n = observation.size();
  std::vector<double> residual;
  residual.reserve(observed);
  for (std::size_t i = 0; i < n; ++i)
    if (weight[i] > 0)
      residual.push_back(observation[i] - d[i]);
  // Residuals within a share of the reach always keep most of their weight: exact data (a mesh)
  // leaves a tiny spread, beyond which detail the membrane smooths is no outlier.
  const double width =
      std::max(RobustWidth * 1.4826 * medianMagnitude(residual), RobustFloor * reach);
  for (std::size_t i = 0; i < n; ++i)
  {
    const double r = (observation[i] - d[i]) / width;
    w[i] = weight[i] / (1 + r * r);
  }
}

} // namespace

DisplacementFitter::DisplacementFitter(const SubdivisionMap& map) : Map(map)
{
  const std::size_t n = map.fineVertices();
  std::vector<std::pair<std::int64_t, std::int64_t>> pairs;
  const auto& tri = map.fineTriangles();
  pairs.reserve(2 * tri.size());
  for (std::size_t t = 0; t < tri.size(); t += 3)
    for (int k = 0; k < 3; ++k)
    {
      const std::int64_t a = tri[t + k], b = tri[t + (k + 1) % 3];
      pairs.emplace_back(a, b);
      pairs.emplace_back(b, a);
    }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  NeighbourStart.assign(n + 1, 0);
  for (const auto& [a, b] : pairs)
    ++NeighbourStart[static_cast<std::size_t>(a) + 1];
  for (std::size_t i = 0; i < n; ++i)
    NeighbourStart[i + 1] += NeighbourStart[i];
  Neighbours.reserve(pairs.size());
  for (const auto& [a, b] : pairs)
    Neighbours.push_back(b);
}

int DisplacementFitter::solve(const std::vector<double>& w, const std::vector<double>& wo,
                              double lambda, const DisplacementFitOptions& options,
                              std::vector<double>& d) const
{
  const std::size_t n = d.size();
  const MembraneSystem system{NeighbourStart, Neighbours, w, lambda, n};
  std::vector<double> r(n), z(n), p(n), q(n);
  const std::vector<double> inverseDiagonal = system.inverseDiagonal();
  system.multiply(d, q);
  forEachIndex(n,
               [&](std::size_t i)
               {
                 r[i] = wo[i] - q[i];
                 z[i] = inverseDiagonal[i] * r[i];
                 p[i] = z[i];
               });
  const double goal2 =
      std::pow(options.tolerance, 2) *
      std::max(orderedSum(n, [&](std::size_t i) { return wo[i] * wo[i]; }), 1e-300);
  double rz = orderedSum(n, [&](std::size_t i) { return r[i] * z[i]; });
  int iteration = 0;
  for (; iteration < options.maximumIterations; ++iteration)
  {
    if (orderedSum(n, [&](std::size_t i) { return r[i] * r[i]; }) <= goal2)
      break;
    system.multiply(p, q);
    const double pq = orderedSum(n, [&](std::size_t i) { return p[i] * q[i]; });
    if (!(pq > 0))
      break;
    const double alpha = rz / pq;
    forEachIndex(n,
                 [&](std::size_t i)
                 {
                   d[i] += alpha * p[i];
                   r[i] -= alpha * q[i];
                   z[i] = inverseDiagonal[i] * r[i];
                 });
    const double next = orderedSum(n, [&](std::size_t i) { return r[i] * z[i]; });
    const double beta = next / rz;
    rz = next;
    forEachIndex(n, [&](std::size_t i) { p[i] = z[i] + beta * p[i]; });
  }
  return iteration;
}

DisplacementFit DisplacementFitter::fit(const double* finePositions, const double* fineNormals,
                                        const FrameSurface& data,
                                        const DisplacementFitOptions& options) const
{
  if (!(options.reach > 0) || !std::isfinite(options.reach))
    throw std::invalid_argument("the detail layer's reach must be > 0, not " +
                                std::to_string(options.reach));
  const std::size_t n = Map.fineVertices();
  std::vector<double> observation(n, 0.0), weight(n, 0.0);
  crossData(finePositions, fineNormals, data, options, observation, weight);
  DisplacementFit out;
  out.displacement = observation;
  out.met.resize(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    out.met[i] = weight[i] > 0 ? 1 : 0;
    out.observed += out.met[i];
  }
  std::vector<double> w = weight, wo(n);
  for (int round = 0; round <= options.robustRounds; ++round)
  {
    for (std::size_t i = 0; i < n; ++i)
      wo[i] = w[i] * observation[i];
    out.iterations += solve(w, wo, options.smoothness, options, out.displacement);
    if (round == options.robustRounds)
      break;
    reweight(observation, weight, out.displacement, out.observed, options.reach, w);
  }
  out.residual.resize(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    out.downweighted += weight[i] > 0 && w[i] < 0.5 * weight[i] ? 1 : 0;
    out.residual[i] = out.met[i] ? std::abs(observation[i] - out.displacement[i]) : -1.0;
  }
  return out;
}

} // namespace dp
