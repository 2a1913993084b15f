// SPDX-License-Identifier: BSD-3-Clause
// Surface reconstruction from oriented points: a closed, outward-facing mesh on the sampled
// surface with the wanted vertex count (within 10%) and well-shaped triangles, at any scale,
// from estimated normals too, with the data's holes bridged and a patch of wrong normals
// tolerated; open data give an open mesh; pieces kept by size; bad input refused with a message.
#include "dp/field/SurfaceReconstruction.h"
#include "dp/geometry/DepthRig.h"
#include "dp/geometry/NormalEstimation.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/geometry/TriangleMesh.h"
#include "dp/io/AnimatedMesh.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <random>

namespace
{
struct Cloud
{
  std::vector<double> points;
  std::vector<float> normals;
};

// Random points on a sphere of radius r about the origin, with outward normals.
Cloud sphere(std::size_t n, double r, double noise = 0)
{
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g;
  Cloud c;
  for (std::size_t i = 0; i < n; ++i)
  {
    double d[3] = {g(rng), g(rng), g(rng)};
    const double l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (double& v : d)
      v /= l;
    for (int k = 0; k < 3; ++k)
    {
      c.points.push_back(r * d[k] + noise * r * g(rng));
      c.normals.push_back(static_cast<float>(d[k]));
    }
  }
  return c;
}

// A torus about the z axis (radii R and r), as a closed triangle mesh.
struct Torus
{
  double R = 1.0, r = 0.4;
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;
  Torus()
  {
    const int nu = 96, nv = 48;
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j)
      {
        const double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
        positions.insert(positions.end(), {(R + r * std::cos(v)) * std::cos(u),
                                           (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
        const std::int64_t a = i * nv + j, b = ((i + 1) % nu) * nv + j,
                           c = ((i + 1) % nu) * nv + (j + 1) % nv, d = i * nv + (j + 1) % nv;
        triangles.insert(triangles.end(), {a, b, c, a, c, d});
      }
  }
  // Distance from x to the torus surface.
  double distance(const double* x) const
  {
    const double rho = std::hypot(x[0], x[1]);
    return std::abs(std::hypot(rho - R, x[2]) - r);
  }
};

// Edges used by one triangle only, and by more than two.
std::pair<std::size_t, std::size_t> badEdges(const dp::ReconstructedMesh& m)
{
  std::map<std::pair<std::int64_t, std::int64_t>, int> uses;
  for (std::size_t t = 0; t < m.triangles.size(); t += 3)
    for (int e = 0; e < 3; ++e)
    {
      const std::int64_t a = m.triangles[t + e], b = m.triangles[t + (e + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  std::size_t open = 0, shared = 0;
  for (const auto& [edge, n] : uses)
  {
    open += n == 1;
    shared += n > 2;
  }
  return {open, shared};
}

// Every directed edge once: consistently oriented.
bool consistentlyOriented(const dp::ReconstructedMesh& m)
{
  std::map<std::pair<std::int64_t, std::int64_t>, int> uses;
  for (std::size_t t = 0; t < m.triangles.size(); t += 3)
    for (int e = 0; e < 3; ++e)
      if (++uses[{m.triangles[t + e], m.triangles[t + (e + 1) % 3]}] > 1)
        return false;
  return true;
}

double signedVolume(const dp::ReconstructedMesh& m)
{
  double v = 0;
  for (std::size_t t = 0; t < m.triangles.size(); t += 3)
  {
    const double* a = &m.positions[3 * m.triangles[t]];
    const double* b = &m.positions[3 * m.triangles[t + 1]];
    const double* c = &m.positions[3 * m.triangles[t + 2]];
    v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
          a[2] * (b[0] * c[1] - b[1] * c[0])) /
         6.0;
  }
  return v;
}
} // namespace

TEST(SurfaceReconstruction, ClosedOutwardMeshOnTheSphereWithTheWantedVertexCount)
{
  const Cloud c = sphere(8000, 1.0);
  dp::ReconstructionOptions o;
  o.targetVertices = 600;
  const dp::ReconstructedMesh m =
      dp::reconstructSurface(c.points.data(), c.normals.data(), c.points.size() / 3, o);
  const std::size_t nv = m.positions.size() / 3;
  EXPECT_GE(nv, 540u);
  EXPECT_LE(nv, 660u);
  // Closed: every edge has two triangles (one hinge per edge).
  const dp::TriangleMesh mesh(m.triangles, nv);
  EXPECT_EQ(mesh.hinges().size(), mesh.edges().size());
  EXPECT_TRUE(m.closed);
  EXPECT_EQ(mesh.poorlyShapedShare(m.positions.data()), 0.0);
  // On the sphere, and facing out (positive volume close to the sphere's).
  for (std::size_t v = 0; v < nv; ++v)
  {
    const double* p = &m.positions[3 * v];
    EXPECT_NEAR(std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), 1.0, 0.5 * m.voxelSize);
  }
  EXPECT_NEAR(signedVolume(m) / (4.0 / 3.0 * M_PI), 1.0, 0.05);
}

TEST(SurfaceReconstruction, DoesNotDependOnUnitsAndWorksFromEstimatedNormals)
{
  std::size_t counts[2] = {0, 0};
  int k = 0;
  for (double scale : {1e-3, 1e3})
  {
    const Cloud c = sphere(6000, scale, 0.003);
    // Noisy points, normals estimated (and oriented) from the points alone.
    const std::vector<float> normals = dp::estimateNormals(c.points.data(), c.points.size() / 3);
    dp::ReconstructionOptions o;
    o.targetVertices = 300;
    const dp::ReconstructedMesh m =
        dp::reconstructSurface(c.points.data(), normals.data(), c.points.size() / 3, o);
    counts[k++] = m.positions.size() / 3;
    EXPECT_NEAR(std::abs(signedVolume(m)) / (4.0 / 3.0 * M_PI * scale * scale * scale), 1.0, 0.08);
  }
  EXPECT_EQ(counts[0], counts[1]);
  EXPECT_GE(counts[0], 270u);
  EXPECT_LE(counts[0], 330u);
}

TEST(SurfaceReconstruction, BridgesHolesInTheDataWithAClosedWellShapedMesh)
{
  // A torus sampled like a scanner that missed two patches, with noise; normals estimated.
  const Torus torus;
  dp::SamplerOptions sampling;
  sampling.pointsPerFrame = 12000;
  sampling.noiseStdDev = 0.003;
  sampling.holes = 2;
  sampling.holeRadius = 0.12;
  sampling.normals = false;
  sampling.seed = 5;
  const dp::PointCloud cloud = dp::sampleSurface(torus.positions, torus.triangles, sampling, 0);
  const std::vector<double> holes = dp::holeCentres(torus.positions, torus.triangles, sampling, 0);
  const std::vector<float> normals =
      dp::estimateNormals(cloud.points.data(), cloud.numberOfPoints());
  for (std::size_t target : {300u, 1500u})
  {
    dp::ReconstructionOptions o;
    o.targetVertices = target;
    const dp::ReconstructedMesh m =
        dp::reconstructSurface(cloud.points.data(), normals.data(), cloud.numberOfPoints(), o);
    const std::size_t nv = m.positions.size() / 3;
    EXPECT_NEAR(static_cast<double>(nv), static_cast<double>(target), 0.1 * target);
    // Watertight and manifold, one piece of genus one: V - E + F = 0.
    const auto [open, shared] = badEdges(m);
    EXPECT_EQ(open, 0u) << target;
    EXPECT_EQ(shared, 0u) << target;
    EXPECT_TRUE(m.closed);
    const dp::TriangleMesh mesh(m.triangles, nv);
    EXPECT_EQ(static_cast<long>(nv) - static_cast<long>(mesh.edges().size()) +
                  static_cast<long>(mesh.numberOfTriangles()),
              0);
    // Outward, and on the surface: no vertex far off it (no spikes), none far inside a hole.
    EXPECT_TRUE(consistentlyOriented(m));
    const double volume = 2 * M_PI * M_PI * torus.R * torus.r * torus.r;
    EXPECT_NEAR(signedVolume(m) / volume, 1.0, 0.08) << target;
    double worst = 0;
    for (std::size_t v = 0; v < nv; ++v)
      worst = std::max(worst, torus.distance(&m.positions[3 * v]));
    EXPECT_LT(worst, 0.06) << target;
    // The holes are covered: a vertex near each hole's centre.
    for (std::size_t h = 0; h < holes.size(); h += 3)
    {
      double nearest = 1e9;
      for (std::size_t v = 0; v < nv; ++v)
        nearest = std::min(nearest, std::hypot(m.positions[3 * v] - holes[h],
                                               m.positions[3 * v + 1] - holes[h + 1],
                                               m.positions[3 * v + 2] - holes[h + 2]));
      EXPECT_LT(nearest, 0.1) << "hole " << h / 3 << ", target " << target;
    }
    // Well-shaped triangles: no slivers for the cloth energy, and none flat (which the tracker
    // refuses).
    EXPECT_LT(mesh.poorlyShapedShare(m.positions.data(), 0.1), 0.002) << target;
    EXPECT_EQ(mesh.poorlyShapedShare(m.positions.data(), 0.01), 0.0) << target;
  }
}

TEST(SurfaceReconstruction, APatchOfWrongNormalsMakesNoSpike)
{
  // Normals of a cap of the sphere flipped (data folded over itself, a badly oriented patch).
  Cloud c = sphere(8000, 1.0, 0.002);
  for (std::size_t i = 0; i < c.points.size() / 3; ++i)
    if (c.points[3 * i + 2] > 0.97)
      for (int k = 0; k < 3; ++k)
        c.normals[3 * i + k] = -c.normals[3 * i + k];
  dp::ReconstructionOptions o;
  o.targetVertices = 500;
  const dp::ReconstructedMesh m =
      dp::reconstructSurface(c.points.data(), c.normals.data(), c.points.size() / 3, o);
  EXPECT_TRUE(m.closed);
  EXPECT_EQ(badEdges(m).first, 0u);
  for (std::size_t v = 0; v < m.positions.size() / 3; ++v)
  {
    const double* p = &m.positions[3 * v];
    EXPECT_NEAR(std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), 1.0, 0.06);
  }
  EXPECT_GT(signedVolume(m), 0);
}

TEST(SurfaceReconstruction, OpenDataGiveAnOpenMesh)
{
  // The upper half of a sphere: a surface seen from one side.
  Cloud all = sphere(12000, 1.0), c;
  for (std::size_t i = 0; i < all.points.size() / 3; ++i)
    if (all.points[3 * i + 2] > 0)
      for (int k = 0; k < 3; ++k)
      {
        c.points.push_back(all.points[3 * i + k]);
        c.normals.push_back(all.normals[3 * i + k]);
      }
  dp::ReconstructionOptions o;
  o.targetVertices = 400;
  const dp::ReconstructedMesh m =
      dp::reconstructSurface(c.points.data(), c.normals.data(), c.points.size() / 3, o);
  EXPECT_FALSE(m.closed);
  EXPECT_GT(badEdges(m).first, 0u);
  EXPECT_EQ(badEdges(m).second, 0u);
  EXPECT_NEAR(static_cast<double>(m.positions.size() / 3), 400.0, 40.0);
  for (std::size_t v = 0; v < m.positions.size() / 3; ++v)
  {
    const double* p = &m.positions[3 * v];
    EXPECT_NEAR(std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), 1.0, 0.05);
    EXPECT_GT(p[2], -0.1);
  }
  // Facing along the data's normals (outward, upward).
  double up = 0;
  for (std::size_t t = 0; t < m.triangles.size(); t += 3)
  {
    const double* a = &m.positions[3 * m.triangles[t]];
    const double* b = &m.positions[3 * m.triangles[t + 1]];
    const double* d = &m.positions[3 * m.triangles[t + 2]];
    up += (b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]);
  }
  EXPECT_GT(up, 0);
}

