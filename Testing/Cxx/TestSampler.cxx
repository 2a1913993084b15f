// SPDX-License-Identifier: BSD-3-Clause
// Procedural animated meshes and the sequence sampler that makes the test data.
#include "TestUtilities.h"

#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/io/FrameSequence.h"
#include "dp/io/PointCloudIO.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>

namespace
{

using dp::test::TempDir;
constexpr double Pi = 3.14159265358979323846;

double signedVolume(const std::vector<double>& p, const std::vector<std::int64_t>& t)
{
  double v = 0;
  for (std::size_t k = 0; k < t.size(); k += 3)
  {
    const double* a = &p[3 * t[k]];
    const double* b = &p[3 * t[k + 1]];
    const double* c = &p[3 * t[k + 2]];
    v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
          a[2] * (b[0] * c[1] - b[1] * c[0])) /
         6.0;
  }
  return v;
}

// Directed edge -> count; a closed, consistently oriented surface has each edge once each way.
std::map<std::pair<std::int64_t, std::int64_t>, int>
directedEdges(const std::vector<std::int64_t>& t)
{
  std::map<std::pair<std::int64_t, std::int64_t>, int> edges;
  for (std::size_t k = 0; k < t.size(); k += 3)
    for (int e = 0; e < 3; ++e)
      ++edges[{t[k + e], t[k + (e + 1) % 3]}];
  return edges;
}

TEST(BendingTube, IsClosedOutwardOrientedAndMoves)
{
  dp::BendingTube tube;
  const auto edges = directedEdges(tube.triangles());
  for (const auto& [edge, count] : edges)
  {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(edges.count({edge.second, edge.first}), 1u) << "open or inconsistently oriented edge";
  }
  for (std::size_t f = 0; f < tube.numberOfFrames(); f += 7)
    EXPECT_GT(signedVolume(tube.positions(f), tube.triangles()), 0.0) << "frame " << f;
  const auto p0 = tube.positions(0), p5 = tube.positions(5);
  double moved = 0;
  for (std::size_t i = 0; i < p0.size(); ++i)
    moved = std::max(moved, std::abs(p0[i] - p5[i]));
  EXPECT_GT(moved, 0.1);
  EXPECT_THROW(tube.positions(tube.numberOfFrames()), std::out_of_range);
}

TEST(BendingTube, BendingKeepsTheAxisLength)
{
  dp::BendingTube::Options o;
  o.segments = 8;
  dp::BendingTube tube(o);
  // Cap centres are the axis ends; the axis is an arc of the rest length, so the chord is
  // 2 sin(theta/2)/kappa. At a quarter of the animation the bend angle is maxBendRadians.
  const std::size_t quarter = (o.frames - 1) / 4;
  const double s = static_cast<double>(quarter) / static_cast<double>(o.frames - 1);
  const double theta = o.maxBendRadians * std::sin(2 * Pi * s);
  const auto p = tube.positions(quarter);
  const std::size_t bottom = tube.numberOfVertices() - 2, top = bottom + 1;
  const double chord = std::hypot(p[3 * top] - p[3 * bottom], p[3 * top + 1] - p[3 * bottom + 1],
                                  p[3 * top + 2] - p[3 * bottom + 2]);
  EXPECT_NEAR(chord, 2 * std::sin(theta / 2) * o.length / theta, 1e-9);
}

TEST(WavingSheet, HasAnOpenBoundaryAndFixedXY)
{
  dp::WavingSheet::Options o;
  dp::WavingSheet sheet(o);
  int boundary = 0;
  const auto edges = directedEdges(sheet.triangles());
  for (const auto& [edge, count] : edges)
    boundary += edges.count({edge.second, edge.first}) == 0;
  EXPECT_EQ(boundary, static_cast<int>(2 * (o.columns - 1) + 2 * (o.rows - 1)));
  const auto a = sheet.positions(0), b = sheet.positions(11);
  double dz = 0;
  for (std::size_t i = 0; i < a.size(); i += 3)
  {
    EXPECT_EQ(a[i], b[i]);
    EXPECT_EQ(a[i + 1], b[i + 1]);
    dz = std::max(dz, std::abs(a[i + 2] - b[i + 2]));
  }
  EXPECT_GT(dz, 0.05);
}

