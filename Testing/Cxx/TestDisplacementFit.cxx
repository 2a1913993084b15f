// SPDX-License-Identifier: BSD-3-Clause
// The detail layer of one frame (DisplacementFitter, FrameSurface): a coarse sphere subdivided
// and displaced onto a bumpy sphere given as a mesh or as points, with holes and stray data.
#include "FineMeshShapes.h"

#include "dp/detail/DisplacementFit.h"
#include "dp/geometry/MeshDistortion.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace
{

using dp::test::Mesh;

constexpr double Bumps = 0.03; // bump height on the unit sphere

double bumpy(const double* u)
{
  return dp::test::bumpyRadius(u, Bumps);
}

// The base (162 vertices on the unit sphere), its map and fitter, the fine mesh of a frame.
struct Fixture
{
  Mesh base = dp::test::icosphere(2);
  dp::SubdivisionMap map{base.triangles, base.vertices(), 2};
  dp::DisplacementFitter fitter{map};
  std::vector<double> positions, normals;
  dp::DisplacementFitOptions options;

  Fixture() : positions(3 * map.fineVertices()), normals(positions.size())
  {
    map.subdivide(base.positions.data(), positions.data(), normals.data());
    options.reach = 0.2; // about the base's edge length
  }

  Mesh displaced(const std::vector<double>& d) const
  {
    Mesh m;
    m.triangles = map.fineTriangles();
    m.positions.resize(positions.size());
    dp::displaceAlongNormals(positions.data(), normals.data(), d.data(), map.fineVertices(),
                             m.positions.data());
    return m;
  }
};

// The RMS distance from the fine vertices to the bumpy sphere along the radius.
double radialRms(const Mesh& m)
{
  double sum = 0;
  for (std::size_t i = 0; i < m.vertices(); ++i)
  {
    const double* x = &m.positions[3 * i];
    const double r = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    const double u[3] = {x[0] / r, x[1] / r, x[2] / r};
    sum += std::pow(r - bumpy(u), 2);
  }
  return std::sqrt(sum / static_cast<double>(m.vertices()));
}

TEST(DisplacementFit, ABumpySphereGivenAsAMeshIsRecovered)
{
  Fixture f;
  const Mesh data = dp::test::icosphere(5, bumpy); // 10242 vertices
  const dp::FrameSurface surface = dp::FrameSurface::ofMesh(data.surface());
  const dp::DisplacementFit fit =
      f.fitter.fit(f.positions.data(), f.normals.data(), surface, f.options);
  EXPECT_EQ(fit.observed, f.map.fineVertices());
  const Mesh flat = f.displaced(std::vector<double>(f.map.fineVertices(), 0.0));
  const Mesh fine = f.displaced(fit.displacement);
  // The subdivided base alone misses the bumps by about their height; displaced, the fine
  // vertices lie on the data (a little off where the membrane term smooths the sharpest bumps).
  EXPECT_GT(radialRms(flat), 0.3 * Bumps);
  EXPECT_LT(radialRms(fine), 0.02 * Bumps);
  const double before = dp::meshDistortion(data.surface(), flat.surface(), 20000).d1Psnr();
  const double after = dp::meshDistortion(data.surface(), fine.surface(), 20000).d1Psnr();
  EXPECT_GT(after, before + 15);
}

TEST(DisplacementFit, ABumpySphereGivenAsNoisyPointsIsRecoveredWithinItsNoise)
{
  Fixture f;
  const Mesh data = dp::test::icosphere(5, bumpy);
  std::mt19937 random(3);
  std::normal_distribution<double> noise(0.0, 0.002);
  std::vector<double> points;
  for (int copy = 0; copy < 2; ++copy) // about 8 points per fine vertex
    for (std::size_t i = 0; i < data.vertices(); ++i)
      for (int c = 0; c < 3; ++c)
        points.push_back(data.positions[3 * i + c] + noise(random));
  const dp::FrameSurface surface =
      dp::FrameSurface::ofPoints(points.data(), points.size() / 3, nullptr);
  const dp::DisplacementFit fit =
      f.fitter.fit(f.positions.data(), f.normals.data(), surface, f.options);
  EXPECT_GT(fit.observed, 0.99 * static_cast<double>(f.map.fineVertices()));
  EXPECT_LT(radialRms(f.displaced(fit.displacement)), 0.1 * Bumps);
}

TEST(DisplacementFit, AHoleIsSpannedSmoothlyWithinTheDisplacementsAroundIt)
{
  Fixture f;
  Mesh data = dp::test::icosphere(5, bumpy);
  // A cap of the data (z > 0.7) taken away: a hole of about 45 degrees across.
  std::vector<std::int64_t> kept;
  for (std::size_t t = 0; t < data.triangles.size(); t += 3)
  {
    bool inCap = true;
    for (int k = 0; k < 3; ++k)
      inCap = inCap && data.positions[3 * data.triangles[t + k] + 2] > 0.7;
    if (!inCap)
      kept.insert(kept.end(), &data.triangles[t], &data.triangles[t] + 3);
  }
  data.triangles = kept;
  const dp::FrameSurface surface = dp::FrameSurface::ofMesh(data.surface());
  const dp::DisplacementFit fit =
      f.fitter.fit(f.positions.data(), f.normals.data(), surface, f.options);
  double rimLow = HUGE_VAL, rimHigh = -HUGE_VAL, holeLow = HUGE_VAL, holeHigh = -HUGE_VAL;
  std::size_t inHole = 0;
  for (std::size_t i = 0; i < f.map.fineVertices(); ++i)
  {
    const double z = f.positions[3 * i + 2], d = fit.displacement[i];
    if (z > 0.72 && z < 0.8)
    {
      rimLow = std::min(rimLow, d);
      rimHigh = std::max(rimHigh, d);
    }
    if (z > 0.85)
    {
      holeLow = std::min(holeLow, d);
      holeHigh = std::max(holeHigh, d);
      ++inHole;
    }
  }
  EXPECT_GT(inHole, 20u);
  EXPECT_LT(fit.observed, f.map.fineVertices() - inHole);
  // The hole's displacements stay within those of its rim (no spike), and vary smoothly:
  // neighbours inside differ by far less than the bumps.
  EXPECT_GE(holeLow, rimLow - 1e-6);
  EXPECT_LE(holeHigh, rimHigh + 1e-6);
  EXPECT_LT(holeHigh - holeLow, 2 * Bumps);
}

TEST(DisplacementFit, AStrayPartAndAnotherSurfaceBehindDoNotPullTheMesh)
{
  Fixture f;
  Mesh data = dp::test::icosphere(5, bumpy);
  // A stray shell a little outside one side (x > 0.9) facing inward (its normals point at the
  // mesh: another body's surface), and a small blob of points floating off the other side.
  const std::size_t n = data.vertices();
  const Mesh shell = dp::test::icosphere(4, [](const double*) { return 1.08; });
  for (std::size_t t = 0; t < shell.triangles.size(); t += 3)
  {
    bool near = true;
    for (int k = 0; k < 3; ++k)
      near = near && shell.positions[3 * shell.triangles[t + k]] > 0.9;
    if (near) // reversed winding: facing inward
      data.triangles.insert(data.triangles.end(),
                            {shell.triangles[t] + static_cast<std::int64_t>(n),
                             shell.triangles[t + 2] + static_cast<std::int64_t>(n),
                             shell.triangles[t + 1] + static_cast<std::int64_t>(n)});
  }
  data.positions.insert(data.positions.end(), shell.positions.begin(), shell.positions.end());
  const dp::FrameSurface surface = dp::FrameSurface::ofMesh(data.surface());
  const dp::DisplacementFit fit =
      f.fitter.fit(f.positions.data(), f.normals.data(), surface, f.options);
  EXPECT_LT(radialRms(f.displaced(fit.displacement)), 0.05 * Bumps);
}

TEST(DisplacementFit, AnInwardWindingMeshIsReadTheRightWayRound)
{
  Fixture f;
  Mesh data = dp::test::icosphere(5, bumpy);
  for (std::size_t t = 0; t < data.triangles.size(); t += 3)
    std::swap(data.triangles[t + 1], data.triangles[t + 2]);
  dp::FrameSurface surface = dp::FrameSurface::ofMesh(data.surface());
  EXPECT_TRUE(surface.orientAgainst(f.positions.data(), f.normals.data(), f.map.fineVertices(),
                                    f.options.reach));
  const dp::DisplacementFit fit =
      f.fitter.fit(f.positions.data(), f.normals.data(), surface, f.options);
  EXPECT_EQ(fit.observed, f.map.fineVertices());
  EXPECT_LT(radialRms(f.displaced(fit.displacement)), 0.02 * Bumps);
}

TEST(DisplacementFit, TheSameBitsOnOneThreadAsOnAll)
{
  Fixture f;
  const Mesh data = dp::test::icosphere(4, bumpy);
  const dp::FrameSurface surface = dp::FrameSurface::ofMesh(data.surface());
  const dp::DisplacementFit all =
      f.fitter.fit(f.positions.data(), f.normals.data(), surface, f.options);
  const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
  const dp::DisplacementFit one =
      f.fitter.fit(f.positions.data(), f.normals.data(), surface, f.options);
  EXPECT_EQ(all.displacement, one.displacement);
  EXPECT_EQ(all.iterations, one.iterations);
}

TEST(DisplacementFit, RefusesEmptyAndNonFiniteFramesAndAReachOfNothing)
{
  const std::vector<double> points = {0, 0, 0, 1, 0, 0, std::nan(""), 0, 0};
  try
  {
    dp::FrameSurface::ofPoints(points.data(), 3, nullptr);
    ADD_FAILURE() << "a NaN coordinate was taken";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("point 2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(dp::FrameSurface::ofPoints(points.data(), 0, nullptr), std::invalid_argument);
  const Mesh sphere = dp::test::icosphere(1);
  Mesh broken = sphere;
  broken.positions[7] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(dp::FrameSurface::ofMesh(broken.surface()), std::invalid_argument);
  broken = sphere;
  broken.triangles[4] = 1000;
  EXPECT_THROW(dp::FrameSurface::ofMesh(broken.surface()), std::invalid_argument);
  Fixture f;
  const dp::FrameSurface surface = dp::FrameSurface::ofMesh(sphere.surface());
  for (const double reach : {0.0, -1.0, std::nan("")})
  {
    f.options.reach = reach;
    EXPECT_THROW(f.fitter.fit(f.positions.data(), f.normals.data(), surface, f.options),
                 std::invalid_argument);
  }
}

} // namespace
