// SPDX-License-Identifier: BSD-3-Clause
// The energy terms (internal, distance, coverage, temporal): gradients and Gauss-Newton models
// against finite differences; the coverage term's pull and followed matches; the sum of terms
// (EnergyTerm.h) and the robust kernels' weights against their penalties' slopes.

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
#include "dp/track/EnergyTerm.h"
#include "dp/track/FrameData.h"
#include "dp/track/FrameQuality.h"
#include "dp/track/GraphRegistration.h"
#include "dp/track/InternalEnergyTerm.h"
#include "dp/track/RobustKernel.h"
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

class Terms : public ::testing::TestWithParam<int>
{
};

// Term number `kind` of the suite on frame f: 0 internal, 1 distance to the planes (squared), 2
// the paper's distance to the points (linear), 3 robust, 4 points -> mesh, 5 temporal.
std::unique_ptr<dp::EnergyTerm> termOf(int kind, const Frame& f, const dp::ClothEnergy& cloth,
                                       const std::vector<double>& target)
{
  dp::DistanceTermOptions d;
  d.normalTestDegrees = 180;
  dp::CoverageOptions c;
  c.robustScale = 3 * f.voxel;
  switch (kind)
  {
  case 0:
    return std::make_unique<dp::InternalEnergyTerm>(cloth);
  case 1:
    return std::make_unique<dp::DistanceTerm>(*f.data, f.mesh, f.mass, f.L, d);
  case 2:
    d.measure = dp::DistanceMeasure::Points;
    d.squared = false;
    return std::make_unique<dp::DistanceTerm>(*f.data, f.mesh, f.mass, f.L, d);
  case 3:
    d.robustScale = 2 * f.voxel;
    return std::make_unique<dp::DistanceTerm>(*f.data, f.mesh, f.mass, f.L, d);
  case 4:
    return std::make_unique<dp::CoverageTerm>(f.data->spreadSamples(), f.mesh, f.L, c);
  default:
    return std::make_unique<dp::TemporalTerm>(target, f.mass, 3.0, f.L, f.voxel);
  }
}

// The model's matrix as a dense symmetric matrix (it stores its lower triangle, diagonal blocks
// whole: that triangle, mirrored).
Eigen::MatrixXd denseModel(const dp::support::BlockSparseMatrix& H)
{
  const Eigen::MatrixXd lower = Eigen::MatrixXd(H.matrix()).triangularView<Eigen::Lower>();
  Eigen::MatrixXd dense = lower + lower.transpose();
  dense.diagonal() /= 2;
  return dense;
}

