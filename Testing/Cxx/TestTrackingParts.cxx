// SPDX-License-Identifier: BSD-3-Clause
// The tracker's parts, each alone: the closest-point locator against brute force, every energy
// term's gradient and Gauss-Newton model against finite differences, the deformation graph
// (rigid motions, geodesic blending, fitting), the coarse level's node-space gradient and the
// local thickness that softens trunks.
#include "dp/geometry/BoundingBox.h"
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
#include "dp/track/LocalThickness.h"
#include "dp/track/Solvers.h"
#include "dp/track/SurfaceLocator.h"
#include "dp/track/TemporalTerm.h"
#include "dp/track/TracePreconditioner.h"
#include "dp/track/Tracker.h"

#include "NumericChecks.h"

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

struct Shape
{
  std::vector<std::int64_t> triangles;
  std::vector<double> positions;
};

Shape tube(std::size_t rings = 10, std::size_t segments = 12)
{
  dp::BendingTube::Options o;
  o.rings = rings;
  o.segments = segments;
  dp::BendingTube t(o);
  return {t.triangles(), t.positions(0)};
}

using dp::test::expectGradientMatches;
using dp::test::jiggle;

// The frame data of a tube's samples (with their true normals), voxel = diagonal / 60.
struct Frame
{
  Shape shape;
  dp::TriangleMesh mesh{shape.triangles, shape.positions.size() / 3};
  double voxel = dp::boundingBoxDiagonal(shape.positions) / 60;
  std::unique_ptr<dp::FrameData> data;
  std::vector<double> mass;
  double L = 0;
  // `truth`: the frame's vertex positions on `base`'s connectivity (the template).
  explicit Frame(const std::vector<double>& truth, bool estimateNormals = false,
                 Shape base = tube())
      : shape(std::move(base))
  {
    dp::SamplerOptions o;
    o.pointsPerFrame = 3000;
    const dp::PointCloud c = dp::sampleSurface(truth, shape.triangles, o, 0);
    dp::FrameDataOptions fo;
    fo.voxelSize = voxel;
    fo.surfaceArea = mesh.totalArea(shape.positions.data());
    fo.spreadCount = 600;
    data = std::make_unique<dp::FrameData>(c.points.data(), c.numberOfPoints(),
                                           estimateNormals ? nullptr : c.normals.data(), fo);
    const dp::ClothEnergy cloth(mesh, shape.positions.data(), dp::ClothParameters{});
    mass = cloth.vertexMass();
    L = cloth.lengthScale();
  }
};

TEST(SurfaceLocator, FindsTheClosestPointsBruteForceFinds)
{
  const Shape s = tube(8, 10);
  const dp::TriangleMesh mesh(s.triangles, s.positions.size() / 3);
  dp::SurfaceLocator locator(mesh, s.positions.data());
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.6, 1.6);
  auto brute = [&](const std::vector<double>& x, const double p[3])
  {
    double best = HUGE_VAL;
    for (std::size_t t = 0; t < mesh.numberOfTriangles(); ++t)
    {
      double w[3], c[3];
      best = std::min(best, dp::closestPointOnTriangle(p, &x[3 * s.triangles[3 * t]],
                                                       &x[3 * s.triangles[3 * t + 1]],
                                                       &x[3 * s.triangles[3 * t + 2]], w, c));
    }
    return best;
  };
  for (int round = 0; round < 2; ++round)
  {
    // Round 1: the same tree refitted to a deformed shape.
    const std::vector<double> x = round == 0 ? s.positions : jiggle(s.positions, 0.05, 8);
    if (round == 1)
      locator.refit(x.data());
    for (int i = 0; i < 300; ++i)
    {
      const double p[3] = {0.4 * u(rng), 0.4 * u(rng), u(rng)};
      const double expected = brute(x, p);
      const dp::SurfaceLocator::Hit hit = locator.closest(p);
      ASSERT_GE(hit.triangle, 0);
      EXPECT_NEAR(hit.squaredDistance, expected, 1e-12);
      // The barycentric weights give the point, which lies at that distance.
      double d2 = 0, sum = 0;
      for (int k = 0; k < 3; ++k)
      {
        double q = 0;
        for (int c = 0; c < 3; ++c)
          q += hit.barycentric[c] * x[3 * s.triangles[3 * hit.triangle + c] + k];
        EXPECT_NEAR(q, hit.point[k], 1e-12);
        d2 += (q - p[k]) * (q - p[k]);
        sum += hit.barycentric[k];
      }
      EXPECT_NEAR(sum, 1.0, 1e-12);
      EXPECT_NEAR(d2, expected, 1e-12);
      // A hint (any triangle) does not change the answer; a bound below the distance finds none.
      EXPECT_EQ(locator.closest(p, HUGE_VAL, i % 50).triangle, hit.triangle);
      EXPECT_EQ(locator.closest(p, 0.99 * std::sqrt(expected)).triangle, -1);
    }
  }
}

TEST(SurfaceLocator, TreesOfEverySizeFindWhatBruteForceFinds)
{
  // Strips of 1 to 40 triangles, crumpled at random: trees of one leaf, and four-child nodes
  // with one to four children, leaves and inner nodes mixed. Every triangle as a hint.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int count = 1; count <= 40; ++count)
  {
    std::vector<double> positions;
    std::vector<std::int64_t> triangles;
    for (int i = 0; i < count + 2; ++i)
      positions.insert(positions.end(),
                       {0.3 * i + 0.1 * u(rng), 0.3 * (i % 2) + 0.1 * u(rng), 0.2 * u(rng)});
    for (int t = 0; t < count; ++t)
      triangles.insert(triangles.end(), {t, t + 1, t + 2});
    const dp::TriangleMesh mesh(triangles, positions.size() / 3);
    const dp::SurfaceLocator locator(mesh, positions.data());
    for (int i = 0; i < 20; ++i)
    {
      const double p[3] = {0.3 * count * 0.5 * (1 + u(rng)), u(rng), u(rng)};
      double best = HUGE_VAL;
      std::int64_t lowest = -1;
      for (int t = 0; t < count; ++t)
      {
        double w[3], c[3];
        const double d2 = dp::closestPointOnTriangle(p, &positions[3 * triangles[3 * t]],
                                                     &positions[3 * triangles[3 * t + 1]],
                                                     &positions[3 * triangles[3 * t + 2]], w, c);
        if (d2 < best)
        {
          best = d2;
          lowest = t;
        }
      }
      const dp::SurfaceLocator::Hit hit = locator.closest(p);
      ASSERT_EQ(hit.triangle, lowest) << count << " triangles";
      EXPECT_EQ(hit.squaredDistance, best);
      for (std::int64_t hint = 0; hint < count; ++hint)
        ASSERT_EQ(locator.closest(p, HUGE_VAL, hint).triangle, lowest)
            << count << " triangles, hint " << hint;
      EXPECT_EQ(locator.closest(p, 0.99 * std::sqrt(best), count / 2).triangle, -1);
    }
  }
}

