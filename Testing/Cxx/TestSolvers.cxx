// SPDX-License-Identifier: BSD-3-Clause
// The fine level's solvers, the choice among them (FineSolver) and the trace preconditioner.

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/LocalThickness.h"
#include "dp/geometry/SurfaceLocator.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/track/AndersonAcceleration.h"
#include "dp/track/ClothEnergy.h"
#include "dp/track/CoverageTerm.h"
#include "dp/track/DeformationGraph.h"
#include "dp/track/DistanceTerm.h"
#include "dp/track/FineSolver.h"
#include "dp/track/FrameData.h"
#include "dp/track/FrameQuality.h"
#include "dp/track/GraphRegistration.h"
#include "dp/track/InternalEnergyTerm.h"
#include "dp/track/Solvers.h"
#include "dp/track/TemporalTerm.h"
#include "dp/track/TracePreconditioner.h"
#include "dp/track/Tracker.h"

#include "NumericChecks.h"
#include "TrackingShapes.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <random>
#include <utility>

namespace
{

using dp::test::expectGradientMatches;
using dp::test::Frame;
using dp::test::jiggle;
using dp::test::Shape;
using dp::test::tube;

// Springs of rest length zero between vertices plus anchors pulling each vertex to a target:
// E = sum k_ab |x_a - x_b|^2 / 2 + sum c_v |x_v - t_v|^2 / 2. Its Gauss-Newton matrix is
// (weighted Laplacian + diag c) (x) I_3, exactly the solver's preconditioner.
class SpringsAndAnchors : public dp::EnergyTerm
{
public:
  std::vector<std::array<std::int64_t, 2>> springs;
  std::vector<double> stiffness, anchor, target;
  const char* name() const override { return "springs and anchors"; }
  double evaluate(const double* x, double* gradient) const override
  {
    double e = 0;
    for (std::size_t s = 0; s < springs.size(); ++s)
      for (int k = 0; k < 3; ++k)
      {
        const double d = x[3 * springs[s][0] + k] - x[3 * springs[s][1] + k];
        e += 0.5 * stiffness[s] * d * d;
        if (gradient)
        {
          gradient[3 * springs[s][0] + k] += stiffness[s] * d;
          gradient[3 * springs[s][1] + k] -= stiffness[s] * d;
        }
      }
    for (std::size_t i = 0; i < target.size(); ++i)
    {
      const double d = x[i] - target[i];
      e += 0.5 * anchor[i / 3] * d * d;
      if (gradient)
        gradient[i] += anchor[i / 3] * d;
    }
    return e;
  }
  double addModel(const double* x, dp::support::BlockSparseMatrix& hessian,
                  double* gradient) const override
  {
    const auto scaledIdentity = [](double w)
    {
      std::array<double, 9> m{};
      m[0] = m[4] = m[8] = w;
      return m;
    };
    for (std::size_t s = 0; s < springs.size(); ++s)
    {
      const std::int64_t a = springs[s][0], b = springs[s][1];
      hessian.addBlock(hessian.slotOf(a, a), scaledIdentity(stiffness[s]).data());
      hessian.addBlock(hessian.slotOf(b, b), scaledIdentity(stiffness[s]).data());
      hessian.addBlock(hessian.slotOf(a, b), scaledIdentity(-stiffness[s]).data());
    }
    for (std::size_t v = 0; v < anchor.size(); ++v)
      hessian.addBlock(hessian.slotOf(static_cast<std::int64_t>(v), static_cast<std::int64_t>(v)),
                       scaledIdentity(anchor[v]).data());
    return evaluate(x, gradient);
  }
  void couplings(std::vector<std::array<std::int64_t, 2>>& pairs) const override
  {
    pairs.insert(pairs.end(), springs.begin(), springs.end());
  }
};

// The minimum of springs and anchors: (L + C) X = C T, three right-hand sides (x y z per column).
Eigen::MatrixXd exactMinimum(const SpringsAndAnchors& term, std::int64_t n)
{
  std::vector<Eigen::Triplet<double>> entries;
  for (std::size_t s = 0; s < term.springs.size(); ++s)
  {
    const auto a = static_cast<int>(term.springs[s][0]), b = static_cast<int>(term.springs[s][1]);
    entries.emplace_back(a, a, term.stiffness[s]);
    entries.emplace_back(b, b, term.stiffness[s]);
    entries.emplace_back(a, b, -term.stiffness[s]);
    entries.emplace_back(b, a, -term.stiffness[s]);
  }
  Eigen::MatrixXd rhs(n, 3);
  for (std::int64_t v = 0; v < n; ++v)
  {
    entries.emplace_back(static_cast<int>(v), static_cast<int>(v), term.anchor[v]);
    for (int k = 0; k < 3; ++k)
      rhs(v, k) = term.anchor[v] * term.target[3 * v + k];
  }
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(entries.begin(), entries.end());
  return Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>(A).solve(rhs);
}

// When the preconditioner is the model's own matrix, conjugate gradients solve each step exactly:
// Levenberg-Marquardt reaches the minimum in a few steps whatever the fill-reducing order of the
// factor, so any slip in applying it (order, transposes, D) shows. Run on n vertices: below and
// at the size from which the preconditioner's factorisation is supernodal.
void solvesAQuadraticInFewSteps(std::int64_t n)
{
  std::mt19937 random(5);
  std::uniform_real_distribution<double> unit(0, 1);
  SpringsAndAnchors term;
  for (std::int64_t v = 0; v + 1 < n; ++v)
    term.springs.push_back({v, v + 1});
  for (std::int64_t s = 0; s < 3 * n; ++s)
  {
    const auto a = static_cast<std::int64_t>(unit(random) * n), b = (a + 7 + s % 53) % n;
    if (a != b)
      term.springs.push_back({std::min(a, b), std::max(a, b)});
  }
  for (std::size_t s = 0; s < term.springs.size(); ++s)
    term.stiffness.push_back(0.5 + 10 * unit(random));
  for (std::int64_t v = 0; v < n; ++v)
    term.anchor.push_back(v % 5 == 0 ? 1 + unit(random) : 1e-3);
  for (std::int64_t i = 0; i < 3 * n; ++i)
    term.target.push_back(unit(random) - 0.5);

  const Eigen::MatrixXd minimum = exactMinimum(term, n);

  std::vector<std::array<std::int64_t, 2>> pairs;
  term.couplings(pairs);
  dp::GaussNewtonSolver solver(static_cast<std::size_t>(n), pairs);
  std::vector<double> x(3 * n, 0.0);
  dp::SolveSettings settings;
  settings.tolerance = 1e-12;
  settings.maxIterations = 40;
  const int iterations = solver.solve(x, {&term}, nullptr, settings);
  EXPECT_LE(iterations, 6);
  double error = 0;
  for (std::int64_t v = 0; v < n; ++v)
    for (int k = 0; k < 3; ++k)
      error = std::max(error, std::abs(x[3 * v + k] - minimum(v, k)));
  EXPECT_LT(error, 1e-6 * minimum.cwiseAbs().maxCoeff());
}

TEST(GaussNewtonSolver, SolvesAQuadraticItsPreconditionerFactorsExactlyInFewSteps)
{
  solvesAQuadraticInFewSteps(400);
  solvesAQuadraticInFewSteps(dp::TracePreconditioner::SupernodalFrom);
}

// P of a triangulated w x h grid (weighted Laplacian plus a positive diagonal), a surface mesh's
// pattern.
Eigen::SparseMatrix<double> gridTraceMatrix(int w, int h, std::mt19937& random)
{
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<Eigen::Triplet<double>> entries;
  const auto couple = [&](int a, int b)
  {
    const double k = 0.5 + unit(random);
    entries.emplace_back(std::max(a, b), std::min(a, b), -k);
    entries.emplace_back(a, a, k);
    entries.emplace_back(b, b, k);
  };
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
    {
      const int v = j * w + i;
      entries.emplace_back(v, v, 1e-2 * (1 + unit(random)));
      if (i + 1 < w)
        couple(v, v + 1);
      if (j + 1 < h)
        couple(v, v + w);
      if (i + 1 < w && j + 1 < h)
        couple(v, v + w + 1);
    }
  Eigen::SparseMatrix<double> P(w * h, w * h);
  P.setFromTriplets(entries.begin(), entries.end());
  return P;
}

TEST(TracePreconditioner, BothFactorisationsSolveEachCoordinateAndAgree)
{
  std::mt19937 random(3);
  const int w = 60, h = 60; // 3 600 vertices: the supernodal kind by default
  const Eigen::SparseMatrix<double> P = gridTraceMatrix(w, h, random);
  const Eigen::VectorXd r = Eigen::VectorXd::Random(3 * P.rows());
  const auto S = P.selfadjointView<Eigen::Lower>();
  std::vector<Eigen::VectorXd> solutions;
  for (auto kind :
       {dp::TracePreconditioner::Kind::Automatic, dp::TracePreconditioner::Kind::Simplicial})
  {
    dp::TracePreconditioner preconditioner(P.rows(), kind);
    EXPECT_EQ(preconditioner.supernodal(), kind == dp::TracePreconditioner::Kind::Automatic);
    ASSERT_TRUE(preconditioner.factorise(P));
    ASSERT_TRUE(preconditioner.factorise(P)); // the same pattern again: analysis reused
    const Eigen::VectorXd z = preconditioner.apply(r);
    for (int k = 0; k < 3; ++k) // P z_k = r_k, coordinate by coordinate
    {
      Eigen::VectorXd zk(P.rows()), rk(P.rows());
      for (Eigen::Index v = 0; v < P.rows(); ++v)
      {
        zk[v] = z[3 * v + k];
        rk[v] = r[3 * v + k];
      }
      EXPECT_LT((S * zk - rk).norm(), 1e-9 * rk.norm()) << "coordinate " << k;
    }
    solutions.push_back(z);
  }
  EXPECT_LT((solutions[0] - solutions[1]).norm(), 1e-8 * solutions[1].norm());
  EXPECT_FALSE(dp::TracePreconditioner(1000).supernodal());
}

TEST(TracePreconditioner, TheSupernodalFactorisationReportsAMatrixThatIsNotPositiveDefinite)
{
  // Its LL^T needs P positive definite; the solver then falls back to a diagonal step.
  std::mt19937 random(4);
  Eigen::SparseMatrix<double> P = gridTraceMatrix(30, 30, random);
  dp::TracePreconditioner preconditioner(P.rows(), dp::TracePreconditioner::Kind::Supernodal);
  EXPECT_TRUE(preconditioner.factorise(P));
  P.coeffRef(450, 450) = -5; // a negative pivot
  EXPECT_FALSE(preconditioner.factorise(P));
  EXPECT_FALSE(preconditioner.factorised());
}

TEST(FineSolver, EachMethodTheOptionsNameReachesTheMinimumOnTheMeshsCouplings)
{
  // Springs along the tube's edges and across its hinges (every pair the fine level's terms may
  // couple, which the Gauss-Newton matrix's pattern must hold), anchors to random targets: each
  // method ends at the minimum a sparse solve gives, Gauss-Newton closest.
  const Shape shape = tube();
  const dp::TriangleMesh mesh(shape.triangles, shape.positions.size() / 3);
  const auto n = static_cast<std::int64_t>(mesh.numberOfVertices());
  std::mt19937 random(3);
  std::uniform_real_distribution<double> unit(0, 1);
  SpringsAndAnchors term;
  for (const auto& e : mesh.edges())
    term.springs.push_back({std::min(e[0], e[1]), std::max(e[0], e[1])});
  for (const auto& h : mesh.hinges())
    term.springs.push_back({std::min(h[2], h[3]), std::max(h[2], h[3])});
  for (std::size_t s = 0; s < term.springs.size(); ++s)
    term.stiffness.push_back(0.2 + 0.3 * unit(random));
  term.anchor.assign(static_cast<std::size_t>(n), 1.0);
  for (std::int64_t i = 0; i < 3 * n; ++i)
    term.target.push_back(unit(random) - 0.5);
  const Eigen::MatrixXd minimum = exactMinimum(term, n);
  const double scale = minimum.cwiseAbs().maxCoeff();

  const std::pair<dp::TrackerSolver, double> methods[] = {
      {dp::TrackerSolver::GaussNewton, 1e-6},
      {dp::TrackerSolver::LBFGS, 1e-4},
      {dp::TrackerSolver::SteepestDescent, 1e-3}};
  for (const auto& [method, tolerance] : methods)
  {
    dp::TrackerOptions options;
    options.solver = method;
    options.provisionalDetermination = false;
    const std::unique_ptr<dp::FineSolver> solver = dp::FineSolver::make(options, mesh, 1.0);
    EXPECT_EQ(solver->takesFewStepsAfterCoarseLevel(), method == dp::TrackerSolver::GaussNewton);
    std::vector<double> x(3 * n, 0.0);
    std::vector<std::uint8_t> frozen(static_cast<std::size_t>(n), 0);
    dp::SolveSettings settings;
    settings.tolerance = 1e-12;
    settings.maxIterations = 3000;
    EXPECT_GT(solver->solve(x, {&term}, nullptr, settings, frozen), 0);
    double error = 0;
    for (std::int64_t v = 0; v < n; ++v)
      for (int k = 0; k < 3; ++k)
        error = std::max(error, std::abs(x[3 * v + k] - minimum(v, k)));
    EXPECT_LT(error, tolerance * scale) << "solver " << static_cast<int>(method);
    // Without provisional determination nothing is frozen.
    EXPECT_EQ(std::count(frozen.begin(), frozen.end(), 1), 0) << static_cast<int>(method);
  }
}

} // namespace
