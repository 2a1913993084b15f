// SPDX-License-Identifier: BSD-3-Clause
// ClothEnergy: gradients against finite differences, stiffness scales, rest state, invariances
// and the subdivision rule.
#include "dp/field/SurfaceReconstruction.h"
#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/SurfaceLocator.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/geometry/TriangleMesh.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/track/ClothEnergy.h"
#include "dp/track/Tracker.h"

#include "NumericChecks.h"

#include <gtest/gtest.h>
#include <memory>
#include <tbb/global_control.h>

#include "TrackingShapes.h"
#include <cmath>
#include <future>
#include <map>
#include <random>
#include <string>

namespace
{

using dp::test::expectGradientMatches;
using dp::test::jiggle;
using dp::test::makeSequence;
using dp::test::Sequence;
using dp::test::Shape;
using dp::test::tube;
using dp::test::tubeOptions;
using dp::test::vertexRms;

class ClothTerms : public ::testing::TestWithParam<int>
{
};

TEST_P(ClothTerms, GradientMatchesFiniteDifferences)
{
  const Shape m = tube();
  dp::TriangleMesh mesh(m.triangles, m.positions.size() / 3);
  dp::ClothParameters k{0, 0, 0};
  (GetParam() == 0 ? k.stretch : GetParam() == 1 ? k.shear : k.bend) = 1.0;
  dp::ClothEnergy energy(mesh, m.positions.data(), k);
  const std::vector<double> x = jiggle(m.positions, 0.02, 7);
  expectGradientMatches([&](const double* p, double* g)
                        { return g ? energy.addGradient(p, g) : energy.value(p); },
                        x, 1e-5);
}

INSTANTIATE_TEST_SUITE_P(StretchShearBend, ClothTerms, ::testing::Values(0, 1, 2));

TEST(ClothEnergy, StiffnessScalesWeighEachEdgeAndHingeAndKeepTheGradient)
{
  const Shape m = tube();
  dp::TriangleMesh mesh(m.triangles, m.positions.size() / 3);
  dp::ClothEnergy energy(mesh, m.positions.data(), dp::ClothParameters{1, 0, 1});
  const std::vector<double> x = jiggle(m.positions, 0.02, 7);
  const double unscaled = energy.value(x.data());
  energy.setStiffnessScales(std::vector<double>(mesh.edges().size(), 2.0),
                            std::vector<double>(mesh.hinges().size(), 2.0));
  EXPECT_NEAR(energy.value(x.data()), 2 * unscaled, 1e-12 * unscaled);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> scale(0.0, 3.0);
  std::vector<double> edges(mesh.edges().size()), hinges(mesh.hinges().size());
  for (double& s : edges)
    s = scale(random);
  for (double& s : hinges)
    s = scale(random);
  energy.setStiffnessScales(edges, hinges);
  expectGradientMatches([&](const double* p, double* g)
                        { return g ? energy.addGradient(p, g) : energy.value(p); },
                        x, 1e-5);
  edges.pop_back();
  EXPECT_THROW(energy.setStiffnessScales(edges, hinges), std::invalid_argument);
  EXPECT_THROW(energy.setStiffnessScales({}, std::vector<double>(hinges.size(), -1.0)),
               std::invalid_argument);
}

TEST(ClothEnergy, ZeroAtRestWithZeroGradientAndPositiveWhenDeformed)
{
  const Shape m = tube();
  dp::TriangleMesh mesh(m.triangles, m.positions.size() / 3);
  dp::ClothEnergy energy(mesh, m.positions.data(), dp::ClothParameters{});
  std::vector<double> g(m.positions.size(), 0.0);
  EXPECT_NEAR(energy.addGradient(m.positions.data(), g.data()), 0.0, 1e-20);
  for (double v : g)
    EXPECT_NEAR(v, 0.0, 1e-12);
  EXPECT_GT(energy.value(jiggle(m.positions, 0.01, 3).data()), 1e-6);
}

TEST(ClothEnergy, ARestStateOfAnotherShapeMakesThatShapeTheMinimum)
{
  const Shape m = tube();
  dp::TriangleMesh mesh(m.triangles, m.positions.size() / 3);
  dp::ClothEnergy energy(mesh, m.positions.data(), dp::ClothParameters{});
  const std::vector<double> other = jiggle(m.positions, 0.02, 11);
  const dp::ClothRestState templateRest = energy.restState();
  energy.setRestState(energy.restStateOf(other.data()));
  std::vector<double> g(other.size(), 0.0);
  EXPECT_NEAR(energy.addGradient(other.data(), g.data()), 0.0, 1e-20);
  for (double v : g)
    EXPECT_NEAR(v, 0.0, 1e-12);
  EXPECT_GT(energy.value(m.positions.data()), 1e-6);
  // Halfway between the two rest states, both shapes cost energy, less than the full change.
  const double full = energy.value(m.positions.data());
  energy.setRestState(dp::ClothRestState::blend(templateRest, energy.restState(), 0.5));
  EXPECT_GT(energy.value(m.positions.data()), 0.0);
  EXPECT_LT(energy.value(m.positions.data()), full);
  EXPECT_GT(energy.value(other.data()), 0.0);
  // A rest state of another mesh is refused.
  dp::ClothRestState wrong = templateRest;
  wrong.length.pop_back();
  EXPECT_THROW(energy.setRestState(wrong), std::invalid_argument);
}

TEST(ClothEnergy, InvariantToRigidMotionAndUniformScaling)
{
  const Shape m = tube();
  dp::TriangleMesh mesh(m.triangles, m.positions.size() / 3);
  dp::ClothEnergy energy(mesh, m.positions.data(), dp::ClothParameters{});
  const std::vector<double> x = jiggle(m.positions, 0.02, 5);
  const double e = energy.value(x.data());
  // Rotation about an arbitrary axis plus a translation.
  const double c = std::cos(0.7), s = std::sin(0.7);
  std::vector<double> moved(x.size());
  for (std::size_t i = 0; i < x.size(); i += 3)
  {
    moved[i] = c * x[i] - s * x[i + 1] + 3.0;
    moved[i + 1] = s * x[i] + c * x[i + 1] - 1.0;
    moved[i + 2] = x[i + 2] + 0.5;
  }
  EXPECT_NEAR(energy.value(moved.data()), e, 1e-12 * std::max(1.0, e));
  // The same shapes in other units: template and deformation scaled together.
  for (double scale : {1e-3, 1e3})
  {
    std::vector<double> rest(m.positions), y(x);
    for (double& v : rest)
      v *= scale;
    for (double& v : y)
      v *= scale;
    dp::ClothEnergy scaled(mesh, rest.data(), dp::ClothParameters{});
    EXPECT_NEAR(scaled.value(y.data()), e, 1e-9 * e) << scale;
  }
}

// Splits every triangle into four at its edge midpoints.
Shape subdivide(const Shape& m)
{
  Shape out{{}, m.positions};
  std::map<std::pair<std::int64_t, std::int64_t>, std::int64_t> midpoint;
  auto mid = [&](std::int64_t a, std::int64_t b)
  {
    const auto key = std::make_pair(std::min(a, b), std::max(a, b));
    const auto found = midpoint.find(key);
    if (found != midpoint.end())
      return found->second;
    const auto id = static_cast<std::int64_t>(out.positions.size() / 3);
    for (int k = 0; k < 3; ++k)
      out.positions.push_back(0.5 * (m.positions[3 * a + k] + m.positions[3 * b + k]));
    midpoint[key] = id;
    return id;
  };
  for (std::size_t t = 0; t < m.triangles.size(); t += 3)
  {
    const std::int64_t a = m.triangles[t], b = m.triangles[t + 1], c = m.triangles[t + 2];
    const std::int64_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
    out.triangles.insert(out.triangles.end(), {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca});
  }
  return out;
}

TEST(ClothEnergy, SubdivisionKeepsTheTotals)
{
  const Shape coarse = tube(8, 10);
  const Shape fine = subdivide(coarse);
  dp::TriangleMesh coarseMesh(coarse.triangles, coarse.positions.size() / 3);
  dp::TriangleMesh fineMesh(fine.triangles, fine.positions.size() / 3);
  dp::ClothEnergy a(coarseMesh, coarse.positions.data(), dp::ClothParameters{});
  dp::ClothEnergy b(fineMesh, fine.positions.data(), dp::ClothParameters{});
  // Masses are area shares: they sum to 1 at any resolution.
  double massA = 0, massB = 0;
  for (double m : a.vertexMass())
    massA += m;
  for (double m : b.vertexMass())
    massB += m;
  EXPECT_NEAR(massA, 1.0, 1e-12);
  EXPECT_NEAR(massB, 1.0, 1e-12);
  EXPECT_NEAR(a.lengthScale(), b.lengthScale(), 1e-12); // same shape, same area
  // The same uniform stretch of the same shape costs the same stretch energy (k_st constant).
  dp::ClothParameters onlyStretch{1.0, 0.0, 0.0};
  dp::ClothEnergy sa(coarseMesh, coarse.positions.data(), onlyStretch);
  dp::ClothEnergy sb(fineMesh, fine.positions.data(), onlyStretch);
  std::vector<double> xa(coarse.positions), xb(fine.positions);
  for (double& v : xa)
    v *= 1.01;
  for (double& v : xb)
    v *= 1.01;
  const double ea = sa.value(xa.data()), eb = sb.value(xb.data());
  EXPECT_GT(ea, 0);
  EXPECT_NEAR(eb / ea, 1.0, 0.3) << "stretch energy of a 1% uniform stretch, coarse vs fine";
  // Bending weights are area shares too: a closed mesh's hinge weights sum to 1 at any
  // resolution, so the same bend costs the same.
  dp::ClothParameters onlyBend{0.0, 0.0, 1.0};
  dp::ClothEnergy ba(coarseMesh, coarse.positions.data(), onlyBend);
  dp::ClothEnergy bb(fineMesh, fine.positions.data(), onlyBend);
  EXPECT_NEAR(ba.value(xa.data()), 0.0, 1e-12); // scaling does not bend
}

} // namespace