TEST_P(Terms, GradientAndModelMatchFiniteDifferences)
{
  Frame f(tube().positions);
  const std::vector<double> target = jiggle(f.shape.positions, 0.01, 4);
  const dp::ClothEnergy cloth(f.mesh, f.shape.positions.data(), dp::ClothParameters{1, 0.1, 0.5});
  const std::unique_ptr<dp::EnergyTerm> term = termOf(GetParam(), f, cloth, target);
  const std::vector<double> x = jiggle(f.shape.positions, 0.01, 9);
  term->decide(x.data());
  term->linearise(x.data());
  // Small steps stay inside the distance field's voxel cells, where D is smooth.
  expectGradientMatches([&](const double* p, double* g) { return term->evaluate(p, g); }, x,
                        GetParam() == 0 ? 1e-5 : 2e-4, GetParam() == 0 ? 1e-6 : 1e-8);
  std::vector<std::array<std::int64_t, 2>> pairs;
  term->couplings(pairs);
  dp::support::BlockSparseMatrix H(f.mesh.numberOfVertices(), pairs);
  std::vector<double> modelGradient(x.size(), 0.0), gradient(x.size(), 0.0);
  const double modelValue = term->addModel(x.data(), H, modelGradient.data());
  const double value = term->evaluate(x.data(), gradient.data());
  EXPECT_NEAR(modelValue, value, 1e-12 * std::abs(value));
  const Eigen::Map<const Eigen::VectorXd> a(modelGradient.data(),
                                            static_cast<Eigen::Index>(x.size()));
  const Eigen::Map<const Eigen::VectorXd> b(gradient.data(), static_cast<Eigen::Index>(x.size()));
  if (GetParam() >= 1 && GetParam() <= 3)
  {
    // The distance term's model holds the field's interpolation weights (and, for the paper's
    // D, reweights by 1 / max(D, voxel)): its gradient leaves out the weights' own slopes, a
    // voxel-scale ripple, so it points the way the true gradient does without equalling it.
    EXPECT_GT(a.dot(b), 0.95 * a.norm() * b.norm());
  }
  else
    EXPECT_LT((a - b).norm(), 1e-9 * b.norm());
  // The model's matrix is positive semidefinite (a sum of J^T W J).
  const Eigen::MatrixXd dense = denseModel(H);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(dense);
  EXPECT_GT(eigen.eigenvalues().minCoeff(), -1e-9 * eigen.eigenvalues().maxCoeff());
  // Points -> mesh and temporal terms are quadratic for fixed correspondences: their model is
  // exact, so it predicts the term after a step.
  if (GetParam() >= 4)
  {
    const std::vector<double> step = jiggle(std::vector<double>(x.size(), 0.0), 0.003, 2);
    std::vector<double> moved(x);
    for (std::size_t i = 0; i < x.size(); ++i)
      moved[i] += step[i];
    const Eigen::Map<const Eigen::VectorXd> s(step.data(), static_cast<Eigen::Index>(step.size()));
    const Eigen::Map<const Eigen::VectorXd> g(gradient.data(),
                                              static_cast<Eigen::Index>(gradient.size()));
    const double predicted = value + g.dot(s) + 0.5 * s.dot(dense * s);
    EXPECT_NEAR(term->evaluate(moved.data(), nullptr), predicted, 1e-9 * std::abs(value));
  }
}

INSTANTIATE_TEST_SUITE_P(Internal_Planes_Points_Robust_Coverage_Temporal, Terms,
                         ::testing::Values(0, 1, 2, 3, 4, 5));

TEST(CoverageTerm, PullsTheMeshOntoDataItLetGoOf)
{
  // The data moved away from the mesh: the mesh -> points term sees nothing wrong with a mesh
  // sitting on a part of the data, but points it does not cover pull it back.
  Frame f(tube().positions);
  std::vector<double> x = f.shape.positions;
  for (std::size_t i = 0; i < x.size(); i += 3)
    x[i] += 0.02; // the mesh is 0.02 off in x
  dp::CoverageOptions c;
  dp::CoverageTerm coverage(f.data->spreadSamples(), f.mesh, f.L, c);
  coverage.linearise(x.data());
  std::vector<double> g(x.size(), 0.0);
  coverage.evaluate(x.data(), g.data());
  double pull = 0;
  for (std::size_t i = 0; i < x.size(); i += 3)
    pull += g[i];
  EXPECT_GT(pull, 0) << "the descent direction moves the mesh back toward -x";
  std::size_t matched = 0;
  for (const auto& m : coverage.matches())
    matched += m.triangle >= 0;
  EXPECT_GT(matched, coverage.matches().size() / 2);
  // A normal test refuses points whose normals disagree with the mesh's: turned around, none
  // pull.
  f.data->flipNormals();
  dp::CoverageTerm flipped(f.data->spreadSamples(), f.mesh, f.L, c);
  flipped.linearise(x.data());
  matched = 0;
  for (const auto& m : flipped.matches())
    matched += m.triangle >= 0;
  EXPECT_EQ(matched, 0u);
}