TEST(SurfaceLocator, ATieGoesToTheLowestTriangleWhateverTheHint)
{
  // A flat grid of 12 x 12 squares, two triangles each: a point above an inner vertex is
  // equally near its six triangles (their closest point is the vertex itself).
  const int n = 12;
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      positions.insert(positions.end(), {double(i), double(j), 0.0});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
    {
      const std::int64_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      triangles.insert(triangles.end(), {a, b, d, a, d, c});
    }
  const dp::TriangleMesh mesh(triangles, positions.size() / 3);
  const dp::SurfaceLocator locator(mesh, positions.data());
  for (const auto& [i, j] : {std::pair{3, 4}, std::pair{7, 7}, std::pair{10, 2}})
  {
    const std::int64_t vertex = j * (n + 1) + i;
    std::int64_t lowest = -1;
    for (std::size_t t = 0; t < mesh.numberOfTriangles() && lowest < 0; ++t)
      for (int c = 0; c < 3; ++c)
        if (triangles[3 * t + c] == vertex)
          lowest = static_cast<std::int64_t>(t);
    const double p[3] = {double(i), double(j), 0.5};
    EXPECT_EQ(locator.closest(p).triangle, lowest);
    for (std::int64_t hint = 0; hint < static_cast<std::int64_t>(mesh.numberOfTriangles()); ++hint)
      ASSERT_EQ(locator.closest(p, HUGE_VAL, hint).triangle, lowest) << "hint " << hint;
  }
}

TEST(SurfaceLocator, FollowingASmallMoveReachesTheClosestPoint)
{
  // Points just outside a tube (a convex surface there: its only local minimum of the distance
  // is the closest point), each followed from the closest triangle of a point up to 0.1 away
  // (a step's move, a few triangles): the walk ends where brute force does.
  const Shape s = tube(8, 10);
  const dp::TriangleMesh mesh(s.triangles, s.positions.size() / 3);
  const dp::SurfaceLocator locator(mesh, s.positions.data());
  std::vector<double> normals(s.positions.size());
  mesh.vertexNormals(s.positions.data(), normals.data());
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int moved = 0;
  for (int i = 0; i < 300; ++i)
  {
    // A point of a random triangle, 0.02 off the surface, away from the tube's axis.
    const std::size_t t = static_cast<std::size_t>(u(rng) * mesh.numberOfTriangles());
    double a = u(rng), b = u(rng);
    if (a + b > 1)
    {
      a = 1 - a;
      b = 1 - b;
    }
    const double w[3] = {1 - a - b, a, b};
    double p[3] = {0, 0, 0}, n[3] = {0, 0, 0};
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k)
      {
        p[k] += w[c] * s.positions[3 * s.triangles[3 * t + c] + k];
        n[k] += w[c] * normals[3 * s.triangles[3 * t + c] + k];
      }
    const double outward = n[0] * p[0] + n[1] * p[1] >= 0 ? 1.0 : -1.0;
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; ++k)
      p[k] += 0.02 * outward * n[k] / length;
    double q[3];
    for (int k = 0; k < 3; ++k)
      q[k] = p[k] + 0.1 * (2 * u(rng) - 1) / std::sqrt(3.0);
    const std::int64_t from = locator.closest(q).triangle;
    const dp::SurfaceLocator::Hit exact = locator.closest(p);
    const dp::SurfaceLocator::Hit hit = locator.follow(p, from);
    ASSERT_GE(hit.triangle, 0);
    EXPECT_NEAR(hit.squaredDistance, exact.squaredDistance, 1e-12) << "point " << i;
    moved += from != exact.triangle;
    // Its weights give its point; a bound below its distance finds none.
    for (int k = 0; k < 3; ++k)
    {
      double x = 0;
      for (int c = 0; c < 3; ++c)
        x += hit.barycentric[c] * s.positions[3 * s.triangles[3 * hit.triangle + c] + k];
      EXPECT_NEAR(x, hit.point[k], 1e-12);
    }
    EXPECT_EQ(locator.follow(p, from, 0.99 * std::sqrt(exact.squaredDistance)).triangle, -1);
  }
  EXPECT_GT(moved, 100) << "most walks start away from the answer";
}

TEST(SurfaceLocator, FollowingStaysOnItsPartOfTheSurface)
{
  // Two parallel sheets, 0.3 apart; a point 0.1 below the upper one. Followed from the lower
  // sheet, the walk finds the lower sheet's closest point (0.2 away): it is local, unlike the
  // search.
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;
  const int n = 6;
  for (int sheet = 0; sheet < 2; ++sheet)
  {
    const auto base = static_cast<std::int64_t>(positions.size() / 3);
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
        positions.insert(positions.end(), {0.1 * i, 0.1 * j, 0.3 * sheet});
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
      {
        const std::int64_t a = base + j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
        triangles.insert(triangles.end(), {a, b, d, a, d, c});
      }
  }
  const dp::TriangleMesh mesh(triangles, positions.size() / 3);
  const dp::SurfaceLocator locator(mesh, positions.data());
  const double p[3] = {0.33, 0.27, 0.2};
  const dp::SurfaceLocator::Hit search = locator.closest(p);
  EXPECT_NEAR(search.squaredDistance, 0.01, 1e-12);
  EXPECT_GE(search.triangle, 2 * n * n) << "the upper sheet";
  const dp::SurfaceLocator::Hit walk = locator.follow(p, 0); // a corner triangle of the lower one
  EXPECT_NEAR(walk.squaredDistance, 0.04, 1e-12);
  EXPECT_LT(walk.triangle, 2 * n * n) << "the lower sheet";
  EXPECT_NEAR(walk.point[0], 0.33, 1e-12);
  EXPECT_NEAR(walk.point[1], 0.27, 1e-12);
  EXPECT_EQ(locator.follow(p, 0, 0.15).triangle, -1);
}

TEST(FrameData, SpreadsTheSubsampleEvenlyAndFlipsNormals)
{
  Frame f(tube().positions);
  const auto& spread = f.data->spread();
  EXPECT_GE(spread.size(), 450u); // about the 600 asked for
  EXPECT_LE(spread.size(), 900u);
  // Even: the kept points' nearest-neighbour distances are near the spacing an even spread
  // would have (random samples' would be far more scattered, down to almost 0).
  const double spacing = std::sqrt(f.mesh.totalArea(f.shape.positions.data()) / spread.size());
  std::vector<double> nearest(spread.size(), HUGE_VAL);
  for (std::size_t i = 0; i < spread.size(); ++i)
    for (std::size_t j = 0; j < spread.size(); ++j)
    {
      const double* a = f.data->point(spread[i]);
      const double* b = f.data->point(spread[j]);
      if (i != j)
        nearest[i] = std::min(nearest[i], std::sqrt((a[0] - b[0]) * (a[0] - b[0]) +
                                                    (a[1] - b[1]) * (a[1] - b[1]) +
                                                    (a[2] - b[2]) * (a[2] - b[2])));
    }
  std::sort(nearest.begin(), nearest.end());
  EXPECT_GT(nearest[nearest.size() / 2], 0.6 * spacing);
  EXPECT_GT(nearest[nearest.size() / 20], 0.25 * spacing);
  const float before = f.data->normal(5)[1];
  f.data->flipNormals();
  EXPECT_EQ(f.data->normal(5)[1], -before);
}

// Every term, at a shape off the data: gradient against finite differences, and the Gauss-Newton
// model's value and gradient equal to the term's own.

