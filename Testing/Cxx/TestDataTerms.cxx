// SPDX-License-Identifier: BSD-3-Clause
// The energy terms (internal, distance, coverage, temporal): gradients and Gauss-Newton models
// against finite differences; the coverage term's pull and followed matches.

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

} // namespace