TEST(Sampler, SameSeedSameFramesOtherSeedOtherFrames)
{
  dp::BendingTube tube;
  dp::SamplerOptions o;
  o.pointsPerFrame = 500;
  o.noiseStdDev = 0.001;
  const auto p = tube.positions(4);
  const auto a = dp::sampleSurface(p, tube.triangles(), o, 4);
  const auto b = dp::sampleSurface(p, tube.triangles(), o, 4);
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.normals, b.normals);
  o.seed = 2;
  EXPECT_NE(a.points, dp::sampleSurface(p, tube.triangles(), o, 4).points);
  o.seed = 1;
  EXPECT_NE(a.points, dp::sampleSurface(p, tube.triangles(), o, 5).points); // other frame
}

TEST(Sampler, PointsLieOnTheSurfaceAreaUniformlyWithOutwardNormals)
{
  dp::BendingTube::Options to;
  dp::BendingTube tube(to);
  dp::SamplerOptions o;
  o.pointsPerFrame = 20000;
  const auto cloud = dp::sampleSurface(tube.positions(0), tube.triangles(), o, 0);
  ASSERT_EQ(cloud.numberOfPoints(), o.pointsPerFrame);
  const double m = static_cast<double>(to.segments);
  const double inner = to.radius * std::cos(Pi / m); // the facets' distance from the axis
  std::size_t onCaps = 0;
  for (std::size_t i = 0; i < cloud.numberOfPoints(); ++i)
  {
    const double* q = &cloud.points[3 * i];
    const float* n = &cloud.normals[3 * i];
    const double r = std::hypot(q[0], q[1]);
    EXPECT_NEAR(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), 1.0, 1e-5);
    if (std::abs(q[2]) < 1e-12 || std::abs(q[2] - to.length) < 1e-12)
    {
      ++onCaps;
      EXPECT_LE(r, to.radius + 1e-12);
      continue;
    }
    ASSERT_GE(r, inner - 1e-9);
    ASSERT_LE(r, to.radius + 1e-9);
    // Points on the side away from the caps have (smoothed) radial normals pointing out.
    if (q[2] > 0.1 && q[2] < to.length - 0.1)
    {
      EXPECT_GT((n[0] * q[0] + n[1] * q[1]) / r, 0.95);
    }
  }
  const double capArea = 2 * 0.5 * m * to.radius * to.radius * std::sin(2 * Pi / m);
  const double sideArea = m * 2 * to.radius * std::sin(Pi / m) * to.length;
  const double expected = capArea / (capArea + sideArea);
  const double fraction = static_cast<double>(onCaps) / static_cast<double>(o.pointsPerFrame);
  const double sigma = std::sqrt(expected * (1 - expected) / static_cast<double>(o.pointsPerFrame));
  EXPECT_NEAR(fraction, expected, 5 * sigma);
}

TEST(Sampler, NoiseHasTheRequestedStandardDeviation)
{
  dp::WavingSheet sheet;
  dp::SamplerOptions clean;
  clean.pointsPerFrame = 20000;
  dp::SamplerOptions noisy = clean;
  noisy.noiseStdDev = 0.01;
  const auto p = sheet.positions(3);
  const auto a = dp::sampleSurface(p, sheet.triangles(), clean, 3);
  const auto b = dp::sampleSurface(p, sheet.triangles(), noisy, 3);
  ASSERT_EQ(a.points.size(), b.points.size());
  double sum = 0, sum2 = 0;
  for (std::size_t i = 0; i < a.points.size(); ++i)
  {
    const double d = b.points[i] - a.points[i];
    sum += d;
    sum2 += d * d;
  }
  const double n = static_cast<double>(a.points.size());
  EXPECT_NEAR(sum / n, 0.0, 5 * 0.01 / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.01, 0.0003);
}