TEST(FrameData, KeepsEveryPointWithItsNormalInCurveOrder)
{
  const Shape shape = tube();
  dp::SamplerOptions o;
  o.pointsPerFrame = 3000;
  const dp::PointCloud c = dp::sampleSurface(shape.positions, shape.triangles, o, 0);
  dp::FrameDataOptions fo;
  fo.voxelSize = dp::boundingBoxDiagonal(shape.positions) / 60;
  const dp::FrameData data(c.points.data(), c.numberOfPoints(), c.normals.data(), fo);
  ASSERT_EQ(data.size(), c.numberOfPoints());
  // The same points, each with its own normal: matched by sorting both sides.
  auto rows = [](const double* p, const float* n, std::size_t count)
  {
    std::vector<std::array<double, 6>> r(count);
    for (std::size_t i = 0; i < count; ++i)
      r[i] = {p[3 * i], p[3 * i + 1], p[3 * i + 2], n[3 * i], n[3 * i + 1], n[3 * i + 2]};
    std::sort(r.begin(), r.end());
    return r;
  };
  EXPECT_EQ(rows(data.points(), data.normals(), data.size()),
            rows(c.points.data(), c.normals.data(), c.numberOfPoints()));
  // Near in memory, near in space: consecutive points are far closer than the sampler's
  // random order puts them.
  auto path = [](const double* p, std::size_t count)
  {
    double length = 0;
    for (std::size_t i = 1; i < count; ++i)
      length += std::sqrt((p[3 * i] - p[3 * i - 3]) * (p[3 * i] - p[3 * i - 3]) +
                          (p[3 * i + 1] - p[3 * i - 2]) * (p[3 * i + 1] - p[3 * i - 2]) +
                          (p[3 * i + 2] - p[3 * i - 1]) * (p[3 * i + 2] - p[3 * i - 1]));
    return length;
  };
  EXPECT_LT(path(data.points(), data.size()), 0.1 * path(c.points.data(), c.numberOfPoints()));
}
class Terms : public ::testing::TestWithParam<int>
{
};

