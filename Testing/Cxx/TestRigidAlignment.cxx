// SPDX-License-Identifier: BSD-3-Clause
// RigidAlignment: a cube moved by a known rotation and translation is moved back onto its data,
// rigidly; a shape on its data stays; an open cylinder is moved only along what its data pin down
// (across its axis, not along it).
#include "FineMeshShapes.h"
#include "TrackingShapes.h"

#include "dp/track/DistanceTerm.h"
#include "dp/track/RigidAlignment.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <vector>

namespace
{

using dp::test::Frame;
using dp::test::Shape;
using dp::test::vertexRms;

// The icosphere of 642 vertices pushed out onto the cube [-1, 1]^3: its flat faces pin every
// rigid motion, the turns about a quarter as firmly as the moves (on a rounder shape, an
// ellipsoid or a rounded cube, the turns fall under the fifth the alignment asks for).
Shape cube()
{
  const dp::test::Mesh m = dp::test::icosphere(3);
  Shape s{m.triangles, m.positions};
  for (std::size_t i = 0; i < s.positions.size(); i += 3)
  {
    double* p = &s.positions[i];
    const double largest = std::max({std::abs(p[0]), std::abs(p[1]), std::abs(p[2])});
    for (int k = 0; k < 3; ++k)
      p[k] /= largest;
  }
  return s;
}

// An open cylinder of radius 0.3 from z = -1 to 1 (41 rings of 32), faces outward.
Shape openCylinder()
{
  Shape s;
  const int rings = 41, segments = 32;
  for (int r = 0; r < rings; ++r)
    for (int k = 0; k < segments; ++k)
    {
      const double a = 2 * M_PI * k / segments;
      s.positions.insert(s.positions.end(),
                         {0.3 * std::cos(a), 0.3 * std::sin(a), -1 + 2.0 * r / (rings - 1)});
    }
  for (int r = 0; r + 1 < rings; ++r)
    for (int k = 0; k < segments; ++k)
    {
      const std::int64_t a = r * segments + k, b = r * segments + (k + 1) % segments;
      s.triangles.insert(s.triangles.end(), {a, b, b + segments, a, b + segments, a + segments});
    }
  return s;
}

// `x` turned by `angle` about `axis` through its centroid and moved by `t`.
std::vector<double> moved(const std::vector<double>& x, double angle, const Eigen::Vector3d& axis,
                          const Eigen::Vector3d& t)
{
  const std::size_t n = x.size() / 3;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (std::size_t v = 0; v < n; ++v)
    centre += Eigen::Vector3d(&x[3 * v]) / static_cast<double>(n);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  std::vector<double> y(x.size());
  for (std::size_t v = 0; v < n; ++v)
  {
    const Eigen::Vector3d p = R * (Eigen::Vector3d(&x[3 * v]) - centre) + centre + t;
    for (int k = 0; k < 3; ++k)
      y[3 * v + k] = p[k];
  }
  return y;
}

// The largest change of an edge's length between two shapes of the mesh, relative to it.
double largestEdgeChange(const dp::TriangleMesh& mesh, const std::vector<double>& a,
                         const std::vector<double>& b)
{
  double worst = 0;
  for (const auto& [i, j] : mesh.edges())
  {
    const double la = (Eigen::Vector3d(&a[3 * i]) - Eigen::Vector3d(&a[3 * j])).norm();
    const double lb = (Eigen::Vector3d(&b[3 * i]) - Eigen::Vector3d(&b[3 * j])).norm();
    worst = std::max(worst, std::abs(la - lb) / la);
  }
  return worst;
}

TEST(RigidAlignment, AKnownRotationAndTranslationAreUndone)
{
  // The cube's data; the mesh turned 5 degrees and moved by about a voxel: aligned, it is back on
  // the truth, and only moved rigidly on the way.
  const Shape truth = cube();
  Frame f(truth.positions, false, truth);
  dp::DistanceTerm term(*f.data, f.mesh, f.mass, f.L, dp::DistanceTermOptions{});
  const std::vector<double> start =
      moved(truth.positions, 5 * M_PI / 180, {1, 2, 3}, {0.03, -0.02, 0.015});
  std::vector<double> x = start;
  term.decide(x.data());
  const int kept = dp::alignRigidly(x, term);
  EXPECT_GE(kept, 1);
  const double before = vertexRms(start, truth.positions), after = vertexRms(x, truth.positions);
  EXPECT_GT(before, f.voxel);
  EXPECT_LT(after, 0.05 * before) << "from " << before;
  EXPECT_LT(after, 0.1 * f.voxel);
  EXPECT_LT(largestEdgeChange(f.mesh, start, x), 1e-12);
}

TEST(RigidAlignment, AShapeOnItsDataStays)
{
  const Shape truth = cube();
  Frame f(truth.positions, false, truth);
  dp::DistanceTerm term(*f.data, f.mesh, f.mass, f.L, dp::DistanceTermOptions{});
  std::vector<double> x = truth.positions;
  term.decide(x.data());
  dp::alignRigidly(x, term);
  EXPECT_LT(vertexRms(x, truth.positions), 0.05 * f.voxel);
}

TEST(RigidAlignment, AnOpenCylinderMovesAcrossItsAxisOnly)
{
  // Moved across and along its axis: the data pin the sideways offset, which is undone, but say
  // nothing of a slide along the axis (every plane distance is the same), which is kept.
  const Shape truth = openCylinder();
  Frame f(truth.positions, false, truth);
  dp::DistanceTerm term(*f.data, f.mesh, f.mass, f.L, dp::DistanceTermOptions{});
  std::vector<double> x = moved(truth.positions, 0, {0, 0, 1}, {0.04, 0, 0.1});
  term.decide(x.data());
  EXPECT_GE(dp::alignRigidly(x, term), 1);
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  const std::size_t n = x.size() / 3;
  for (std::size_t v = 0; v < n; ++v)
    offset += (Eigen::Vector3d(&x[3 * v]) - Eigen::Vector3d(&truth.positions[3 * v])) /
              static_cast<double>(n);
  EXPECT_LT(std::abs(offset.x()), 0.1 * f.voxel) << "the sideways offset stays";
  EXPECT_LT(std::abs(offset.y()), 0.1 * f.voxel);
  EXPECT_NEAR(offset.z(), 0.1, 0.1 * f.voxel) << "the slide along the axis was undone";
}

} // namespace
