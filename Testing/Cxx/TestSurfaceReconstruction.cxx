// SPDX-License-Identifier: BSD-3-Clause
// Surface reconstruction from oriented points: a closed, outward-facing mesh on the sampled
// surface with about the wanted vertex count, at any scale, from estimated normals too; bad
// input refused with a message.
#include "dp/DistanceField.h"
#include "dp/SurfaceReconstruction.h"
#include "dp/TriangleMesh.h"

#include <gtest/gtest.h>

#include <cmath>
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
  EXPECT_GE(nv, 450u);
  EXPECT_LE(nv, 750u);
  // Closed: every edge has two triangles (one hinge per edge).
  const dp::TriangleMesh mesh(m.triangles, nv);
  EXPECT_EQ(mesh.hinges().size(), mesh.edges().size());
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
  EXPECT_GE(counts[0], 200u);
  EXPECT_LE(counts[0], 400u);
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
}
