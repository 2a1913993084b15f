// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/Solvers.h"

#include "dp/track/DistanceTerm.h"

#include <lbfgs.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace dp
{
namespace
{
// Relative residual at which conjugate gradients stop (an inexact Newton step: tighter solves
// cost more than the extra iterations they save).
constexpr double StepTolerance = 0.3;
// The least global damping (relative to the mean diagonal) a rejected step is tried again with:
// below about 1e-2 the step stays what it was (captured takes: jumping), so each smaller retry
// repeated the rejected step at the cost of a conjugate-gradient solve and an evaluation.
constexpr double RetryDamping = 1e-2;

// Preconditioned conjugate gradients on the lower-stored symmetric positive definite A, from
// x = 0, until the residual falls below tolerance * |b| or after `limit` iterations. Every
// iterate is a descent direction of the quadratic model, so an early stop still gives a usable
// (inexact Newton) step.
template <typename Preconditioner>
Eigen::VectorXd conjugateGradients(const support::BlockSparseMatrix::Matrix& A,
                                   const Eigen::VectorXd& b, const Preconditioner& precondition,
                                   double tolerance, int limit)
{
  const auto S = A.selfadjointView<Eigen::Lower>();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(b.size());
  Eigen::VectorXd r = b;
  Eigen::VectorXd z = precondition(r);
  Eigen::VectorXd p = z;
  double rz = r.dot(z);
  const double target = tolerance * b.norm();
  for (int iteration = 0; iteration < limit && r.norm() > target; ++iteration)
  {
    const Eigen::VectorXd q = S * p;
    const double curvature = p.dot(q);
    if (!(curvature > 0))
      break;
    const double alpha = rz / curvature;
    x += alpha * p;
    r -= alpha * q;
    z = precondition(r);
    const double next = r.dot(z);
    p = z + (next / rz) * p;
    rz = next;
  }
  return x;
}

std::size_t decideAll(const std::vector<EnergyTerm*>& terms, const double* x)
{
  std::size_t changed = 0;
  for (EnergyTerm* t : terms)
    changed += t->decide(x);
  return changed;
}
} // namespace

GaussNewtonSolver::GaussNewtonSolver(std::size_t vertexCount,
                                     const std::vector<std::array<std::int64_t, 2>>& pairs)
    : Hessian(vertexCount, pairs), Preconditioner(static_cast<long>(vertexCount))
{
}

namespace
{
// E at `trial`; the distance term (when given) per vertex into `dataAtTrial`, for the blame.
double energyAt(const std::vector<double>& trial, const std::vector<EnergyTerm*>& terms,
                const DistanceTerm* distance, std::vector<double>& dataAtTrial)
{
  double energy = 0;
  for (const EnergyTerm* t : terms)
  {
    if (t != distance)
    {
      energy += t->evaluate(trial.data(), nullptr);
      continue;
    }
    distance->vertexValues(trial.data(), dataAtTrial.data());
    for (double value : dataAtTrial)
      energy += value;
  }
  return energy;
}

// After a rejected step: damps the vertices whose distance term at the trial exceeds the model's
// promise by a fifth of the shortfall (they sit on a ridge of the field). False when none did.
bool blameVertices(const DistanceTerm* distance, const Eigen::VectorXd& step,
                   const std::vector<double>& dataAtTrial, double shortfall,
                   std::vector<double>& vertexDamping)
{
  bool blamed = false;
  for (std::size_t v = 0; distance && v < vertexDamping.size() && shortfall > 0; ++v)
  {
    const double c = distance->stiffness(v);
    if (c == 0)
      continue;
    if (dataAtTrial[v] - distance->promised(v, &step[static_cast<Eigen::Index>(3 * v)]) >
        0.2 * shortfall)
    {
      vertexDamping[v] = 10 * std::max(vertexDamping[v], c);
      blamed = true;
    }
  }
  return blamed;
}

// The damping of the steps: global (Levenberg, relative to the mean diagonal) plus per vertex
// (where the distance term keeps breaking the model's promise).
struct StepDamping
{
  double global = 1e-4;
  std::vector<double> vertex;

  // The shift of the Hessian's diagonal, 3 entries per vertex.
  Eigen::VectorXd shift(double meanDiagonal) const
  {
    Eigen::VectorXd out(static_cast<Eigen::Index>(3 * vertex.size()));
    for (std::size_t v = 0; v < vertex.size(); ++v)
      out.segment<3>(static_cast<Eigen::Index>(3 * v))
          .setConstant(global * meanDiagonal + vertex[v]);
    return out;
  }
  // After an accepted step (`good`: it kept most of its promise): less damping.
  void relax(bool good)
  {
    if (good)
      global = std::max(global * 0.3, 1e-9);
    for (double& d : vertex)
      d *= 0.3;
  }
  // After a rejected step: the blamed vertices damped, or if none, more global damping.
  void raise(const DistanceTerm* distance, const Eigen::VectorXd& step,
             const std::vector<double>& dataAtTrial, double shortfall)
  {
    if (!blameVertices(distance, step, dataAtTrial, shortfall, vertex))
      global = std::max(global * 10, RetryDamping);
  }
};

// The decrease the quadratic model (gradient, lower-stored Hessian H) promises for a step:
// -(gradient.step + step.H.step / 2).
double predictedDecrease(const Eigen::VectorXd& gradient, const Eigen::VectorXd& step,
                         const support::BlockSparseMatrix::Matrix& H)
{
  return -(gradient.dot(step) + 0.5 * step.dot(H.selfadjointView<Eigen::Lower>() * step));
}
} // namespace

double GaussNewtonSolver::buildModel(const std::vector<double>& x,
                                     const std::vector<EnergyTerm*>& terms,
                                     Eigen::VectorXd& gradient)
{
  for (EnergyTerm* t : terms)
    t->linearise(x.data());
  Hessian.setZero();
  gradient.setZero();
  double energy = 0;
  for (const EnergyTerm* t : terms)
    energy += t->addModel(x.data(), Hessian, gradient.data());
  return energy;
}

Eigen::VectorXd GaussNewtonSolver::dampedStep(const Eigen::VectorXd& gradient,
                                              const Eigen::VectorXd& shift, bool factorise)
{
  Hessian.addToDiagonal(shift);
  if (factorise)
    Preconditioner.factorise(Hessian.traceMatrix());
  const Eigen::VectorXd step =
      Preconditioner.factorised()
          ? conjugateGradients(
                Hessian.matrix(), -gradient,
                [&](const Eigen::VectorXd& r) { return Preconditioner.apply(r); }, StepTolerance,
                200)
          : Eigen::VectorXd(-gradient.cwiseQuotient(shift));
  Hessian.addToDiagonal(-shift);
  return step;
}

int GaussNewtonSolver::solve(std::vector<double>& x, const std::vector<EnergyTerm*>& terms,
                             const DistanceTerm* distance, const SolveSettings& settings)
{
  const std::size_t nv = Hessian.blockCount();
  const auto n = static_cast<Eigen::Index>(3 * nv);
  std::vector<double> trial(x.size()), dataAtTrial(nv, 0.0);
  StepDamping damping{1e-4, std::vector<double>(nv, 0.0)};
  Eigen::VectorXd gradient(n);
  int decisions = 0;
  int iteration = 0;
  for (; iteration < settings.maxIterations; ++iteration)
  {
    const double energyAtX = buildModel(x, terms, gradient);
    const double meanDiagonal = std::max(Hessian.diagonal().mean(), 1e-300);

    // One preconditioner per iteration, at the damping of its first attempt; later attempts
    // (more damping) reuse it. (Once per solve was 1.8x faster on the fine level at 1000
    // vertices, but its poorer steps end solves early: a sheet's frame lost 0.3 % more of its
    // points.) Damping is global (Levenberg) plus per vertex: where a vertex's distance term
    // keeps breaking the model's promise (it sits on a ridge of the field, between two parts of
    // the data), that vertex alone is damped, so it does not stall the others.
    bool accepted = false, converged = false;
    for (int attempt = 0; attempt < 12 && !accepted; ++attempt)
    {
      const Eigen::VectorXd step = dampedStep(gradient, damping.shift(meanDiagonal), attempt == 0);
      for (std::size_t i = 0; i < x.size(); ++i)
        trial[i] = x[i] + step[static_cast<Eigen::Index>(i)];
      const double predicted = predictedDecrease(gradient, step, Hessian.matrix());
      const double actual = energyAtX - energyAt(trial, terms, distance, dataAtTrial);
      if (predicted > 0 && actual > 0.1 * predicted)
      {
        accepted = true;
        x.swap(trial);
        damping.relax(actual > 0.75 * predicted);
        converged = actual <= settings.tolerance * std::abs(energyAtX) ||
                    step.cwiseAbs().maxCoeff() <= settings.settledStep;
        continue;
      }
      damping.raise(distance, step, dataAtTrial, predicted - actual);
    }
    // Settled: decide the terms' choices again at the new shape (at most `decisions` times); go
    // on only if that changed something.
    if (accepted && converged && decisions < settings.decisions && decideAll(terms, x.data()) > 0)
    {
      ++decisions;
      continue;
    }
    if (!accepted || converged)
      break; // no step decreases E any more, or the last one barely moved: a (local) minimum
  }
  return std::min(iteration + 1, settings.maxIterations); // models built
}

namespace
{
struct LbfgsObjective
{
  const std::vector<EnergyTerm*>* terms;
  std::size_t size;
  int evaluations = 0;
};

lbfgsfloatval_t evaluateForLbfgs(void* instance, const lbfgsfloatval_t* x, lbfgsfloatval_t* g,
                                 const int, const lbfgsfloatval_t)
{
  auto* objective = static_cast<LbfgsObjective*>(instance);
  ++objective->evaluations;
  std::fill(g, g + objective->size, 0.0);
  return evaluateAll(*objective->terms, x, g);
}

// Largest eigenvalue of the Hessian of the terms at x, by power iteration on finite differences
// of the gradient.
double largestCurvature(const std::vector<EnergyTerm*>& terms, const std::vector<double>& x,
                        double lengthScale)
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
    std::fill(gp.begin(), gp.end(), 0.0);
    std::fill(gm.begin(), gm.end(), 0.0);
    evaluateAll(terms, xp.data(), gp.data());
    evaluateAll(terms, xm.data(), gm.data());
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

int solveLbfgs(std::vector<double>& x, const std::vector<EnergyTerm*>& terms,
               const SolveSettings& settings)
{
  lbfgs_parameter_t parameters;
  lbfgs_parameter_init(&parameters);
  parameters.m = 8;
  parameters.max_iterations = settings.maxIterations;
  parameters.epsilon = 1e-8;
  parameters.past = 5;
  parameters.delta = 0.1 * settings.tolerance;
  parameters.linesearch = LBFGS_LINESEARCH_MORETHUENTE;
  LbfgsObjective objective{&terms, x.size()};
  // Two passes: after the first, the terms' choices are decided again at the new shape.
  for (int pass = 0; pass < 2; ++pass)
  {
    for (EnergyTerm* t : terms)
      t->linearise(x.data());
    lbfgsfloatval_t fx = 0;
    // Any stop (converged, iteration limit, line-search failure) leaves x at the best point
    // found, which is what the frame gets.
    lbfgs(static_cast<int>(x.size()), x.data(), &fx, evaluateForLbfgs, nullptr, &objective,
          &parameters);
    if (pass == 0)
      decideAll(terms, x.data());
  }
  return objective.evaluations;
}

namespace
{
// The paper's provisional determination (PD): a vertex that barely moves is frozen. The distance
// term's gradient has the same size everywhere, so a settled vertex keeps stepping but goes
// nowhere: over a window of iterations, it freezes when its net motion is under a quarter of the
// path it stepped, and wakes when a neighbour moves steadily (net motion over half its path).
class ProvisionalDetermination
{
public:
  static constexpr int Window = 5;

  ProvisionalDetermination(const TriangleMesh& mesh, const std::vector<double>& x)
      : Mesh(mesh), Anchor(x), Path(mesh.numberOfVertices(), 0.0),
        Steady(mesh.numberOfVertices(), 0), Still(mesh.numberOfVertices(), 0)
  {
  }

  bool frozen(std::size_t v) const { return Still[v] != 0; }
  void stepped(std::size_t v, double length) { Path[v] += length; }

  /** At the end of each window: decides who is still and who wakes, from x. */
  void endWindow(const std::vector<double>& x)
  {
    const std::size_t nv = Mesh.numberOfVertices();
    for (std::size_t v = 0; v < nv; ++v)
    {
      double d2 = 0;
      for (int k = 0; k < 3; ++k)
        d2 += (x[3 * v + k] - Anchor[3 * v + k]) * (x[3 * v + k] - Anchor[3 * v + k]);
      const double net = std::sqrt(d2);
      Steady[v] = Path[v] > 0 && net > 0.5 * Path[v];
      if (!Still[v] && Path[v] > 0 && net < 0.25 * Path[v])
        Still[v] = 1;
    }
    for (std::size_t v = 0; v < nv; ++v)
      if (Still[v])
        for (std::int64_t u : Mesh.neighbours(v))
          if (Steady[u])
          {
            Still[v] = 0; // a neighbour moves: wake up
            break;
          }
    Anchor = x;
    std::fill(Path.begin(), Path.end(), 0.0);
  }

  const std::vector<std::uint8_t>& still() const { return Still; }

private:
  const TriangleMesh& Mesh;
  std::vector<double> Anchor, Path;
  std::vector<std::uint8_t> Steady, Still;
};

// Steepest descent's stop: it compares the energy with the one ten iterations before. Its steps
// are short (h < 2 / k_max), so its gains are small long before it settles: it stops at a tenth
// of the relative gain the other solvers stop at.
bool stalled(std::vector<double>& recent, double energy, double tolerance)
{
  recent.push_back(energy);
  return recent.size() > 10 &&
         recent[recent.size() - 11] - energy <= 0.1 * tolerance * std::abs(energy);
}

// A step of h times the gradient down for each of the nv vertices but the frozen ones (when
// `freezing`); each vertex's step length is handed to the provisional determination.
void stepDown(std::vector<double>& x, const std::vector<double>& gradient, double h, std::size_t nv,
              bool freezing, ProvisionalDetermination& pd)
{
  for (std::size_t v = 0; v < nv; ++v)
  {
    if (freezing && pd.frozen(v))
      continue;
    double step2 = 0;
    for (int k = 0; k < 3; ++k)
    {
      const double d = h * gradient[3 * v + k];
      x[3 * v + k] -= d;
      step2 += d * d;
    }
    pd.stepped(v, std::sqrt(step2));
  }
}
} // namespace

int solveSteepestDescent(std::vector<double>& x, const std::vector<EnergyTerm*>& terms,
                         const TriangleMesh& mesh, double lengthScale,
                         const SolveSettings& settings, std::vector<std::uint8_t>* frozen)
{
  const std::size_t nv = mesh.numberOfVertices();
  for (EnergyTerm* t : terms)
    t->linearise(x.data());
  const double kMax = largestCurvature(terms, x, lengthScale);
  double h = kMax > 0 ? 1.9 / kMax : lengthScale;
  std::vector<double> gradient(x.size()), before;
  ProvisionalDetermination pd(mesh, x);
  std::vector<double> recent; // energies of the last iterations
  double previous = std::numeric_limits<double>::infinity();
  int iteration = 0;
  for (; iteration < settings.maxIterations; ++iteration)
  {
    std::fill(gradient.begin(), gradient.end(), 0.0);
    double e = evaluateAll(terms, x.data(), gradient.data());
    // h < 2 / k_max holds for the curvature where it was estimated; where the energy rises
    // anyway, take the step back and halve h.
    for (int halvings = 0; e > previous && halvings < 20 && !before.empty(); ++halvings)
    {
      h *= 0.5;
      x = before;
      std::fill(gradient.begin(), gradient.end(), 0.0);
      e = evaluateAll(terms, x.data(), gradient.data());
    }
    previous = e;
    before = x;
    if (stalled(recent, e, settings.tolerance))
      break;
    stepDown(x, gradient, h, nv, frozen != nullptr, pd);
    if (frozen &&
        iteration % ProvisionalDetermination::Window == ProvisionalDetermination::Window - 1)
      pd.endWindow(x);
    if (iteration % 25 == 24)
    {
      decideAll(terms, x.data());
      for (EnergyTerm* t : terms)
        t->linearise(x.data());
    }
  }
  if (frozen)
    *frozen = pd.still();
  return iteration + 1;
}

} // namespace dp