// Three separate balls: radius 1 at the origin, 0.4 at x = 3 and 0.06 at x = -3 (a floater).
// By default only the largest is meshed; with keptPieceShare 0.1 the 0.4 ball (a sixth of the
// largest's area) is kept too, and the floater is not.
TEST(SurfaceReconstruction, KeepsThePiecesAsLargeAsTheAskedShareOfTheLargest)
{
  Cloud c = sphere(8000, 1.0);
  const auto add = [&](const Cloud& ball, double x)
  {
    for (std::size_t i = 0; i < ball.points.size(); i += 3)
    {
      c.points.insert(c.points.end(), {ball.points[i] + x, ball.points[i + 1], ball.points[i + 2]});
      c.normals.insert(c.normals.end(), &ball.normals[i], &ball.normals[i] + 3);
    }
  };
  add(sphere(1280, 0.4), 3.0);
  add(sphere(40, 0.06), -3.0);
  const auto piecesMeshed = [&](double share)
  {
    dp::ReconstructionOptions o;
    o.targetVertices = 800;
    o.keptPieceShare = share;
    const dp::ReconstructedMesh m =
        dp::reconstructSurface(c.points.data(), c.normals.data(), c.points.size() / 3, o);
    std::array<std::size_t, 3> onBall{0, 0, 0};
    for (std::size_t v = 0; v < m.positions.size(); v += 3)
      onBall[m.positions[v] > 2 ? 1 : m.positions[v] < -2 ? 2 : 0]++;
    return onBall;
  };
  const std::array<std::size_t, 3> largest = piecesMeshed(1);
  EXPECT_GT(largest[0], 700u);
  EXPECT_EQ(largest[1], 0u);
  EXPECT_EQ(largest[2], 0u);
  const std::array<std::size_t, 3> large = piecesMeshed(0.1);
  EXPECT_GT(large[0], 500u);
  EXPECT_GT(large[1], 40u); // about a sixth of the vertices, by area
  EXPECT_EQ(large[2], 0u);
  EXPECT_GT(piecesMeshed(0.0001)[2], 0u); // the floater is a piece of its own, dropped by size
}

