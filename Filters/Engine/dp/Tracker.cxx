// SPDX-License-Identifier: BSD-3-Clause
#include "dp/Tracker.h"

#include "dp/SurfaceSampler.h"

#include <lbfgs.h>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace dp
{
namespace
{
constexpr double Pi = 3.14159265358979323846;

// What the solvers minimise: the tracker's energy with fixed data weights.
struct Objective
{
  const Tracker* tracker;
  const DistanceField* field;
  const std::vector<double>* weights;
  int evaluations = 0;
  double operator()(const double* x, double* gradient)
  {
    ++evaluations;
    if (gradient)
      std::fill(gradient, gradient + tracker->templatePositions().size(), 0.0);
    return tracker->energy(x, field, *weights, gradient);
  }
};

lbfgsfloatval_t evaluateForLbfgs(void* instance, const lbfgsfloatval_t* x, lbfgsfloatval_t* g,
                                 const int, const lbfgsfloatval_t)
{
  return (*static_cast<Objective*>(instance))(x, g);
}

// Largest eigenvalue of the Hessian of the objective at x, by power iteration on finite
// differences of the gradient.
double largestCurvature(Objective& objective, const std::vector<double>& x, double lengthScale)
{
  const std::size_t n = x.size();
  std::vector<double> v(n), gp(n), gm(n), xp(n), xm(n);
  for (std::size_t i = 0; i < n; ++i)
    v[i] = std::sin(12.9898 * static_cast<double>(i) + 1.0); // fixed, generic start
  double lambda = 0;
  const double h = 1e-6 * lengthScale;
  for (int iteration = 0; iteration < 30; ++iteration)
  {
    double length = 0;
    for (double value : v)
      length += value * value;
    length = std::sqrt(length);
    if (length == 0)
      break;
    for (std::size_t i = 0; i < n; ++i)
    {
      v[i] /= length;
      xp[i] = x[i] + h * v[i];
      xm[i] = x[i] - h * v[i];
    }
    objective(xp.data(), gp.data());
    objective(xm.data(), gm.data());
    double rayleigh = 0;
    for (std::size_t i = 0; i < n; ++i)
    {
      const double hv = (gp[i] - gm[i]) / (2 * h);
      rayleigh += v[i] * hv;
      v[i] = hv;
    }
    if (iteration > 3 && std::abs(rayleigh - lambda) < 1e-3 * std::abs(rayleigh))
    {
      lambda = rayleigh;
      break;
    }
    lambda = rayleigh;
  }
  return std::abs(lambda);
}
} // namespace

Tracker::Tracker(TriangleMesh mesh, std::vector<double> templatePositions,
                 const TrackerOptions& options)
    : Mesh(std::move(mesh)), Template(std::move(templatePositions)), Options(options),
      Cloth(Mesh, Template.data(), options.cloth)
{
  if (Template.size() != 3 * Mesh.numberOfVertices())
    throw std::invalid_argument("the template has " + std::to_string(Template.size() / 3) +
                                " positions for " + std::to_string(Mesh.numberOfVertices()) +
                                " vertices");
  if (!(options.distanceWeight >= 0) || !(options.tolerance > 0) || options.maxIterations < 1 ||
      options.voxelSize < 0 || options.bandWidth < 0 || options.outlierDistance < 0 ||
      !(options.restUpdate >= 0 && options.restUpdate <= 1))
    throw std::invalid_argument("tracker options out of range (weights, sizes and tolerance "
                                "must be non-negative, iterations at least 1, the rest update "
                                "between 0 and 1)");
  TemplateRest = Cloth.restState();
  Voxel = options.voxelSize > 0 ? options.voxelSize : boundingBoxDiagonal(Template) / 200.0;
}

double Tracker::energy(const double* x, const DistanceField* field,
                       const std::vector<double>& weights, double* gradient, double* internal,
                       double* distance) const
{
  const double eInt = Cloth.addGradient(x, gradient);
  double eDis = 0;
  if (field)
  {
    const auto& mass = Cloth.vertexMass();
    const double scale = Options.distanceWeight / Cloth.lengthScale();
    for (std::size_t v = 0; v < mass.size(); ++v)
    {
      if (weights[v] == 0)
        continue;
      const DistanceSample s = sampleData(*field, x + 3 * v, v);
      const double w = scale * mass[v] * weights[v];
      // Squared: D^2 / (2 voxel), smooth at the data; else the paper's D.
      const double value =
          Options.squaredDistance ? 0.5 * s.distance * s.distance / Voxel : s.distance;
      const double slope = Options.squaredDistance ? s.distance / Voxel : 1.0;
      eDis += w * value;
      if (gradient)
        for (int k = 0; k < 3; ++k)
          gradient[3 * v + k] += w * slope * s.gradient[k];
    }
  }
  if (internal)
    *internal = eInt;
  if (distance)
    *distance = eDis;
  return eInt + eDis;
}

DistanceSample Tracker::sampleData(const DistanceField& field, const double* x,
                                   std::size_t vertex) const
{
  VoxelCell* cell = vertex < Cells.size() ? &Cells[vertex] : nullptr;
  if (Options.distanceMeasure == DistanceMeasure::Planes && !FrameNormals.empty())
    return field.sampleToPlanes(x, FrameNormals.data(), 2 * Voxel, cell);
  return field.sample(x, cell);
}

std::vector<double> Tracker::predict() const
{
  return History.empty() ? Template : History.back();
}

int Tracker::solveGaussNewton(
    std::vector<double>& x, const DistanceField* field, std::vector<double>& weights,
    const std::function<void(const std::vector<double>&)>& decideWeights) const
{
  using Sparse = Eigen::SparseMatrix<double>;
  const std::size_t nv = Mesh.numberOfVertices();
  const Eigen::Index n = static_cast<Eigen::Index>(3 * nv);
  const double L = Cloth.lengthScale();
  const double scale = Options.distanceWeight / L;
  const auto& mass = Cloth.vertexMass();
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::SimplicialLDLT<Sparse> solver;
  bool analysed = false;
  std::vector<double> gradient(x.size()), trial(x.size());
  double damping = 1e-4; // relative to the mean diagonal
  int evaluations = 0;
  double e = energy(x.data(), field, weights,
                    (std::fill(gradient.begin(), gradient.end(), 0.0), gradient.data()));
  ++evaluations;
  int iteration = 0;
  for (; iteration < Options.maxIterations; ++iteration)
  {
    // Gauss-Newton matrix: cloth terms, distance terms (reweighted), Levenberg damping.
    triplets.clear();
    auto addBlock =
        [&](std::int64_t a, std::int64_t b, const double* ga, const double* gb, double w)
    {
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          triplets.emplace_back(static_cast<int>(3 * a + r), static_cast<int>(3 * b + c),
                                w * ga[r] * gb[c]);
    };
    Cloth.forEachTerm(x.data(),
                      [&](const ClothTerm& t)
                      {
                        for (int a = 0; a < t.count; ++a)
                          for (int b = 0; b < t.count; ++b)
                            addBlock(t.vertex[a], t.vertex[b], t.gradient[a], t.gradient[b],
                                     t.weight);
                      });
    const double floor = Voxel;
    for (std::size_t v = 0; v < nv; ++v)
    {
      double g[3] = {0, 0, 0};
      double w = 0;
      if (field && weights[v] != 0)
      {
        const DistanceSample sample = sampleData(*field, &x[3 * v], v);
        w = scale * mass[v] * weights[v] /
            (Options.squaredDistance ? Voxel : std::max(sample.distance, floor));
        std::copy(sample.gradient, sample.gradient + 3, g);
      }
      addBlock(static_cast<std::int64_t>(v), static_cast<std::int64_t>(v), g, g, w);
    }
    Sparse H(n, n);
    H.setFromTriplets(triplets.begin(), triplets.end());
    // Every vertex has a (possibly zero) data block, so the diagonal is stored and damping
    // can be added in place without changing the pattern.
    const Eigen::VectorXd diagonal = H.diagonal();
    const double meanDiagonal = std::max(diagonal.mean(), 1e-300);
    const Eigen::Map<const Eigen::VectorXd> g(gradient.data(), n);

    bool accepted = false;
    for (int attempt = 0; attempt < 12 && !accepted; ++attempt)
    {
      Sparse A = H;
      A.diagonal().array() += damping * meanDiagonal;
      if (!analysed)
      {
        solver.analyzePattern(A);
        analysed = true;
      }
      solver.factorize(A);
      if (solver.info() != Eigen::Success)
      {
        damping *= 10;
        continue;
      }
      const Eigen::VectorXd step = solver.solve(-g);
      for (std::size_t i = 0; i < x.size(); ++i)
        trial[i] = x[i] + step[static_cast<Eigen::Index>(i)];
      const double eTrial = energy(trial.data(), field, weights, nullptr);
      ++evaluations;
      if (eTrial < e)
      {
        accepted = true;
        const double decrease = e - eTrial;
        x.swap(trial);
        std::fill(gradient.begin(), gradient.end(), 0.0);
        e = energy(x.data(), field, weights, gradient.data());
        ++evaluations;
        damping = std::max(damping * 0.3, 1e-9);
        if (decrease <= Options.tolerance * std::abs(e) ||
            step.cwiseAbs().maxCoeff() <= Options.tolerance * L)
          return evaluations;
      }
      else
      {
        damping *= 10;
      }
    }
    if (!accepted)
      break; // no step decreases E any more: a (local) minimum
    if (iteration % 5 == 4)
    {
      decideWeights(x);
      std::fill(gradient.begin(), gradient.end(), 0.0);
      e = energy(x.data(), field, weights, gradient.data());
    }
  }
  return evaluations;
}

FrameResult Tracker::track(const double* points, std::size_t count, const float* normals)
{
  const auto start = std::chrono::steady_clock::now();
  const std::size_t nv = Mesh.numberOfVertices();
  const double L = Cloth.lengthScale();
  FrameResult result;
  result.frozen.assign(nv, 0);
  result.rejected.assign(nv, 0);
  result.residual.assign(nv, -1.0);

  // The frame's distance field and target normals.
  DistanceField field;
  FrameNormals.clear();
  const bool haveData = count > 0;
  if (haveData)
  {
    DistanceFieldOptions fieldOptions;
    fieldOptions.voxelSize = Voxel;
    fieldOptions.bandWidth = Options.bandWidth > 0 ? Options.bandWidth : 4 * Voxel;
    fieldOptions.lazy = true; // only the voxels around the vertices are ever needed
    field.build(points, count, fieldOptions);
    if (Options.normalTestDegrees < 180 || Options.distanceMeasure == DistanceMeasure::Planes)
      FrameNormals = normals ? std::vector<float>(normals, normals + 3 * count)
                             : estimateNormals(points, count);
  }

  if (Options.restUpdate > 0)
    Cloth.setRestState(History.empty() ? TemplateRest
                                       : ClothRestState::blend(
                                             TemplateRest, Cloth.restStateOf(History.back().data()),
                                             Options.restUpdate));

  // Data weights: the normal test and the outlier cut-off, decided at a given shape.
  std::vector<double> weights(nv, haveData ? 1.0 : 0.0);
  Cells.assign(nv, VoxelCell{}); // a new field
  auto decideWeights = [&](const std::vector<double>& x)
  {
    if (!haveData)
      return;
    std::vector<double> vertexNormals(3 * nv);
    Mesh.vertexNormals(x.data(), vertexNormals.data());
    const double cosLimit = std::cos(Options.normalTestDegrees * Pi / 180.0);
    for (std::size_t v = 0; v < nv; ++v)
    {
      const DistanceSample s = field.sample(&x[3 * v], &Cells[v]);
      bool keep = Options.outlierDistance <= 0 || s.distance <= Options.outlierDistance;
      if (keep && Options.normalTestDegrees < 180)
      {
        const float* n = &FrameNormals[3 * static_cast<std::size_t>(s.nearest)];
        const double agreement = vertexNormals[3 * v] * n[0] + vertexNormals[3 * v + 1] * n[1] +
                                 vertexNormals[3 * v + 2] * n[2];
        keep = agreement >= cosLimit;
      }
      weights[v] = keep ? 1.0 : 0.0;
      result.rejected[v] = keep ? 0 : 1;
    }
  };

  Objective objective{this, haveData ? &field : nullptr, &weights};

  // Start: the template for the first frame; afterwards motion prediction. Without data
  // there is nothing to search the predictions against: keep moving as before (linear).
  std::vector<double> x = predict();
  if (!haveData && History.size() >= 2)
  {
    const auto& last = History.back();
    const auto& before = History[History.size() - 2];
    for (std::size_t i = 0; i < x.size(); ++i)
      x[i] = 2 * last[i] - before[i];
  }
  else if (!History.empty() && Options.motionPrediction)
  {
    decideWeights(x);
    const std::vector<double>& last = History.back();
    std::vector<std::vector<double>> targets;
    if (History.size() >= 2)
    {
      const auto& before = History[History.size() - 2];
      std::vector<double> linear(last.size());
      for (std::size_t i = 0; i < last.size(); ++i)
        linear[i] = 2 * last[i] - before[i];
      targets.push_back(std::move(linear));
      if (History.size() >= 3)
      {
        const auto& earlier = History[History.size() - 3];
        std::vector<double> quadratic(last.size());
        for (std::size_t i = 0; i < last.size(); ++i)
          quadratic[i] = 3 * last[i] - 3 * before[i] + earlier[i];
        targets.push_back(std::move(quadratic));
      }
    }
    double best = objective(last.data(), nullptr);
    std::vector<double> candidate(last.size());
    for (const auto& target : targets)
      for (double alpha : {0.25, 0.5, 0.75, 1.0, 1.25, 1.5})
      {
        for (std::size_t i = 0; i < last.size(); ++i)
          candidate[i] = last[i] + alpha * (target[i] - last[i]);
        const double e = objective(candidate.data(), nullptr);
        if (e < best)
        {
          best = e;
          x = candidate;
        }
      }
  }
  decideWeights(x);

  if (!haveData)
  {
    result.emptyFrame = true;
  }

  if (Options.solver == TrackerSolver::GaussNewton)
  {
    result.iterations = solveGaussNewton(x, haveData ? &field : nullptr, weights, decideWeights);
  }
  else if (Options.solver == TrackerSolver::LBFGS)
  {
    lbfgs_parameter_t parameters;
    lbfgs_parameter_init(&parameters);
    parameters.m = 8;
    parameters.max_iterations = Options.maxIterations;
    parameters.epsilon = 1e-8;
    parameters.past = 5;
    parameters.delta = 0.1 * Options.tolerance;
    parameters.linesearch = LBFGS_LINESEARCH_MORETHUENTE;
    // Two passes: after the first, the normal test is decided again at the new shape.
    for (int pass = 0; pass < 2; ++pass)
    {
      lbfgsfloatval_t fx = 0;
      // Any stop (converged, iteration limit, line-search failure) leaves x at the best point
      // found, which is what the frame gets.
      lbfgs(static_cast<int>(x.size()), x.data(), &fx, evaluateForLbfgs, nullptr, &objective,
            &parameters);
      if (pass == 0)
        decideWeights(x);
    }
    result.iterations = objective.evaluations;
  }
  else
  {
    // The paper's solver: steepest descent with h < 2 / k_max.
    const double kMax = largestCurvature(objective, x, L);
    double h = kMax > 0 ? 1.9 / kMax : L;
    std::vector<double> gradient(x.size()), before;
    // PD: a vertex that barely moves is frozen. The distance term's gradient has the same size
    // everywhere, so a settled vertex keeps stepping but goes nowhere: over a window of
    // iterations, it freezes when its net motion is under a quarter of the path it stepped,
    // and wakes when a neighbour moves steadily (net motion over half its path).
    constexpr int window = 5;
    std::vector<double> anchor = x, path(nv, 0.0);
    std::vector<std::uint8_t> steady(nv, 0);
    std::vector<double> recent; // energies of the last iterations
    int iteration = 0;
    double previous = std::numeric_limits<double>::infinity();
    for (; iteration < Options.maxIterations; ++iteration)
    {
      double e = objective(x.data(), gradient.data());
      // h < 2 / k_max holds for the curvature where it was estimated; where the energy rises
      // anyway, take the step back and halve h.
      int halvings = 0;
      while (e > previous && halvings < 20 && !before.empty())
      {
        h *= 0.5;
        x = before;
        e = objective(x.data(), gradient.data());
        ++halvings;
      }
      previous = e;
      before = x;
      // Stop when ten iterations gained less than the tolerance (relative).
      recent.push_back(e);
      if (recent.size() > 10)
      {
        const double gained = recent[recent.size() - 11] - e;
        if (gained <= Options.tolerance * std::abs(e))
          break;
      }
      for (std::size_t v = 0; v < nv; ++v)
      {
        if (Options.provisionalDetermination && result.frozen[v])
          continue;
        double step2 = 0;
        for (int k = 0; k < 3; ++k)
        {
          const double d = h * gradient[3 * v + k];
          x[3 * v + k] -= d;
          step2 += d * d;
        }
        path[v] += std::sqrt(step2);
      }
      if (Options.provisionalDetermination && iteration % window == window - 1)
      {
        for (std::size_t v = 0; v < nv; ++v)
        {
          double d2 = 0;
          for (int k = 0; k < 3; ++k)
            d2 += (x[3 * v + k] - anchor[3 * v + k]) * (x[3 * v + k] - anchor[3 * v + k]);
          const double net = std::sqrt(d2);
          steady[v] = path[v] > 0 && net > 0.5 * path[v];
          if (!result.frozen[v] && path[v] > 0 && net < 0.25 * path[v])
            result.frozen[v] = 1;
        }
        for (std::size_t v = 0; v < nv; ++v)
          if (result.frozen[v])
            for (std::int64_t u : Mesh.neighbours(v))
              if (steady[u])
              {
                result.frozen[v] = 0; // a neighbour moves: wake up
                break;
              }
        anchor = x;
        std::fill(path.begin(), path.end(), 0.0);
      }
      if (iteration % 25 == 24)
        decideWeights(x);
    }
    result.iterations = iteration + 1;
  }

  result.positions = x;
  energy(x.data(), haveData ? &field : nullptr, weights, nullptr, &result.internalEnergy,
         &result.distanceEnergy);
  if (haveData)
    for (std::size_t v = 0; v < nv; ++v)
      result.residual[v] = sampleData(field, &x[3 * v], v).distance;
  // Both index this frame's points and field, which end here (energy() called from outside
  // must not meet them with another field).
  Cells.clear();
  FrameNormals.clear();
  History.push_back(x);
  if (History.size() > 3)
    History.erase(History.begin());
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

} // namespace dp