TEST_P(Terms, GradientAndModelMatchFiniteDifferences)
{
  Frame f(tube().positions);
  const std::vector<double> target = jiggle(f.shape.positions, 0.01, 4);
  const dp::ClothEnergy cloth(f.mesh, f.shape.positions.data(), dp::ClothParameters{1, 0.1, 0.5});
  std::unique_ptr<dp::EnergyTerm> term;
  dp::DistanceTermOptions d;
  d.normalTestDegrees = 180;
  dp::CoverageOptions c;
  c.robustScale = 3 * f.voxel;
  switch (GetParam())
  {
  case 0:
    term = std::make_unique<dp::InternalEnergyTerm>(cloth);
    break;
  case 1: // the distance to the data's tangent planes, squared
    term = std::make_unique<dp::DistanceTerm>(*f.data, f.mesh, f.mass, f.L, d);
    break;
  case 2: // the paper's distance to the points, linear
    d.measure = dp::DistanceMeasure::Points;
    d.squared = false;
    term = std::make_unique<dp::DistanceTerm>(*f.data, f.mesh, f.mass, f.L, d);
    break;
  case 3: // robust weights
    d.robustScale = 2 * f.voxel;
    term = std::make_unique<dp::DistanceTerm>(*f.data, f.mesh, f.mass, f.L, d);
    break;
  case 4:
    term = std::make_unique<dp::CoverageTerm>(f.data->spreadSamples(), f.mesh, f.L, c);
    break;
  default:
    term = std::make_unique<dp::TemporalTerm>(target, f.mass, 3.0, f.L, f.voxel);
  }
  const std::vector<double> x = jiggle(f.shape.positions, 0.01, 9);
  term->decide(x.data());
  term->linearise(x.data());
  // Small steps stay inside the distance field's voxel cells, where D is smooth.
  expectGradientMatches([&](const double* p, double* g) { return term->evaluate(p, g); }, x,
                        GetParam() == 0 ? 1e-5 : 2e-4, GetParam() == 0 ? 1e-6 : 1e-8);
  std::vector<std::array<std::int64_t, 2>> pairs;
  term->couplings(pairs);
  dp::detail::BlockSparseMatrix H(f.mesh.numberOfVertices(), pairs);
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
  // The matrix stores its lower triangle (diagonal blocks whole): its scalar lower triangle,
  // mirrored, is the full matrix.
  const Eigen::MatrixXd lower = Eigen::MatrixXd(H.matrix()).triangularView<Eigen::Lower>();
  Eigen::MatrixXd dense = lower + lower.transpose();
  dense.diagonal() /= 2;
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

TEST(FrameQuality, ATearIsTheLargestStiffEdgeGrowthInMeanEdgeLengths)
{
  // A unit square of two triangles: four sides of 1 and a diagonal of sqrt(2).
  const dp::TriangleMesh mesh({0, 1, 2, 1, 3, 2}, 4);
  const std::vector<double> rest{0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  const double mean = (4 + std::sqrt(2.0)) / 5;
  EXPECT_DOUBLE_EQ(dp::largestEdgeGrowth(mesh, rest, rest, {}), 0.0);
  // Shrinking tears nothing.
  std::vector<double> shrunk = rest;
  for (double& c : shrunk)
    c *= 0.5;
  EXPECT_DOUBLE_EQ(dp::largestEdgeGrowth(mesh, rest, shrunk, {}), 0.0);
  // Vertex 3 pulled 3 away: edge 1-3 grows by 3, edge 3-2 by sqrt(10) - 1.
  std::vector<double> pulled = rest;
  pulled[3 * 3 + 1] = 4;
  EXPECT_NEAR(dp::largestEdgeGrowth(mesh, rest, pulled, {}), 3 / mean, 1e-12);
  // An edge made soft to stretch counts by its stiffness: edge 1-3 at 0.1 leaves edge 3-2.
  std::vector<double> scales;
  for (const auto& e : mesh.edges())
    scales.push_back(std::min(e[0], e[1]) == 1 && std::max(e[0], e[1]) == 3 ? 0.1 : 1.0);
  EXPECT_NEAR(dp::largestEdgeGrowth(mesh, rest, pulled, scales), (std::sqrt(10.0) - 1) / mean,
              1e-12);
}

TEST(FrameQuality, MeshTakenOffItsDataDepartsMeshOverAHoleDoesNot)
{
  const Shape shape = tube(20, 12);
  const std::size_t nv = shape.positions.size() / 3;
  const dp::TriangleMesh mesh(shape.triangles, nv);
  const std::vector<double> mass(nv, 1.0 / static_cast<double>(nv));
  dp::SamplerOptions o;
  o.pointsPerFrame = 6000;
  const dp::PointCloud c = dp::sampleSurface(shape.positions, shape.triangles, o, 0);
  dp::FrameDataOptions fo;
  fo.voxelSize = dp::boundingBoxDiagonal(shape.positions) / 60;
  const double reach = 3 * fo.voxelSize;
  // The top of the tube (its highest tenth) is where a hole is, or what is pulled off.
  double top = -1e300, bottom = 1e300;
  for (std::size_t v = 0; v < nv; ++v)
  {
    top = std::max(top, shape.positions[3 * v + 2]);
    bottom = std::min(bottom, shape.positions[3 * v + 2]);
  }
  const double cut = top - 0.1 * (top - bottom);
  double topMass = 0;
  std::vector<double> pulled = shape.positions;
  for (std::size_t v = 0; v < nv; ++v)
    if (shape.positions[3 * v + 2] > cut)
    {
      pulled[3 * v] += 10 * reach;
      topMass += mass[v];
    }
  ASSERT_GT(topMass, 0.05);
  const dp::FrameData all(c.points.data(), c.numberOfPoints(), c.normals.data(), fo);
  dp::FrameQuality q =
      dp::assessFrame(all, mesh, pulled.data(), mass, reach, shape.positions.data());
  EXPECT_NEAR(q.departed, topMass, 1e-12);
  EXPECT_NEAR(q.unsupported, topMass, 1e-12);
  // Without a start nothing departs.
  EXPECT_EQ(dp::assessFrame(all, mesh, pulled.data(), mass, reach).departed, 0.0);
  // A hole in the data over the top: the mesh there lacks data where it started too.
  std::vector<double> kept;
  std::vector<float> keptNormals;
  for (std::size_t i = 0; i < c.numberOfPoints(); ++i)
    if (c.points[3 * i + 2] < cut - 2 * reach)
    {
      kept.insert(kept.end(), &c.points[3 * i], &c.points[3 * i] + 3);
      keptNormals.insert(keptNormals.end(), &c.normals[3 * i], &c.normals[3 * i] + 3);
    }
  const dp::FrameData holed(kept.data(), kept.size() / 3, keptNormals.data(), fo);
  q = dp::assessFrame(holed, mesh, shape.positions.data(), mass, reach, shape.positions.data());
  EXPECT_GT(q.unsupported, 0.5 * topMass);
  EXPECT_EQ(q.departed, 0.0);
}

TEST(DeformationGraph, MovesRigidlyFitsRigidMotionsAndContinuesThem)
{
  const Shape s = tube(16, 12);
  const dp::TriangleMesh mesh(s.triangles, s.positions.size() / 3);
  const dp::DeformationGraph graph(mesh, s.positions.data(), 30, 4);
  EXPECT_EQ(graph.numberOfNodes(), 30u);
  std::vector<double> x(s.positions.size());
  graph.deform(graph.identity(), x.data());
  for (std::size_t i = 0; i < x.size(); ++i)
    ASSERT_NEAR(x[i], s.positions[i], 1e-12);
  for (std::size_t v = 0; v < mesh.numberOfVertices(); ++v)
  {
    double total = 0;
    for (auto i = graph.influencesBegin(v); i != graph.influencesEnd(v); ++i)
      total += i->weight;
    ASSERT_NEAR(total, 1.0, 1e-12) << v;
  }
  // One rigid motion for all nodes moves the mesh rigidly; fit() recovers it from the shape.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).matrix();
  const Eigen::Vector3d t(0.3, -0.1, 0.2);
  dp::DeformationGraph::State rigid = graph.identity();
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
  {
    const Eigen::Vector3d g(graph.nodePosition(j));
    rigid.rotation[j] = R;
    rigid.translation[j] = R * g + t - g;
  }
  graph.deform(rigid, x.data());
  for (std::size_t v = 0; v < mesh.numberOfVertices(); ++v)
    ASSERT_LT((Eigen::Vector3d(&x[3 * v]) - (R * Eigen::Vector3d(&s.positions[3 * v]) + t)).norm(),
              1e-12);
  const dp::DeformationGraph::State fitted = graph.fit(x.data());
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
  {
    EXPECT_LT((fitted.rotation[j] - R).norm(), 1e-9) << j;
    EXPECT_LT((fitted.translation[j] - rigid.translation[j]).norm(), 1e-9) << j;
  }
  // A constant turn, continued: identity -> R -> R^2.
  dp::DeformationGraph::State half = graph.identity();
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
    half.rotation[j] = R;
  const dp::DeformationGraph::State next = dp::extrapolate(graph.identity(), half, graph, 1.0);
  EXPECT_LT((next.rotation[0] - R * R).norm(), 1e-12);
  // A rigid motion continued is the same motion once more, x -> R (R x + t) + t, for a turn about
  // a point far from the nodes too (a leg about its hip): not only the rotation continues.
  const dp::DeformationGraph::State twice = dp::extrapolate(graph.identity(), rigid, graph, 1.0);
  graph.deform(twice, x.data());
  for (std::size_t v = 0; v < mesh.numberOfVertices(); ++v)
  {
    const Eigen::Vector3d p(&s.positions[3 * v]);
    ASSERT_LT((Eigen::Vector3d(&x[3 * v]) - (R * (R * p + t) + t)).norm(), 1e-12) << v;
  }
}

TEST(DeformationGraph, BlendsAlongTheSurfaceNotAcrossGaps)
{
  // A U of two long strips joined at the bottom, their tops 1/20 of their length apart: close in
  // space, far along the surface. No vertex of one arm's top blends a node of the other arm.
  const int rows = 40, columns = 4;
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;
  // The strip runs up one arm (x = 0), across the bottom and up the other (x = 0.05).
  const int length = 2 * rows + 2;
  for (int i = 0; i < length; ++i)
    for (int j = 0; j < columns; ++j)
    {
      double x, y;
      if (i < rows)
      {
        x = 0;
        y = 1.0 - static_cast<double>(i) / rows;
      }
      else if (i < rows + 2)
      {
        x = 0.025 * (i - rows + 0.5);
        y = -0.01;
      }
      else
      {
        x = 0.05;
        y = static_cast<double>(i - rows - 2) / rows;
      }
      positions.insert(positions.end(), {x, y, 0.02 * j});
    }
  for (int i = 0; i + 1 < length; ++i)
    for (int j = 0; j + 1 < columns; ++j)
    {
      const std::int64_t a = i * columns + j, b = a + 1, c = a + columns, d = c + 1;
      triangles.insert(triangles.end(), {a, c, b, b, c, d});
    }
  const dp::TriangleMesh mesh(triangles, positions.size() / 3);
  const dp::DeformationGraph graph(mesh, positions.data(), 40, 4);
  for (std::size_t v = 0; v < mesh.numberOfVertices(); ++v)
  {
    if (positions[3 * v + 1] < 0.5)
      continue; // the tops only
    const bool left = positions[3 * v] < 0.025;
    for (auto i = graph.influencesBegin(v); i != graph.influencesEnd(v); ++i)
    {
      const double* g = graph.nodePosition(static_cast<std::size_t>(i->node));
      EXPECT_EQ(g[0] < 0.025, left) << "vertex " << v << " blends a node of the other arm";
    }
  }
}

// A 16 x 12 tube and a 20-node deformation graph on it.
struct TubeGraph
{
  Shape shape = tube(16, 12);
  dp::TriangleMesh mesh{shape.triangles, shape.positions.size() / 3};
  dp::DeformationGraph graph{mesh, shape.positions.data(), 20, 4};
};

// The coarse level's test problem: a 16 x 12 tube, its frame's points and masses, and a 20-node
// deformation graph with the registration over it.
struct GraphProblem
{
  Shape shape = tube(16, 12);
  Frame f{shape.positions, false, shape};
  dp::DeformationGraph graph{f.mesh, f.shape.positions.data(), 20, 4};
  dp::GraphRegistration registration{graph, f.L, f.voxel};
};

// The coarse level's data terms on a problem's frame, as registerFrame() uses them: the
// distance term with `options` and the points -> mesh term with its diagonal model.
struct CoarseTerms
{
  dp::DistanceTerm distance;
  dp::CoverageTerm coverage;
  CoarseTerms(const Frame& f, const dp::DistanceTermOptions& options)
      : distance(*f.data, f.mesh, f.mass, f.L, options),
        coverage(f.data->spreadSamples(), f.mesh, f.L, robustCoverage(f))
  {
    coverage.setDiagonalModel(true);
  }
  std::vector<dp::EnergyTerm*> all() { return {&distance, &coverage}; }
  static dp::CoverageOptions robustCoverage(const Frame& f)
  {
    dp::CoverageOptions c;
    c.robustScale = 3 * f.voxel;
    return c;
  }
};

// A state off the data: every node turned by up to `angle` and moved up to 0.01, differently.
dp::DeformationGraph::State turnedState(const dp::DeformationGraph& graph, double angle,
                                        std::mt19937_64& rng)
{
  std::uniform_real_distribution<double> u(-1, 1);
  dp::DeformationGraph::State state = graph.identity();
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
  {
    state.rotation[j] =
        Eigen::AngleAxisd(angle * u(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized())
            .matrix();
    state.translation[j] = 0.01 * Eigen::Vector3d(u(rng), u(rng), u(rng));
  }
  return state;
}

// `state` moved by h along a node-space direction (angle-axis increments, translations).
dp::DeformationGraph::State movedAlong(const dp::DeformationGraph::State& state,
                                       const Eigen::VectorXd& direction, double h)
{
  dp::DeformationGraph::State s = state;
  for (std::size_t j = 0; j < state.rotation.size(); ++j)
  {
    const Eigen::Vector3d w = h * direction.segment<3>(static_cast<Eigen::Index>(6 * j));
    s.rotation[j] =
        Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix() * state.rotation[j];
    s.translation[j] += h * direction.segment<3>(static_cast<Eigen::Index>(6 * j + 3));
  }
  return s;
}

TEST(GraphRegistration, NodeGradientMatchesFiniteDifferences)
{
  // E(theta) = data terms at x(theta) + E_reg(theta): its node-space gradient (the vertex model
  // carried through the blending) against central differences in each node's rotation
  // (angle-axis increment) and translation.
  GraphProblem problem;
  const Frame& f = problem.f;
  const dp::DeformationGraph& graph = problem.graph;
  dp::GraphRegistration& registration = problem.registration;
  // The distance to the points, squared: its model's gradient is exact (the distance to planes
  // holds the interpolation weights), so the test sees the projection alone.
  dp::DistanceTermOptions d;
  d.normalTestDegrees = 180;
  d.measure = dp::DistanceMeasure::Points;
  CoarseTerms data(f, d);
  const std::vector<dp::EnergyTerm*> terms = data.all();
  std::mt19937_64 rng(5);
  const dp::DeformationGraph::State state = turnedState(graph, 0.05, rng);
  std::vector<double> x(f.shape.positions.size());
  graph.deform(state, x.data());
  data.coverage.linearise(x.data());
  const double rigidity = 3.0;
  Eigen::VectorXd gradient;
  registration.model(state, terms, rigidity, gradient);
  auto energyAt = [&](const dp::DeformationGraph::State& s)
  {
    std::vector<double> y(x.size());
    graph.deform(s, y.data());
    return dp::evaluateAll(terms, y.data(), nullptr) + registration.regularisation(s, rigidity);
  };
  const double h = 1e-7;
  double worst = 0, scale = 0;
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
    for (int k = 0; k < 6; ++k)
    {
      dp::DeformationGraph::State plus = state, minus = state;
      Eigen::Vector3d e = Eigen::Vector3d::Zero();
      e[k % 3] = h;
      if (k < 3)
      {
        plus.rotation[j] = Eigen::AngleAxisd(h, e.normalized()).matrix() * state.rotation[j];
        minus.rotation[j] = Eigen::AngleAxisd(-h, e.normalized()).matrix() * state.rotation[j];
      }
      else
      {
        plus.translation[j] += e;
        minus.translation[j] -= e;
      }
      const double numeric = (energyAt(plus) - energyAt(minus)) / (2 * h);
      worst = std::max(worst, std::abs(numeric - gradient[static_cast<Eigen::Index>(6 * j + k)]));
      scale = std::max(scale, std::abs(numeric));
    }
  ASSERT_GT(scale, 0);
  EXPECT_LT(worst, 1e-4 * scale);
}

TEST(GraphRegistration, LimbsBendButDoNotStretch)
{
  // The regulariser alone on a graph stretched uniformly about its centre (every edge longer by
  // the same share): its gradient against central differences, and its growth with the stretch.
  const TubeGraph tubeGraph;
  const dp::DeformationGraph& graph = tubeGraph.graph;
  const double voxel = 0.01;
  dp::GraphRegistration registration(graph, 1.0, voxel);
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
    centre += Eigen::Vector3d(graph.nodePosition(j)) / static_cast<double>(graph.numberOfNodes());
  auto stretched = [&](double factor)
  {
    dp::DeformationGraph::State s = graph.identity();
    for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
      s.translation[j] = (factor - 1) * (Eigen::Vector3d(graph.nodePosition(j)) - centre);
    return s;
  };
  const double rigidity = 2.0;
  auto growth = [&]
  {
    const double e13 = registration.regularisation(stretched(1.3), rigidity);
    EXPECT_GT(e13, 0);
    return registration.regularisation(stretched(1.6), rigidity) / e13;
  };
  // Bending is least squares outside a solve (no Huber weights yet): alone it grows as
  // (0.6 / 0.3)^2 = 4; the stretch term as (0.5 / 0.2)^2 = 6.25.
  registration.setStretchWeight(0);
  EXPECT_NEAR(growth(), 4.0, 1e-9);
  registration.setStretchWeight(1);
  EXPECT_GT(growth(), 4.3);

  const dp::DeformationGraph::State state = stretched(1.3);
  dp::detail::BlockSparseMatrixOf<6> hessian(graph.numberOfNodes(), graph.edges());
  Eigen::VectorXd gradient =
      Eigen::VectorXd::Zero(static_cast<Eigen::Index>(6 * graph.numberOfNodes()));
  registration.regularisation(state, rigidity, &hessian, &gradient);
  const double h = 1e-7;
  double worst = 0, scale = 0;
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
    for (int k = 3; k < 6; ++k)
    {
      dp::DeformationGraph::State plus = state, minus = state;
      plus.translation[j][k - 3] += h;
      minus.translation[j][k - 3] -= h;
      const double numeric = (registration.regularisation(plus, rigidity) -
                              registration.regularisation(minus, rigidity)) /
                             (2 * h);
      worst = std::max(worst, std::abs(numeric - gradient[static_cast<Eigen::Index>(6 * j + k)]));
      scale = std::max(scale, std::abs(numeric));
    }
  ASSERT_GT(scale, 0);
  EXPECT_LT(worst, 1e-4 * scale);
}

TEST(GraphRegistration, NodeModelIsTheVertexModelCarriedThroughTheBlending)
{
  // The data terms' part of the node model is J^T H J, H their vertex model and J = dx/dtheta
  // the blending's Jacobian: for any direction d in node space, d^T (model - E_reg's part) d
  // equals (J d)^T H (J d), with J d from central differences of the deformed positions.
  GraphProblem problem;
  const Frame& f = problem.f;
  const dp::DeformationGraph& graph = problem.graph;
  dp::GraphRegistration& registration = problem.registration;
  CoarseTerms data(f, dp::DistanceTermOptions{});
  const std::vector<dp::EnergyTerm*> terms = data.all();
  const std::size_t nodes = graph.numberOfNodes();
  std::mt19937_64 rng(11);
  const dp::DeformationGraph::State state = turnedState(graph, 0.3, rng);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> x(f.shape.positions.size());
  graph.deform(state, x.data());
  data.distance.decide(x.data());
  data.coverage.linearise(x.data());
  const double rigidity = 3.0;
  Eigen::VectorXd gradient;
  registration.model(state, terms, rigidity, gradient);
  const Eigen::SparseMatrix<double> nodeModel = registration.nodeModel().matrix();
  dp::detail::BlockSparseMatrixOf<6> regulariser(nodes, graph.edges());
  Eigen::VectorXd unused = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(6 * nodes));
  registration.regularisation(state, rigidity, &regulariser, &unused);
  const Eigen::SparseMatrix<double> dataPart =
      nodeModel - Eigen::SparseMatrix<double>(regulariser.matrix());
  dp::detail::BlockSparseMatrix vertexModel(x.size() / 3, {});
  std::vector<double> vertexGradient(x.size(), 0.0);
  for (const dp::EnergyTerm* t : terms)
    t->addModel(x.data(), vertexModel, vertexGradient.data());
  const Eigen::SparseMatrix<double> H = vertexModel.matrix();
  for (int trial = 0; trial < 3; ++trial)
  {
    Eigen::VectorXd direction(static_cast<Eigen::Index>(6 * nodes));
    for (Eigen::Index i = 0; i < direction.size(); ++i)
      direction[i] = u(rng);
    auto deformedAlong = [&](double h)
    {
      std::vector<double> y(x.size());
      graph.deform(movedAlong(state, direction, h), y.data());
      return Eigen::Map<const Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(y.size()))
          .eval();
    };
    const double h = 1e-6;
    const Eigen::VectorXd moved = (deformedAlong(h) - deformedAlong(-h)) / (2 * h);
    const double expected = moved.dot(H.selfadjointView<Eigen::Lower>() * moved);
    const double modelled = direction.dot(dataPart.selfadjointView<Eigen::Lower>() * direction);
    ASSERT_GT(expected, 0);
    EXPECT_NEAR(modelled, expected, 1e-6 * expected) << "direction " << trial;
  }
}

TEST(GraphRegistration, RegulariserModelIsItsHessianWhereNoEdgeBends)
{
  // Under a rigid motion of the whole graph no edge bends or stretches (E_reg = 0, residuals 0),
  // so the Gauss-Newton model J^T J is E_reg's exact Hessian there: the model times a direction
  // against central differences of the gradient along it (rotation increments and translations).
  const TubeGraph tubeGraph;
  const dp::DeformationGraph& graph = tubeGraph.graph;
  dp::GraphRegistration registration(graph, 1.0, 0.01);
  const std::size_t nodes = graph.numberOfNodes();
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  dp::DeformationGraph::State rigid = graph.identity();
  for (std::size_t j = 0; j < nodes; ++j)
  {
    const Eigen::Vector3d g(graph.nodePosition(j));
    rigid.rotation[j] = turn;
    rigid.translation[j] = turn * g + Eigen::Vector3d(0.1, -0.2, 0.3) - g;
  }
  const double rigidity = 2.0;
  ASSERT_LT(registration.regularisation(rigid, rigidity), 1e-20);
  auto modelAt = [&](const dp::DeformationGraph::State& s, Eigen::VectorXd& gradient)
  {
    dp::detail::BlockSparseMatrixOf<6> hessian(nodes, graph.edges());
    gradient = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(6 * nodes));
    registration.regularisation(s, rigidity, &hessian, &gradient);
    return Eigen::SparseMatrix<double>(hessian.matrix());
  };
  Eigen::VectorXd gradient;
  const Eigen::SparseMatrix<double> lower = modelAt(rigid, gradient);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::VectorXd direction(static_cast<Eigen::Index>(6 * nodes));
  for (Eigen::Index i = 0; i < direction.size(); ++i)
    direction[i] = u(rng);
  const Eigen::VectorXd modelled = lower.selfadjointView<Eigen::Lower>() * direction;
  const double h = 1e-6;
  Eigen::VectorXd plus, minus;
  modelAt(movedAlong(rigid, direction, h), plus);
  modelAt(movedAlong(rigid, direction, -h), minus);
  const Eigen::VectorXd numeric = (plus - minus) / (2 * h);
  ASSERT_GT(numeric.norm(), 0);
  EXPECT_LT((numeric - modelled).norm(), 1e-5 * numeric.norm());
}