TEST(CoverageTerm, FollowedMatchesAreTheSearchedOnes)
{
  // The mesh moved since the matches were searched: followed over the surface (and searched
  // again where a walk ends farther than a voxel, 0.018 here), they are those a search of the
  // whole surface finds.
  Frame f(tube().positions);
  const auto& tri = f.mesh.triangles();
  for (const double shift : {0.005, 0.06})
  {
    std::vector<double> moved = jiggle(f.shape.positions, 0.001, 3);
    for (std::size_t i = 0; i < moved.size(); i += 3)
      moved[i] += shift;
    dp::CoverageOptions c;
    c.followMatches = true;
    dp::CoverageTerm followed(f.data->spreadSamples(), f.mesh, f.L, c);
    c.followMatches = false;
    dp::CoverageTerm searched(f.data->spreadSamples(), f.mesh, f.L, c);
    for (dp::CoverageTerm* term : {&followed, &searched})
    {
      term->linearise(f.shape.positions.data());
      term->linearise(moved.data());
    }
    std::size_t matched = 0;
    for (std::size_t i = 0; i < followed.matches().size(); ++i)
    {
      const auto &a = followed.matches()[i], &b = searched.matches()[i];
      // The same closest point (where it is a vertex, any triangle around it may hold it).
      ASSERT_EQ(a.triangle >= 0, b.triangle >= 0) << "shift " << shift << ", point " << i;
      if (a.triangle < 0)
        continue;
      ++matched;
      for (int k = 0; k < 3; ++k)
      {
        double pa = 0, pb = 0;
        for (int v = 0; v < 3; ++v)
        {
          pa += a.barycentric[v] * moved[3 * tri[3 * a.triangle + v] + k];
          pb += b.barycentric[v] * moved[3 * tri[3 * b.triangle + v] + k];
        }
        ASSERT_NEAR(pa, pb, 1e-12) << "shift " << shift << ", point " << i;
      }
      EXPECT_NEAR(a.weight, b.weight, 1e-12);
    }
    EXPECT_GT(matched, followed.matches().size() / 2);
  }
}

TEST(EnergyTerm, TheSumAddsEachTermsValueAndGradient)
{
  // evaluateAll against each term evaluated alone: the values sum, and the gradients are added to
  // what the buffer held (the solvers add several sums into one).
  Frame f(tube().positions);
  const dp::ClothEnergy cloth(f.mesh, f.shape.positions.data(), dp::ClothParameters{1, 0.1, 0.5});
  const std::vector<double> target = jiggle(f.shape.positions, 0.01, 4);
  dp::InternalEnergyTerm internal(cloth);
  dp::TemporalTerm temporal(target, f.mass, 3.0, f.L, f.voxel);
  const std::vector<double> x = jiggle(f.shape.positions, 0.01, 9);
  std::vector<double> gInternal(x.size(), 0.0), gTemporal(x.size(), 0.0), g(x.size(), 0.25);
  const double eInternal = internal.evaluate(x.data(), gInternal.data());
  const double eTemporal = temporal.evaluate(x.data(), gTemporal.data());
  ASSERT_GT(eInternal, 0);
  ASSERT_GT(eTemporal, 0);
  const double e = dp::evaluateAll({&internal, &temporal}, x.data(), g.data());
  EXPECT_NEAR(e, eInternal + eTemporal, 1e-14 * e);
  for (std::size_t i = 0; i < x.size(); ++i)
    ASSERT_NEAR(g[i], 0.25 + gInternal[i] + gTemporal[i], 1e-12) << i;
  // Without a gradient buffer, the same value; no terms, nothing.
  EXPECT_EQ(dp::evaluateAll({&internal, &temporal}, x.data(), nullptr), e);
  std::vector<double> untouched(x.size(), 0.25);
  EXPECT_EQ(dp::evaluateAll({}, x.data(), untouched.data()), 0.0);
  EXPECT_EQ(untouched, std::vector<double>(x.size(), 0.25));
}

// A term with only what every term must have: E = |x - c|^2 / 2 over one vertex.
class PointPull : public dp::EnergyTerm
{
public:
  const char* name() const override { return "pull"; }
  double evaluate(const double* x, double* gradient) const override
  {
    double e = 0;
    for (int k = 0; k < 3; ++k)
    {
      e += 0.5 * (x[k] - k) * (x[k] - k);
      if (gradient)
        gradient[k] += x[k] - k;
    }
    return e;
  }
  double addModel(const double* x, dp::support::BlockSparseMatrix& hessian,
                  double* gradient) const override
  {
    const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    hessian.addBlock(hessian.slotOf(0, 0), identity);
    return evaluate(x, gradient);
  }
};