TEST(SurfaceReconstruction, RefusesBadInputWithAMessage)
{
  const Cloud c = sphere(100, 1.0);
  dp::ReconstructionOptions o;
  try
  {
    dp::reconstructSurface(c.points.data(), c.normals.data(), 10, o);
    FAIL() << "10 points accepted";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("at least 16 points"), std::string::npos);
  }
  Cloud bad = c;
  bad.points[3 * 42 + 1] = std::nan("");
  try
  {
    dp::reconstructSurface(bad.points.data(), bad.normals.data(), 100, o);
    FAIL() << "NaN accepted";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("point 42"), std::string::npos);
  }
  o.targetVertices = 5;
  EXPECT_THROW(dp::reconstructSurface(c.points.data(), c.normals.data(), 100, o),
               std::invalid_argument);
  // All points in one place: nothing to mesh.
  std::vector<double> same(3 * 50, 0.25);
  std::vector<float> up(3 * 50, 0.0f);
  for (std::size_t i = 0; i < 50; ++i)
    up[3 * i + 2] = 1.0f;
  o.targetVertices = 100;
  EXPECT_THROW(dp::reconstructSurface(same.data(), up.data(), 50, o), std::invalid_argument);
  for (double share : {0.0, 1.5, std::nan("")})
  {
    dp::ReconstructionOptions shares;
    shares.keptPieceShare = share;
    EXPECT_THROW(dp::reconstructSurface(c.points.data(), c.normals.data(), 100, shares),
                 std::invalid_argument);
  }
  o.voxelSize = -1;
  EXPECT_THROW(dp::reconstructSurface(c.points.data(), c.normals.data(), 100, o),
               std::invalid_argument);
  // A voxel far too small for the data: refused with the voxel size before the band is built
  // (a million voxels a side would not fit in memory).
  o.voxelSize = 1e-6;
  try
  {
    dp::reconstructSurface(c.points.data(), c.normals.data(), 100, o);
    FAIL() << "a 1e-6 voxel accepted";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("voxel size"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("would exceed"), std::string::npos) << e.what();
  }
}