TEST(GraphRegistration, AcceleratedStepsFitTheDataAsWellInFewerSteps)
{
  // The coarse schedule from nodes turned (up to 0.3 rad each, about different axes) and moved off
  // the data, with plain and with Anderson-accelerated steps: both end on the data (RMS distance
  // of the vertices from it well under a voxel), the accelerated schedule in fewer steps (4
  // against 9 when written).
  auto run = [](int depth, double& rmsDistance)
  {
    const Frame f(tube().positions);
    const dp::DeformationGraph graph(f.mesh, f.shape.positions.data(), 20, 4);
    dp::GraphRegistration registration(graph, f.L, f.voxel);
    registration.setAcceleration(depth);
    CoarseTerms data(f, dp::DistanceTermOptions{});
    std::mt19937_64 rng(11);
    dp::DeformationGraph::State state = turnedState(graph, 0.3, rng);
    const int steps =
        registration.registerFrame(state, data.distance, &data.coverage, 1.0, 0.5 * f.voxel, 10);
    std::vector<double> x(f.shape.positions.size());
    graph.deform(state, x.data());
    double sum = 0;
    const std::size_t nv = x.size() / 3;
    for (std::size_t v = 0; v < nv; ++v)
      sum += std::pow(data.distance.sample(&x[3 * v], v).distance, 2);
    rmsDistance = std::sqrt(sum / static_cast<double>(nv)) / f.voxel;
    return steps;
  };
  double plainDistance = 0, acceleratedDistance = 0;
  const int plainSteps = run(0, plainDistance);
  const int acceleratedSteps = run(3, acceleratedDistance);
  EXPECT_LT(plainDistance, 0.3);
  EXPECT_LT(acceleratedDistance, 1.05 * plainDistance);
  EXPECT_LT(acceleratedSteps, plainSteps);
}