TEST(Sampler, HolesRemoveEveryPointNearTheirCentresAndFollowTheMaterial)
{
  dp::WavingSheet sheet;
  dp::SamplerOptions o;
  o.pointsPerFrame = 20000;
  o.holes = 3;
  o.holeRadius = 0.08;
  dp::SamplerOptions noHoles = o;
  noHoles.holes = 0;
  for (std::size_t frame : {0u, 9u})
  {
    const auto p = sheet.positions(frame);
    const auto centres = dp::holeCentres(p, sheet.triangles(), o, frame);
    ASSERT_EQ(centres.size(), 9u);
    auto insideHoles = [&](const dp::PointCloud& c)
    {
      std::size_t inside = 0;
      for (std::size_t i = 0; i < c.numberOfPoints(); ++i)
        for (std::size_t h = 0; h < 3; ++h)
          inside +=
              std::hypot(c.points[3 * i] - centres[3 * h], c.points[3 * i + 1] - centres[3 * h + 1],
                         c.points[3 * i + 2] - centres[3 * h + 2]) < o.holeRadius;
      return inside;
    };
    const auto holed = dp::sampleSurface(p, sheet.triangles(), o, frame);
    const auto full = dp::sampleSurface(p, sheet.triangles(), noHoles, frame);
    EXPECT_EQ(insideHoles(holed), 0u);
    EXPECT_GT(insideHoles(full), 100u);
    EXPECT_LT(holed.numberOfPoints(), full.numberOfPoints());
  }
  // Fixed holes sit on the same material point: the sheet's x and y never move.
  const auto c0 = dp::holeCentres(sheet.positions(0), sheet.triangles(), o, 0);
  const auto c9 = dp::holeCentres(sheet.positions(9), sheet.triangles(), o, 9);
  EXPECT_DOUBLE_EQ(c0[0], c9[0]);
  EXPECT_DOUBLE_EQ(c0[1], c9[1]);
  EXPECT_NE(c0[2], c9[2]);
  o.holesMove = true;
  EXPECT_NE(dp::holeCentres(sheet.positions(9), sheet.triangles(), o, 9)[0], c9[0]);
}

TEST(Sampler, RejectsMeshesWithoutAreaAndBadIndices)
{
  dp::SamplerOptions o;
  EXPECT_THROW(dp::sampleSurface({0, 0, 0, 1, 0, 0, 2, 0, 0}, {0, 1, 2}, o, 0),
               std::invalid_argument);
  EXPECT_THROW(dp::sampleSurface({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 3}, o, 0),
               std::invalid_argument);
  o.noiseStdDev = -1;
  EXPECT_THROW(dp::sampleSurface({0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2}, o, 0),
               std::invalid_argument);
}

TEST(Sampler, WritesASequenceTheFrameListReadsBackWithGroundTruth)
{
  TempDir dir;
  dp::BendingTube::Options to;
  to.frames = 4;
  dp::BendingTube tube(to);
  dp::SamplerOptions o;
  o.pointsPerFrame = 300;
  dp::SequenceWriteOptions w;
  w.frameInterval = 0.1;
  w.writeGroundTruth = true;
  const std::string series = dp::writeSampledSequence(tube, o, dir.file("seq"), w);
  const auto frames = dp::FrameSequence::fromSeriesFile(series);
  ASSERT_EQ(frames.size(), 4u);
  EXPECT_DOUBLE_EQ(frames[3].time, 0.30000000000000004);
  const auto cloud = dp::readPointCloud(frames[2].path);
  EXPECT_EQ(cloud.numberOfPoints(), 300u);
  EXPECT_TRUE(cloud.hasNormals());

  // The ground truth reads back as an animated mesh with the tube's connectivity.
  dp::MeshSequenceFiles truth(dp::FrameSequence::fromDirectory(dir.file("seq/truth")));
  EXPECT_EQ(truth.numberOfFrames(), 4u);
  EXPECT_EQ(truth.triangles(), tube.triangles());
  const auto expected = tube.positions(3), got = truth.positions(3);
  ASSERT_EQ(expected.size(), got.size());
  for (std::size_t i = 0; i < got.size(); ++i)
    EXPECT_NEAR(got[i], expected[i], 1e-6);
}

TEST(MeshSequenceFiles, FramesWithAnotherVertexCountAreErrors)
{
  TempDir dir;
  dp::BendingTube tube;
  dp::writePLY(dir.file("m0.ply"), tube.frameMesh(0));
  dp::PointCloud other = tube.frameMesh(1);
  other.points.resize(other.points.size() - 3);
  other.faceOffsets.clear();
  other.faceConnectivity.clear();
  dp::writePLY(dir.file("m1.ply"), other);
  dp::MeshSequenceFiles files(dp::FrameSequence::fromDirectory(dir.path()));
  EXPECT_NO_THROW(files.positions(0));
  dp::test::expectFileError([&] { files.positions(1); }, dir.file("m1.ply"),
                            "not one animated mesh");
  // A first frame without faces cannot define the connectivity.
  dp::test::expectFileError(
      [&] { dp::MeshSequenceFiles(dp::FrameSequence::fromFiles({dir.file("m1.ply")})); },
      dir.file("m1.ply"), "has no faces");
}

} // namespace