TEST(EnergyTerm, ATermWithoutChoicesDecidesNothingAndCouplesNothing)
{
  // The defaults: no discrete choice changes, no coupling beyond each vertex with itself.
  PointPull term;
  const double x[3] = {1, 2, 3};
  term.linearise(x);
  EXPECT_EQ(term.decide(x), 0u);
  std::vector<std::array<std::int64_t, 2>> pairs = {{4, 5}};
  term.couplings(pairs);
  EXPECT_EQ(pairs, (std::vector<std::array<std::int64_t, 2>>{{4, 5}}));
  EXPECT_EQ(term.evaluate(x, nullptr), 0.5 * (1 + 1 + 1));
}

// The penalty whose iteratively reweighted least squares weight the kernel gives: rho(r) with
// rho'(r) = w(u^2) r, u = r / s (Geman-McClure: s^2/2 u^2/(1+u^2); Huber: quadratic up to s,
// linear beyond; none: r^2 / 2).
double penalty(dp::RobustKernel::Kind kind, double r, double s)
{
  const double u2 = (r / s) * (r / s);
  switch (kind)
  {
  case dp::RobustKernel::Kind::GemanMcClure:
    return 0.5 * s * s * u2 / (1 + u2);
  case dp::RobustKernel::Kind::Huber:
    return std::abs(r) <= s ? 0.5 * r * r : s * std::abs(r) - 0.5 * s * s;
  default:
    return 0.5 * r * r;
  }
}

TEST(RobustKernel, TheWeightTimesTheResidualIsThePenaltysSlope)
{
  // Each kernel's weight against the central difference of its closed-form penalty, at residuals
  // from a hundredth to a hundred scales (away from Huber's kink at the scale).
  for (const auto kind : {dp::RobustKernel::Kind::GemanMcClure, dp::RobustKernel::Kind::Huber,
                          dp::RobustKernel::Kind::None})
  {
    dp::RobustKernel kernel;
    kernel.kind = kind;
    kernel.scale = 0.3;
    const double s = kernel.scale;
    for (double ratio : {0.01, 0.2, 0.7, 0.97, 1.03, 1.5, 3.0, 10.0, 100.0})
      for (double sign : {-1.0, 1.0})
      {
        const double r = sign * ratio * s, h = 1e-6 * s;
        const double slope = (penalty(kind, r + h, s) - penalty(kind, r - h, s)) / (2 * h);
        const double weight = kernel.weightOfSquaredRatio((r / s) * (r / s));
        EXPECT_NEAR(weight * r, slope, 1e-7 * std::max(std::abs(slope), s))
            << "kind " << static_cast<int>(kind) << ", r / s = " << r / s;
      }
    // A residual of nothing has the full weight.
    EXPECT_EQ(kernel.weightOfSquaredRatio(0), 1.0);
  }
}

TEST(RobustKernel, OnlyAKernelWithAScaleWeighs)
{
  dp::RobustKernel kernel;
  EXPECT_FALSE(kernel.active()); // none, scale 0
  kernel.kind = dp::RobustKernel::Kind::GemanMcClure;
  EXPECT_FALSE(kernel.active()); // a scale of 0: plain least squares
  kernel.scale = 1;
  EXPECT_TRUE(kernel.active());
  kernel.kind = dp::RobustKernel::Kind::None;
  EXPECT_FALSE(kernel.active());
  EXPECT_EQ(kernel.weightOfSquaredRatio(1e6), 1.0);
  // Geman-McClure fades out far residuals faster than Huber: 1/u^4 against 1/u.
  dp::RobustKernel gm{dp::RobustKernel::Kind::GemanMcClure, 1},
      huber{dp::RobustKernel::Kind::Huber, 1};
  EXPECT_EQ(gm.weightOfSquaredRatio(1), 0.25);
  EXPECT_EQ(huber.weightOfSquaredRatio(1), 1.0);
  EXPECT_EQ(huber.weightOfSquaredRatio(16), 0.25);
  EXPECT_EQ(gm.weightOfSquaredRatio(3), 1.0 / 16);
}

} // namespace
