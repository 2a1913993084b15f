// SPDX-License-Identifier: BSD-3-Clause
// A mesh frame read as a surface: samples spread by area with the faces' normals and the
// vertices' colours (sampleMeshSurface), and the tracker following a take given as coarse meshes.
#include "dp/geometry/MeshSurfaceSamples.h"
#include "dp/geometry/SurfaceLocator.h"
#include "dp/geometry/TriangleMesh.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/track/Tracker.h"

#include "TrackingShapes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace
{

// The unit square z = 0 as a strip of triangles, 1 x 1 cells left of x = 0.5 and cells
// `fine` times smaller right of it: a mesh whose vertex density differs by fine^2.
struct UnevenSquare
{
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;
  std::vector<std::uint8_t> colours; // red = 255 x, green = 255 y, blue 7

  explicit UnevenSquare(int fine)
  {
    addGrid(0, 0.5, 1, 1);
    addGrid(0.5, 1, fine, 2 * fine);
  }

private:
  void addGrid(double x0, double x1, int columns, int rows)
  {
    const auto first = static_cast<std::int64_t>(positions.size() / 3);
    for (int j = 0; j <= rows; ++j)
      for (int i = 0; i <= columns; ++i)
      {
        const double x = x0 + (x1 - x0) * i / columns, y = static_cast<double>(j) / rows;
        positions.insert(positions.end(), {x, y, 0});
        colours.insert(colours.end(), {static_cast<std::uint8_t>(std::lround(255 * x)),
                                       static_cast<std::uint8_t>(std::lround(255 * y)), 7});
      }
    const auto at = [&](int i, int j) { return first + j * (columns + 1) + i; };
    for (int j = 0; j < rows; ++j)
      for (int i = 0; i < columns; ++i)
        triangles.insert(triangles.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j),
                                           at(i + 1, j + 1), at(i, j + 1)});
  }
};

dp::MeshSurface surfaceOf(const std::vector<double>& positions,
                          const std::vector<std::int64_t>& triangles,
                          const std::vector<std::uint8_t>* colours = nullptr)
{
  dp::MeshSurface s;
  s.positions = positions.data();
  s.vertices = positions.size() / 3;
  s.triangles = triangles.data();
  s.triangleCount = triangles.size() / 3;
  if (colours)
  {
    s.colours = colours->data();
    s.colourComponents = 3;
  }
  return s;
}

TEST(MeshSurfaceSamples, SpreadsSamplesByAreaWhateverTheVertexDensity)
{
  const UnevenSquare square(8);
  const dp::PointCloud samples =
      dp::sampleMeshSurface(surfaceOf(square.positions, square.triangles), 4000);
  EXPECT_NEAR(static_cast<double>(samples.numberOfPoints()), 4000, 1);
  std::size_t left = 0;
  for (std::size_t i = 0; i < samples.numberOfPoints(); ++i)
  {
    left += samples.points[3 * i] < 0.5;
    EXPECT_NEAR(samples.points[3 * i + 2], 0, 1e-12);
  }
  // Half the area, half the samples, though the left half has 1/64 of the vertices.
  EXPECT_NEAR(static_cast<double>(left) / 4000, 0.5, 0.01);
  // Spread, not clumped: every 0.1 x 0.1 cell of the square has its share (40) within 30 %.
  std::vector<int> cells(100, 0);
  for (std::size_t i = 0; i < samples.numberOfPoints(); ++i)
    ++cells[std::min(9, static_cast<int>(10 * samples.points[3 * i])) +
            10 * std::min(9, static_cast<int>(10 * samples.points[3 * i + 1]))];
  for (int c : cells)
    EXPECT_NEAR(c, 40, 12);
}

TEST(MeshSurfaceSamples, CarriesTheFacesNormalsAndTheVerticesColours)
{
  const UnevenSquare square(3);
  const dp::PointCloud samples =
      dp::sampleMeshSurface(surfaceOf(square.positions, square.triangles, &square.colours), 500);
  ASSERT_EQ(samples.colorComponents, 3);
  ASSERT_EQ(samples.colors.size(), 3 * samples.numberOfPoints());
  for (std::size_t i = 0; i < samples.numberOfPoints(); ++i)
  {
    EXPECT_NEAR(samples.normals[3 * i + 2], 1, 1e-6); // counter-clockwise in x y: +z
    // Colour linear in x and y over the square, so interpolation gives it back to a byte.
    EXPECT_NEAR(samples.colors[3 * i], 255 * samples.points[3 * i], 1.01);
    EXPECT_NEAR(samples.colors[3 * i + 1], 255 * samples.points[3 * i + 1], 1.01);
    EXPECT_EQ(samples.colors[3 * i + 2], 7);
  }
}