// Adds nothing to the energy; records how far each linearised mesh lies from the trial
// evaluated just before it (the plain step just kept, when an accelerated state follows it).
struct StepRecorder : dp::EnergyTerm
{
  std::vector<double> lastTrial;
  double largestGap = 0;
  int moved = 0; // linearisations away from the last trial
  const char* name() const override { return "recorder"; }
  double evaluate(const double* x, double*) const override
  {
    const_cast<StepRecorder*>(this)->lastTrial.assign(x, x + size);
    return 0;
  }
  double addModel(const double*, dp::detail::BlockSparseMatrix&, double*) const override
  {
    return 0;
  }
  void linearise(const double* x) override
  {
    if (lastTrial.empty())
      return;
    double gap = 0;
    for (std::size_t i = 0; i < size; ++i)
      gap = std::max(gap, std::abs(x[i] - lastTrial[i]));
    largestGap = std::max(largestGap, gap);
    moved += gap > 0;
  }
  std::size_t size = 0;
};

// Pulls each vertex toward a point that every linearisation places a tenth of the way from it
// to its goal: the steps converge linearly (0.9x each), as the coarse level's sliding does, so
// Anderson acceleration extrapolates them far.
struct SlowPull : dp::EnergyTerm
{
  std::vector<double> goal, target;
  const char* name() const override { return "slow pull"; }
  void linearise(const double* x) override
  {
    target.resize(goal.size());
    for (std::size_t i = 0; i < goal.size(); ++i)
      target[i] = x[i] + 0.1 * (goal[i] - x[i]);
  }
  double evaluate(const double* x, double* gradient) const override
  {
    double e = 0;
    for (std::size_t i = 0; i < goal.size(); ++i)
    {
      e += 0.5 * (x[i] - target[i]) * (x[i] - target[i]);
      if (gradient)
        gradient[i] += x[i] - target[i];
    }
    return e;
  }
  double addModel(const double* x, dp::detail::BlockSparseMatrix& hessian,
                  double* gradient) const override
  {
    const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (std::size_t v = 0; v < goal.size() / 3; ++v)
    {
      const auto vertex = static_cast<std::int64_t>(v);
      hessian.addBlock(hessian.slotOf(vertex, vertex), identity);
    }
    return evaluate(x, gradient);
  }
};