// A capsule-like bending tube (1.7 units long, as a person is metres tall) captured by a rig of
// four simulated depth cameras: a layer of noise, stacked views, flying pixels, its caps half
// unseen. The template from those points is what the rig's subject is: one closed piece of genus
// 0, no folded edges, within a few layers of the truth.
TEST(SurfaceReconstruction, ARigsNoisyLayerGivesAClosedGenusZeroTemplate)
{
  dp::BendingTube::Options o;
  o.frames = 1;
  o.length = 1.7;
  o.radius = 0.2;
  const dp::BendingTube tube(o);
  dp::RigOptions rig;
  rig.cameras = 4;
  rig.up = "z";
  rig.subjectHeight = 1.7;
  const dp::PointCloud cloud = dp::DepthRig(tube, rig).fusedCloud(tube.positions(0), 0);
  dp::ReconstructionOptions options;
  options.targetVertices = 600;
  const dp::ReconstructedMesh m = dp::reconstructSurface(cloud.points.data(), cloud.normals.data(),
                                                         cloud.numberOfPoints(), options);
  EXPECT_TRUE(m.smoothedForNoise);
  EXPECT_GT(m.strayPoints, 0u);
  const auto [open, shared] = badEdges(m);
  EXPECT_EQ(open, 0u);
  EXPECT_EQ(shared, 0u);
  const std::size_t vertices = m.positions.size() / 3, faces = m.triangles.size() / 3;
  EXPECT_EQ(
      static_cast<long>(vertices) - static_cast<long>(3 * faces / 2) + static_cast<long>(faces), 2)
      << "Euler characteristic of a sphere";
  // Folded: the faces of an edge turn more than 120 degrees.
  const dp::TriangleMesh mesh(m.triangles, vertices);
  std::vector<double> normals(3 * faces);
  for (std::size_t t = 0; t < faces; ++t)
  {
    const double* a = &m.positions[3 * m.triangles[3 * t]];
    const double* b = &m.positions[3 * m.triangles[3 * t + 1]];
    const double* c = &m.positions[3 * m.triangles[3 * t + 2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; ++k)
      normals[3 * t + k] = n[k] / l;
  }
  std::map<std::pair<std::int64_t, std::int64_t>, std::vector<std::size_t>> facesOf;
  for (std::size_t t = 0; t < faces; ++t)
    for (int e = 0; e < 3; ++e)
    {
      const std::int64_t a = m.triangles[3 * t + e], b = m.triangles[3 * t + (e + 1) % 3];
      facesOf[{std::min(a, b), std::max(a, b)}].push_back(t);
    }
  std::size_t folded = 0;
  for (const auto& [edge, f] : facesOf)
    folded += f.size() == 2 && normals[3 * f[0]] * normals[3 * f[1]] +
                                       normals[3 * f[0] + 1] * normals[3 * f[1] + 1] +
                                       normals[3 * f[0] + 2] * normals[3 * f[1] + 2] <
                                   -0.5;
  EXPECT_LE(folded, facesOf.size() / 200) << "at most 0.5 % of the edges folded";
}