TEST(MeshSurfaceSamples, SmoothNormalsOnACurvedSurfaceAndTheSameSamplesEveryTime)
{
  const dp::test::Shape t = dp::test::tube(6, 8);
  const dp::MeshSurface s = surfaceOf(t.positions, t.triangles);
  const dp::PointCloud a = dp::sampleMeshSurface(s, 2000), b = dp::sampleMeshSurface(s, 2000);
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.normals, b.normals);
  // The tube's axis is z (0 to 1) at frame 0: on the wall between the rings next to the caps
  // (whose vertex normals lean toward the caps), normals point away from the axis.
  std::size_t wall = 0;
  for (std::size_t i = 0; i < a.numberOfPoints(); ++i)
  {
    const double rx = a.points[3 * i], ry = a.points[3 * i + 1], z = a.points[3 * i + 2];
    if (z < 0.21 || z > 0.79)
      continue;
    ++wall;
    EXPECT_GT((rx * a.normals[3 * i] + ry * a.normals[3 * i + 1]) / std::hypot(rx, ry), 0.95);
  }
  EXPECT_GT(wall, 500u);
}

TEST(MeshSurfaceSamples, RefusesBadIndicesAndColoursAndGivesNothingForNoArea)
{
  const std::vector<double> p = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::vector<std::int64_t> bad = {0, 1, 3};
  EXPECT_THROW(dp::sampleMeshSurface(surfaceOf(p, bad), 10), std::invalid_argument);
  const std::vector<std::int64_t> good = {0, 1, 2};
  dp::MeshSurface twoChannels = surfaceOf(p, good);
  const std::vector<std::uint8_t> c(6, 0);
  twoChannels.colours = c.data();
  twoChannels.colourComponents = 2;
  EXPECT_THROW(dp::sampleMeshSurface(twoChannels, 10), std::invalid_argument);
  const std::vector<std::int64_t> flat = {0, 1, 1};
  EXPECT_EQ(dp::sampleMeshSurface(surfaceOf(p, flat), 10).numberOfPoints(), 0u);
}

// A take given as meshes much coarser than the template along the tube (5 rings for the
// template's 16): read as its vertices, the data has gaps of a fifth of the tube between rings;
// read as its surface, the tracked mesh lies on the frame's surface.
double trackCoarseMeshes(std::size_t meshFrameSamples)
{
  dp::BendingTube::Options fine, coarse;
  fine.frames = coarse.frames = 30;
  fine.rings = 16;
  fine.segments = coarse.segments = 12;
  coarse.rings = 5;
  fine.maxBendRadians = coarse.maxBendRadians = 1.0;
  fine.maxTwistRadians = coarse.maxTwistRadians = 0.0;
  const dp::BendingTube templateTube(fine), frames(coarse);
  dp::TrackerOptions options = dp::test::tubeOptions();
  options.meshFrameSamples = meshFrameSamples;
  dp::Tracker tracker(dp::TriangleMesh(templateTube.triangles(), templateTube.numberOfVertices()),
                      templateTube.positions(0), options);
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t f = 0; f < 12; f += 1)
  {
    const std::vector<double> positions = frames.positions(f);
    const dp::FrameResult r =
        tracker.track(tracker.prepare(surfaceOf(positions, frames.triangles())));
    const dp::TriangleMesh mesh(frames.triangles(), frames.numberOfVertices());
    const dp::SurfaceLocator locator(mesh, positions.data());
    for (std::size_t v = 0; v < r.positions.size() / 3; ++v, ++count)
      sum += locator.closest(&r.positions[3 * v]).squaredDistance;
  }
  return std::sqrt(sum / static_cast<double>(count));
}

TEST(MeshSurfaceSamples, TheTrackerReadsAMeshFrameAsItsSurface)
{
  const double asVertices = trackCoarseMeshes(0), asSurface = trackCoarseMeshes(3000);
  std::printf("RMS distance to the frames' surfaces: %.5f as vertices, %.5f as surface\n",
              asVertices, asSurface);
  EXPECT_LT(asSurface, 0.5 * asVertices);
}

} // namespace