TEST(GraphRegistration, AcceleratedStatesStayWithinAVoxelOfThePlainStep)
{
  // A rigid shift of 8 voxels approached by steps 0.9x the one before: each accelerated state
  // (linearised right after the plain step it replaces was evaluated) moves no vertex more than
  // a voxel from that step (6.5 voxels without that limit, when written), and the solve still
  // ends at the goal (0.14 voxel off after 5 accelerated states).
  const TubeGraph tubeGraph;
  const dp::DeformationGraph& graph = tubeGraph.graph;
  const double voxel = 0.01;
  dp::GraphRegistration registration(graph, 1.0, voxel);
  registration.setAcceleration(3);
  SlowPull pull;
  pull.goal = tubeGraph.shape.positions;
  for (std::size_t i = 0; i < pull.goal.size(); i += 3)
    pull.goal[i] += 8 * voxel;
  StepRecorder recorder;
  recorder.size = tubeGraph.shape.positions.size();
  dp::DeformationGraph::State state = graph.identity();
  registration.solve(state, {&pull, &recorder}, 1.0, 40);
  std::vector<double> x(tubeGraph.shape.positions.size());
  graph.deform(state, x.data());
  double offGoal = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
    offGoal = std::max(offGoal, std::abs(x[i] - pull.goal[i]));
  EXPECT_GT(recorder.moved, 0) << "no accelerated state";
  EXPECT_LE(recorder.largestGap, voxel * (1 + 1e-9));
  EXPECT_LT(offGoal, 0.5 * voxel);
}

TEST(AndersonAcceleration, SolvesALinearContractionInAFewSteps)
{
  // u <- A u + b with A's eigenvalues 0.95 ... 0.3 (slow, as the coarse level's sliding is):
  // after 8 plain steps most of the error is left; accelerated steps combining 4 earlier ones
  // (the dimension: GMRES on u = A u + b) leave none.
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Matrix4d random;
  for (int i = 0; i < 16; ++i)
    random(i / 4, i % 4) = u(rng);
  const Eigen::Matrix4d q = Eigen::HouseholderQR<Eigen::Matrix4d>(random).householderQ();
  const Eigen::Matrix4d a = q * Eigen::Vector4d(0.95, 0.9, 0.6, 0.3).asDiagonal() * q.transpose();
  const Eigen::Vector4d b(u(rng), u(rng), u(rng), u(rng));
  const Eigen::Vector4d fixed = (Eigen::Matrix4d::Identity() - a).inverse() * b;
  const double start = fixed.norm();
  Eigen::VectorXd plain = Eigen::Vector4d::Zero(), accelerated = plain;
  dp::AndersonAcceleration anderson(4);
  int combined = 0;
  for (int step = 0; step < 8; ++step)
  {
    plain = a * plain + b;
    const Eigen::VectorXd image = a * accelerated + b;
    Eigen::VectorXd next;
    const bool combines = anderson.next(accelerated, image, next);
    combined += combines;
    accelerated = combines ? next : image;
  }
  EXPECT_EQ(combined, 7); // every step but the first
  EXPECT_GT((plain - fixed).norm(), 0.3 * start);
  EXPECT_LT((accelerated - fixed).norm(), 1e-9 * start);
}

TEST(AndersonAcceleration, CombinesOnlyOnceItHasAnEarlierStepAndForgetsOnReset)
{
  EXPECT_THROW(dp::AndersonAcceleration(0), std::invalid_argument);
  dp::AndersonAcceleration anderson(2);
  Eigen::VectorXd next;
  const Eigen::Vector2d u(1, 2), g(0.5, 1);
  EXPECT_FALSE(anderson.next(u, g, next));
  EXPECT_EQ(next.size(), 0);
  // u -> u / 2 in 2-D from a second point: the fixed point 0 at once.
  EXPECT_TRUE(anderson.next(g, 0.5 * g, next));
  EXPECT_LT(next.norm(), 1e-12);
  anderson.reset();
  EXPECT_FALSE(anderson.next(u, g, next));
}

// A closed lat-long sphere of `radius` around `centre` (rings x segments quads, fans at the poles),
// appended to `shape`; `inward` turns its faces inward.
void addSphere(Shape& shape, const double centre[3], double radius, bool inward = false)
{
  const std::int64_t rings = 12, segments = 24;
  const auto first = static_cast<std::int64_t>(shape.positions.size() / 3);
  const auto put = [&](double polar, double azimuth)
  {
    shape.positions.insert(shape.positions.end(),
                           {centre[0] + radius * std::sin(polar) * std::cos(azimuth),
                            centre[1] + radius * std::sin(polar) * std::sin(azimuth),
                            centre[2] + radius * std::cos(polar)});
  };
  put(0, 0);
  for (std::int64_t r = 1; r < rings; ++r)
    for (std::int64_t s = 0; s < segments; ++s)
      put(M_PI * static_cast<double>(r) / rings, 2 * M_PI * static_cast<double>(s) / segments);
  put(M_PI, 0);
  const std::int64_t south = first + 1 + (rings - 1) * segments;
  const auto ring = [&](std::int64_t r, std::int64_t s)
  { return first + 1 + (r - 1) * segments + s % segments; };
  const auto face = [&](std::int64_t a, std::int64_t b, std::int64_t c)
  {
    if (inward)
      std::swap(b, c);
    shape.triangles.insert(shape.triangles.end(), {a, b, c});
  };
  for (std::int64_t s = 0; s < segments; ++s)
  {
    face(first, ring(1, s), ring(1, s + 1));
    face(south, ring(rings - 1, s + 1), ring(rings - 1, s));
    for (std::int64_t r = 1; r + 1 < rings; ++r)
    {
      face(ring(r, s), ring(r + 1, s), ring(r + 1, s + 1));
      face(ring(r, s), ring(r + 1, s + 1), ring(r, s + 1));
    }
  }
}

