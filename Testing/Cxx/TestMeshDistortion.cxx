// SPDX-License-Identifier: BSD-3-Clause
// D1 / D2 PSNR of a mesh against a frame's own mesh (meshDistortion), on surfaces whose errors
// are known in closed form.
#include "dp/geometry/MeshDistortion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <tbb/global_control.h>
#include <vector>

namespace
{

// The rectangle [0, w] x [0, 1] at height z, as an n x n grid of triangle pairs.
struct Rectangle
{
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;

  Rectangle(double w, double z, int n = 8)
  {
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i)
        positions.insert(positions.end(), {w * i / n, static_cast<double>(j) / n, z});
    const auto at = [n](int i, int j) { return static_cast<std::int64_t>(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        triangles.insert(triangles.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j),
                                           at(i + 1, j + 1), at(i, j + 1)});
  }
  dp::MeshSurface surface() const
  {
    dp::MeshSurface s;
    s.positions = positions.data();
    s.vertices = positions.size() / 3;
    s.triangles = triangles.data();
    s.triangleCount = triangles.size() / 3;
    return s;
  }
};

TEST(MeshDistortion, NoErrorForTheSameSurfaceWhateverItsTriangles)
{
  const Rectangle a(1, 0, 8), b(1, 0, 3);
  const dp::MeshDistortion d = dp::meshDistortion(a.surface(), b.surface(), 5000);
  EXPECT_LT(d.d1, 1e-20);
  EXPECT_LT(d.d2, 1e-20);
  EXPECT_NEAR(d.peak, std::sqrt(2.0), 1e-12);
  EXPECT_GT(d.d1Psnr(), 150);
}

TEST(MeshDistortion, AnOffsetAlongTheNormalCountsInBothMeasures)
{
  const Rectangle a(1, 0), b(1, 0.01);
  const dp::MeshDistortion d = dp::meshDistortion(a.surface(), b.surface(), 4000);
  EXPECT_NEAR(d.d1, 1e-4, 1e-9);
  EXPECT_NEAR(d.d2, 1e-4, 1e-9);
  EXPECT_NEAR(d.d1Psnr(), 10 * std::log10(2.0 / 1e-4), 1e-4);
}

TEST(MeshDistortion, AMissingPartCountsInD1FromTheReferenceSideAndNotAlongTheNormal)
{
  // Half of the reference is missing from the test mesh: the reference's samples on it are
  // x - 0.5 (uniform in [0, 0.5]) from the test's edge: mean square 1/12 on half the samples.
  const Rectangle whole(1, 0), half(0.5, 0);
  const dp::MeshDistortion d = dp::meshDistortion(whole.surface(), half.surface(), 20000);
  EXPECT_NEAR(d.d1, 1.0 / 24, 1e-3);
  EXPECT_LT(d.d2, 1e-20); // the error lies in the plane
  // The other way round the worse direction is the same one.
  const dp::MeshDistortion e = dp::meshDistortion(half.surface(), whole.surface(), 20000);
  EXPECT_NEAR(e.d1, 1.0 / 24, 1e-3);
  EXPECT_NEAR(e.peak, std::hypot(0.5, 1.0), 1e-12);
}

TEST(MeshDistortion, TheSameFiguresOnOneThreadAndRefusesAMeshWithoutArea)
{
  const Rectangle a(1, 0), b(0.7, 0.02, 5);
  const dp::MeshDistortion many = dp::meshDistortion(a.surface(), b.surface(), 9000);
  dp::MeshDistortion one;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = dp::meshDistortion(a.surface(), b.surface(), 9000);
  }
  EXPECT_EQ(many.d1, one.d1);
  EXPECT_EQ(many.d2, one.d2);
  Rectangle flat(1, 0);
  for (std::size_t i = 1; i < flat.positions.size(); i += 3)
    flat.positions[i] = 0; // every vertex on the x axis
  EXPECT_THROW(dp::meshDistortion(flat.surface(), a.surface(), 100), std::invalid_argument);
  EXPECT_THROW(dp::meshDistortion(a.surface(), flat.surface(), 100), std::invalid_argument);
}

} // namespace
