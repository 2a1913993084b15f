// SPDX-License-Identifier: BSD-3-Clause
// The template made from a take (dp::makeTemplate): each repair of a capture's mesh on its own
// and all at once, the remeshing to the count asked, a user's mesh never remeshed, a surface
// from points, and the errors that name the source and the reason.
#include "dp/field/TemplateMesh.h"
#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/geometry/TriangleMesh.h"

#include <gtest/gtest.h>

#include <cmath>

namespace
{

// A closed UV sphere of radius 0.5, `rings` x `segments`, as a capture's mesh would be.
struct Mesh
{
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;
  std::size_t vertices() const { return positions.size() / 3; }
};

Mesh sphere(std::size_t rings, std::size_t segments)
{
  Mesh m;
  m.positions = {0.0, 0.0, 0.5};
  for (std::size_t i = 1; i < rings; ++i)
    for (std::size_t j = 0; j < segments; ++j)
    {
      const double theta = M_PI * static_cast<double>(i) / static_cast<double>(rings);
      const double phi = 2 * M_PI * static_cast<double>(j) / static_cast<double>(segments);
      m.positions.insert(m.positions.end(),
                         {0.5 * std::sin(theta) * std::cos(phi),
                          0.5 * std::sin(theta) * std::sin(phi), 0.5 * std::cos(theta)});
    }
  m.positions.insert(m.positions.end(), {0.0, 0.0, -0.5});
  const auto ring = [&](std::size_t i, std::size_t j)
  { return static_cast<std::int64_t>(1 + (i - 1) * segments + j % segments); };
  const auto south = static_cast<std::int64_t>(m.vertices() - 1);
  for (std::size_t j = 0; j < segments; ++j)
  {
    m.triangles.insert(m.triangles.end(), {0, ring(1, j), ring(1, j + 1)});
    m.triangles.insert(m.triangles.end(), {south, ring(rings - 1, j + 1), ring(rings - 1, j)});
    for (std::size_t i = 1; i + 1 < rings; ++i)
    {
      m.triangles.insert(m.triangles.end(), {ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      m.triangles.insert(m.triangles.end(), {ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  }
  return m;
}

// The defects a capture's mesh has, one kind at a time.
void addDuplicateVertex(Mesh& m) // vertex 5 again, triangle 0 using the copy
{
  m.positions.insert(m.positions.end(), &m.positions[3 * 5], &m.positions[3 * 5] + 3);
  for (std::int64_t& v : m.triangles)
    if (v == 5)
    {
      v = static_cast<std::int64_t>(m.vertices() - 1);
      break;
    }
}
void addDegenerateTriangles(Mesh& m) // a triangle on one edge, one with a repeated corner
{
  m.triangles.insert(m.triangles.end(), {3, 4, 4});
  const std::int64_t a = m.triangles[3], b = m.triangles[4];
  m.positions.insert(m.positions.end(), {0.5 * (m.positions[3 * a] + m.positions[3 * b]),
                                         0.5 * (m.positions[3 * a + 1] + m.positions[3 * b + 1]),
                                         0.5 * (m.positions[3 * a + 2] + m.positions[3 * b + 2])});
  m.triangles.insert(m.triangles.end(), {a, b, static_cast<std::int64_t>(m.vertices() - 1)});
}
void addRepeatedTriangle(Mesh& m)
{
  m.triangles.insert(m.triangles.end(), {m.triangles[7], m.triangles[8], m.triangles[6]});
}
void addStrayPart(Mesh& m) // a speck: one small triangle far off
{
  const auto n = static_cast<std::int64_t>(m.vertices());
  m.positions.insert(m.positions.end(), {2, 0, 0, 2.01, 0, 0, 2, 0.01, 0});
  m.triangles.insert(m.triangles.end(), {n, n + 1, n + 2});
}

dp::TemplateMesh make(const Mesh& m, std::size_t target = 100000, bool remesh = true)
{
  dp::TemplateOptions o;
  o.targetVertices = target;
  o.remesh = remesh;
  return dp::makeTemplate(m.positions.data(), m.vertices(), nullptr, m.triangles, o,
                          "frame 0's mesh");
}

// The tracker's own checks: every triangle has area.
void expectTrackable(const dp::TemplateMesh& t)
{
  const dp::TriangleMesh mesh(t.triangles, t.positions.size() / 3);
  EXPECT_GT(mesh.totalArea(t.positions.data()), 0);
  for (std::size_t i = 0; i < t.triangles.size(); i += 3)
  {
    EXPECT_NE(t.triangles[i], t.triangles[i + 1]);
    EXPECT_NE(t.triangles[i + 1], t.triangles[i + 2]);
    EXPECT_NE(t.triangles[i], t.triangles[i + 2]);
  }
}

TEST(TemplateMesh, ACleanMeshIsUsedAsItIs)
{
  const Mesh m = sphere(12, 16);
  const dp::TemplateMesh t = make(m);
  EXPECT_EQ(t.positions, m.positions);
  EXPECT_EQ(t.triangles, m.triangles);
  EXPECT_FALSE(t.report.remeshed);
  EXPECT_EQ(t.report.summary(),
            "frame 0's mesh: used as it is (" + std::to_string(m.vertices()) + " vertices)");
}

TEST(TemplateMesh, EachRepairOnItsOwnAndAllAtOnce)
{
  const Mesh clean = sphere(12, 16);
  struct Case
  {
    void (*defect)(Mesh&);
    std::size_t dp::TemplateReport::*count;
    std::size_t expected;
    const char* said;
  };
  const Case cases[] = {{addDuplicateVertex, &dp::TemplateReport::duplicateVertices, 1,
                         "1 duplicate vertices merged"},
                        {addDegenerateTriangles, &dp::TemplateReport::degenerateTriangles, 2,
                         "2 triangles without area removed"},
                        {addRepeatedTriangle, &dp::TemplateReport::duplicateTriangles, 1,
                         "1 repeated triangles removed"},
                        {addStrayPart, &dp::TemplateReport::smallPartTriangles, 1,
                         "1 triangles of small stray parts removed"}};
  Mesh all = clean;
  for (const Case& c : cases)
  {
    Mesh m = clean;
    c.defect(m);
    c.defect(all);
    const dp::TemplateMesh t = make(m);
    EXPECT_EQ(t.report.*c.count, c.expected) << c.said;
    EXPECT_NE(t.report.summary().find(c.said), std::string::npos) << t.report.summary();
    // The repair gives the clean sphere back: its triangles, on its vertices.
    EXPECT_EQ(t.triangles.size(), clean.triangles.size()) << c.said;
    EXPECT_EQ(t.positions.size(), clean.positions.size()) << c.said;
    expectTrackable(t);
  }
  const dp::TemplateMesh t = make(all);
  for (const Case& c : cases)
    EXPECT_EQ(t.report.*c.count, c.expected) << c.said;
  EXPECT_EQ(t.triangles.size(), clean.triangles.size());
  EXPECT_EQ(t.positions.size(), clean.positions.size());
  EXPECT_EQ(t.report.trianglesGiven, clean.triangles.size() / 3 + 4);
  expectTrackable(t);
}

TEST(TemplateMesh, AMeshLargerThanAskedIsRemeshedToTheCountAUsersMeshIsNot)
{
  const Mesh fine = sphere(60, 80); // 4742 vertices
  Mesh defective = fine;
  addDegenerateTriangles(defective);
  const dp::TemplateMesh t = make(defective, 1000);
  EXPECT_TRUE(t.report.remeshed);
  EXPECT_NEAR(static_cast<double>(t.report.vertices), 1000.0, 100.0); // within 10 %
  EXPECT_NE(t.report.summary().find("2 triangles without area removed"), std::string::npos)
      << t.report.summary();
  EXPECT_NE(t.report.summary().find("remeshed from " + std::to_string(defective.vertices()) +
                                    " to " + std::to_string(t.report.vertices) + " vertices"),
            std::string::npos)
      << t.report.summary();
  expectTrackable(t);
  // On the sphere still.
  for (std::size_t i = 0; i < t.positions.size(); i += 3)
    EXPECT_NEAR(std::sqrt(t.positions[i] * t.positions[i] +
                          t.positions[i + 1] * t.positions[i + 1] +
                          t.positions[i + 2] * t.positions[i + 2]),
                0.5, 0.002);
  // A user's mesh keeps its resolution: repaired only.
  const dp::TemplateMesh user = make(defective, 1000, false);
  EXPECT_FALSE(user.report.remeshed);
  EXPECT_EQ(user.report.vertices, fine.vertices());
  EXPECT_EQ(user.report.degenerateTriangles, 2u);
  // Smaller than asked: kept, not refined.
  EXPECT_FALSE(make(sphere(12, 16), 1000).report.remeshed);
}

TEST(TemplateMesh, FromPointsASurfaceIsReconstructed)
{
  const Mesh m = sphere(40, 60);
  dp::SamplerOptions s;
  s.pointsPerFrame = 8000;
  const dp::PointCloud c = dp::sampleSurface(m.positions, m.triangles, s, 0);
  dp::TemplateOptions o;
  o.targetVertices = 500;
  o.source = dp::TemplateSource::Points;
  // Points win over the triangles when asked.
  const dp::TemplateMesh t = dp::makeTemplate(c.points.data(), c.numberOfPoints(), c.normals.data(),
                                              {}, o, "frame 0's mesh");
  EXPECT_TRUE(t.report.reconstructed);
  EXPECT_NEAR(static_cast<double>(t.report.vertices), 500.0, 50.0);
  EXPECT_EQ(t.report.summary(), "frame 0's points: a surface of " +
                                    std::to_string(t.report.vertices) +
                                    " vertices reconstructed from 8000 points");
  expectTrackable(t);
}

TEST(TemplateMesh, WhatCannotBeATemplateIsNamedWithTheReason)
{
  const auto message = [](const Mesh& m, dp::TemplateSource source)
  {
    dp::TemplateOptions o;
    o.source = source;
    try
    {
      dp::makeTemplate(m.positions.data(), m.vertices(), nullptr, m.triangles, o, "frame 0's mesh");
    }
    catch (const std::invalid_argument& e)
    {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  Mesh flat;
  flat.positions = {0, 0, 0, 1, 0, 0, 2, 0, 0, 3, 0, 0};
  flat.triangles = {0, 1, 2, 1, 2, 3, 0, 0, 1};
  EXPECT_EQ(message(flat, dp::TemplateSource::Auto),
            "frame 0's mesh has no usable triangle: all 3 have no area or repeat others (give a "
            "template mesh, or track from the points)");
  Mesh outOfRange = sphere(6, 8);
  outOfRange.triangles[4] = 999;
  EXPECT_EQ(message(outOfRange, dp::TemplateSource::Auto),
            "frame 0's mesh: triangle index 999 is out of range (" +
                std::to_string(outOfRange.vertices()) + " vertices)");
  Mesh none = sphere(6, 8);
  none.triangles.clear();
  EXPECT_EQ(message(none, dp::TemplateSource::Mesh),
            "frame 0's mesh has no triangles (track from the points instead)");
  Mesh notANumber = sphere(6, 8);
  notANumber.positions[7] = std::nan("");
  EXPECT_EQ(message(notANumber, dp::TemplateSource::Auto),
            "frame 0's mesh: a vertex has a NaN or infinite coordinate");
}

} // namespace