TEST(LocalThickness, FindsEachPartsRadiusWhicheverWayItsFacesTurn)
{
  // A thin part and a thick one far apart: each vertex's inner ball is its own sphere (within
  // 10 %: area-weighted normals on a lat-long mesh lean a few degrees).
  for (const bool inward : {false, true})
  {
    Shape shape;
    const double thin[3] = {0, 0, 0}, thick[3] = {2, 0, 0};
    addSphere(shape, thin, 0.1, inward);
    const std::size_t thinVertices = shape.positions.size() / 3;
    addSphere(shape, thick, 0.4, inward);
    const dp::TriangleMesh mesh(shape.triangles, shape.positions.size() / 3);
    const std::vector<double> radius = dp::medialRadii(mesh, shape.positions.data(), 1.0);
    ASSERT_EQ(radius.size(), mesh.numberOfVertices());
    for (std::size_t v = 0; v < radius.size(); ++v)
      EXPECT_NEAR(radius[v], v < thinVertices ? 0.1 : 0.4, v < thinVertices ? 0.01 : 0.04)
          << "vertex " << v << (inward ? " (faces turned inward)" : "");
  }
}

TEST(LocalThickness, OutsideBallsMeasureTheGapInFrontOfEachVertex)
{
  // Two spheres of radius 0.3, 0.2 apart: the ball outside the first sphere at its point facing
  // the second fits the gap (radius 0.1); on its far side nothing faces it (the cap).
  Shape shape;
  const double a[3] = {0, 0, 0}, b[3] = {0.8, 0, 0};
  addSphere(shape, a, 0.3);
  const std::size_t first = shape.positions.size() / 3;
  addSphere(shape, b, 0.3);
  const dp::TriangleMesh mesh(shape.triangles, shape.positions.size() / 3);
  const std::vector<double> outer =
      dp::medialRadii(mesh, shape.positions.data(), 1.0, 0, dp::MedialSide::Outside);
  std::size_t facing = 0, away = 0;
  for (std::size_t v = 0; v < first; ++v)
  {
    if (shape.positions[3 * v] > shape.positions[3 * facing])
      facing = v;
    if (shape.positions[3 * v] < shape.positions[3 * away])
      away = v;
  }
  EXPECT_NEAR(outer[facing], 0.1, 0.01);
  EXPECT_DOUBLE_EQ(outer[away], 1.0);
  // Inside, the same vertices measure the sphere.
  const std::vector<double> inner = dp::medialRadii(mesh, shape.positions.data(), 1.0, 0);
  EXPECT_NEAR(inner[facing], 0.3, 0.03);
}

TEST(LocalThickness, TheTrackerSoftensTheStretchWhereTwoPartsFaceEachOther)
{
  // A template of two spheres 0.2 apart (a crease between parts, as where an arm touches the
  // body): the edges facing the other sphere get the crease's factor, those on the far sides
  // keep the full stiffness; with the factor 1 nothing is scaled.
  Shape shape;
  const double a[3] = {0, 0, 0}, b[3] = {0.8, 0, 0};
  addSphere(shape, a, 0.3);
  addSphere(shape, b, 0.3);
  const dp::TriangleMesh mesh(shape.triangles, shape.positions.size() / 3);
  dp::TrackerOptions options;
  options.softening.stretch = 1.0; // the creases' factor alone
  options.creases.stretch = 0.25;
  const dp::Tracker tracker(mesh, shape.positions, options);
  const std::vector<double>& scales = tracker.clothEnergy().stretchScales();
  ASSERT_EQ(scales.size(), mesh.edges().size());
  std::size_t facing = 0, soft = 0;
  for (std::size_t e = 0; e < scales.size(); ++e)
  {
    const auto [i, j] = mesh.edges()[e];
    const double x = 0.5 * (shape.positions[3 * i] + shape.positions[3 * j]);
    const bool inGap = x > 0.25 && x < 0.55; // both ends on the spheres' facing caps
    facing += inGap;
    soft += scales[e] == 0.25;
    if (inGap)
    {
      EXPECT_DOUBLE_EQ(scales[e], 0.25) << "edge " << e << " at x " << x;
    }
    if (x < 0.0 || x > 0.8)
    {
      EXPECT_DOUBLE_EQ(scales[e], 1.0) << "edge " << e << " at x " << x;
    }
  }
  EXPECT_GT(facing, 0u);
  EXPECT_LT(soft, scales.size() / 2);
  options.creases.stretch = 1.0;
  const dp::Tracker stiff(mesh, shape.positions, options);
  EXPECT_TRUE(stiff.clothEnergy().stretchScales().empty());
}

TEST(LocalThickness, OnlyWhatEnclosesABallIsSoftenedAsThick)
{
  // A ball (closed, thick everywhere) gets the thick parts' factor on every edge; a flat sheet
  // (its balls meet nothing) keeps the full stiffness: it is no trunk.
  dp::TrackerOptions options;
  options.softening.stretch = 0.3;
  options.creases.stretch = 1.0; // the thick parts' factor alone
  Shape ball;
  const double centre[3] = {0, 0, 0};
  addSphere(ball, centre, 0.3);
  const dp::TriangleMesh ballMesh(ball.triangles, ball.positions.size() / 3);
  const dp::Tracker round(ballMesh, ball.positions, options);
  ASSERT_EQ(round.clothEnergy().stretchScales().size(), ballMesh.edges().size());
  for (const double scale : round.clothEnergy().stretchScales())
    EXPECT_NEAR(scale, 0.3, 1e-9);

  Shape sheet;
  const int cells = 12;
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i)
      sheet.positions.insert(sheet.positions.end(), {0.1 * i, 0.1 * j, 0.0});
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i)
    {
      const std::int64_t v = j * (cells + 1) + i;
      sheet.triangles.insert(sheet.triangles.end(),
                             {v, v + 1, v + cells + 2, v, v + cells + 2, v + cells + 1});
    }
  const dp::TriangleMesh sheetMesh(sheet.triangles, sheet.positions.size() / 3);
  const dp::Tracker flat(sheetMesh, sheet.positions, options);
  for (const double scale : flat.clothEnergy().stretchScales())
    EXPECT_EQ(scale, 1.0);
}

TEST(LocalThickness, AnOpenTubesRadiusIsItsOwn)
{
  // The bending tube (radius 0.1 here) closed by nothing: balls stop at the tube's own far
  // side, so the radius is the tube's; the cap `largest` bounds balls that meet nothing.
  const Shape shape = tube();
  const dp::TriangleMesh mesh(shape.triangles, shape.positions.size() / 3);
  const std::vector<double> radius = dp::medialRadii(mesh, shape.positions.data(), 5.0, 0);
  std::vector<double> sorted = radius;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2];
  double tubeRadius = 0;
  const std::size_t n = mesh.numberOfVertices();
  for (std::size_t v = 0; v < n; ++v)
    tubeRadius += std::hypot(shape.positions[3 * v], shape.positions[3 * v + 1]) / n;
  EXPECT_NEAR(median, tubeRadius, 0.05 * tubeRadius);
  EXPECT_LE(sorted.back(), 5.0);
}

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
  double addModel(const double* x, dp::detail::BlockSparseMatrix& hessian,
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

  // The minimum: (L + C) X = C T, three right-hand sides.
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
  const Eigen::MatrixXd minimum = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>(A).solve(rhs);

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

} // namespace
