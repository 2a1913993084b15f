// SPDX-License-Identifier: BSD-3-Clause
// Handles cut where they are thinnest (dp/geometry/HandleRemoval.h).
#include "dp/geometry/HandleRemoval.h"

#include <gtest/gtest.h>

#include <cmath>

namespace
{

constexpr double Pi = 3.141592653589793;

// A torus about the z axis, radii R and r, oriented outward.
dp::support::IndexedMesh torus(double R, double r, int nu = 48, int nv = 24)
{
  dp::support::IndexedMesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j)
    {
      const double u = 2 * Pi * i / nu, v = 2 * Pi * j / nv;
      m.positions.push_back({(R + r * std::cos(v)) * std::cos(u),
                             (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
      const int a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = ((i + 1) % nu) * nv + (j + 1) % nv,
                d = i * nv + (j + 1) % nv;
      m.triangles.push_back({a, b, c});
      m.triangles.push_back({a, c, d});
    }
  return m;
}

} // namespace

// A torus is cut across its tube (the loop around the tube, 2 pi r, is shorter than the one
// around the hole, 2 pi (R - r)): genus 0, still closed, nothing moved but the caps' centres.
TEST(HandleRemoval, ATorusIsCutAcrossItsTubeIntoASphere)
{
  dp::support::IndexedMesh m = torus(1.0, 0.25);
  ASSERT_EQ(dp::support::genusOf(m), 1);
  const std::size_t vertices = m.positions.size();
  dp::support::IndexedMesh kept = m;
  EXPECT_EQ(dp::support::removeHandles(kept, 1.5), 0u) << "the tube's loop is 2 pi 0.25 long";
  EXPECT_EQ(dp::support::genusOf(kept), 1);
  EXPECT_EQ(dp::support::removeHandles(m, 2.0), 1u) << "around the hole, 2 pi 0.75";
  EXPECT_EQ(dp::support::genusOf(m), 0);
  // The loop cut runs around the tube (24 vertices; around the hole, 48): its copies and the two
  // caps' centres are the vertices added.
  EXPECT_GE(m.positions.size(), vertices + 24 + 2);
  EXPECT_LE(m.positions.size(), vertices + 28 + 2);
}

// A sphere has no handle to cut; an open mesh is left as it is.
TEST(HandleRemoval, NoHandleNothingCutAndAnOpenMeshLeftAlone)
{
  dp::support::IndexedMesh open = torus(1.0, 0.25);
  open.triangles.resize(open.triangles.size() - 2);
  EXPECT_EQ(dp::support::genusOf(open), -1);
  EXPECT_EQ(dp::support::removeHandles(open, 10), 0u);
}
