// SPDX-License-Identifier: BSD-3-Clause
// The distance field against brute-force nearest-point search, its gradient against finite
// differences, continuity across voxel faces, out-of-band behaviour, and bad input.
#include "dp/field/DistanceField.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>
#include <random>

namespace
{

struct Cloud
{
  std::vector<double> points;
  std::vector<float> normals;
};

Cloud randomCloud(std::size_t n, unsigned seed)
{
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Cloud c;
  for (std::size_t i = 0; i < 3 * n; ++i)
    c.points.push_back(u(rng));
  return c;
}

Cloud tubeCloud(std::size_t n, std::size_t frame = 7)
{
  dp::BendingTube tube;
  dp::SamplerOptions o;
  o.pointsPerFrame = n;
  const dp::PointCloud pc = dp::sampleSurface(tube.positions(frame), tube.triangles(), o, frame);
  return {pc.points, pc.normals};
}

double bruteForce(const std::vector<double>& pts, const double x[3], std::int64_t* index = nullptr)
{
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < pts.size(); i += 3)
  {
    const double d = std::hypot(x[0] - pts[i], x[1] - pts[i + 1], x[2] - pts[i + 2]);
    if (d < best)
    {
      best = d;
      if (index)
        *index = static_cast<std::int64_t>(i / 3);
    }
  }
  return best;
}

// Query points near the cloud: data points displaced by up to `reach` in each coordinate.
std::vector<double> queriesNear(const std::vector<double>& pts, double reach, std::size_t n,
                                unsigned seed)
{
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, pts.size() / 3 - 1);
  std::uniform_real_distribution<double> u(-reach, reach);
  std::vector<double> q;
  for (std::size_t i = 0; i < n; ++i)
  {
    const std::size_t p = pick(rng);
    for (int k = 0; k < 3; ++k)
      q.push_back(pts[3 * p + k] + u(rng));
  }
  return q;
}

struct ErrorStats
{
  double max = 0, rms = 0;
};

ErrorStats distanceError(const dp::DistanceField& field, const std::vector<double>& pts,
                         const std::vector<double>& queries)
{
  ErrorStats e;
  const std::size_t n = queries.size() / 3;
  for (std::size_t i = 0; i < n; ++i)
  {
    const double* x = &queries[3 * i];
    const double err = field.sample(x).distance - bruteForce(pts, x);
    e.max = std::max(e.max, std::abs(err));
    e.rms += err * err;
  }
  e.rms = std::sqrt(e.rms / static_cast<double>(n));
  return e;
}

// 2 cm voxels and a 10 cm band: about a voxel per sample spacing of tubeCloud(5000).
dp::DistanceFieldOptions tubeFieldOptions()
{
  dp::DistanceFieldOptions o;
  o.voxelSize = 0.02;
  o.bandWidth = 0.1;
  return o;
}

TEST(DistanceField, MatchesBruteForceOnARandomCloud)
{
  const Cloud c = randomCloud(3000, 1);
  dp::DistanceFieldOptions o;
  o.voxelSize = 0.05;
  o.bandWidth = 0.2;
  dp::DistanceField field;
  field.build(c.points.data(), 3000, o);
  EXPECT_GT(field.activeVoxelCount(), 1000u);
  const ErrorStats e = distanceError(field, c.points, queriesNear(c.points, 0.15, 2000, 2));
  // Bounds in voxels: trilinear interpolation of exact distances at the voxel centres.
  EXPECT_LT(e.max, 0.75 * o.voxelSize);
  EXPECT_LT(e.rms, 0.2 * o.voxelSize);
}

TEST(DistanceField, MatchesBruteForceOnASurfaceSampledCloud)
{
  const Cloud c = tubeCloud(20000);
  dp::DistanceFieldOptions o;
  o.voxelSize = 0.01;
  o.bandWidth = 0.05;
  dp::DistanceField field;
  field.build(c.points.data(), c.points.size() / 3, o);
  const ErrorStats e = distanceError(field, c.points, queriesNear(c.points, 0.04, 2000, 3));
  EXPECT_LT(e.max, 0.75 * o.voxelSize);
  EXPECT_LT(e.rms, 0.2 * o.voxelSize);

  // The index stored in every voxel is the true nearest point of its centre.
  std::size_t checked = 0, exact = 0;
  double worst = 0;
  for (int i = -15; i <= 15; i += 1)
    for (int j = -15; j <= 15; j += 1)
      for (int k = 0; k <= 100; k += 3)
      {
        const std::int64_t stored = field.voxelNearest(i, j, k);
        if (stored < 0)
          continue;
        const double x[3] = {i * o.voxelSize, j * o.voxelSize, k * o.voxelSize};
        const double* p = &c.points[3 * stored];
        const double excess =
            std::hypot(x[0] - p[0], x[1] - p[1], x[2] - p[2]) - bruteForce(c.points, x);
        ++checked;
        exact += excess < 1e-12;
        worst = std::max(worst, excess);
      }
  ASSERT_GT(checked, 1000u);
  EXPECT_EQ(exact, checked);
  EXPECT_LT(worst, 1e-12);
}

TEST(DistanceField, GradientIsTheDerivativeOfTheDistance)
{
  const Cloud c = tubeCloud(5000);
  const dp::DistanceFieldOptions o = tubeFieldOptions();
  dp::DistanceField field;
  field.build(c.points.data(), c.points.size() / 3, o);
  const std::vector<double> q = queriesNear(c.points, 0.15, 500, 4);
  const double h = 1e-6;
  std::size_t unitLength = 0, far = 0;
  for (std::size_t i = 0; i < q.size() / 3; ++i)
  {
    const double* x = &q[3 * i];
    const dp::DistanceSample s = field.sample(x);
    for (int k = 0; k < 3; ++k)
    {
      double a[3] = {x[0], x[1], x[2]}, b[3] = {x[0], x[1], x[2]};
      a[k] += h;
      b[k] -= h;
      const double fd = (field.sample(a).distance - field.sample(b).distance) / (2 * h);
      EXPECT_NEAR(s.gradient[k], fd, 1e-5) << "query " << i << " axis " << k;
    }
    std::int64_t nearest = -1;
    const double truth = bruteForce(c.points, x, &nearest);
    if (truth > 2 * o.voxelSize)
    {
      // Two voxels and more from the data the gradient is close to the true one: about unit
      // length, pointing away from the nearest point. (Nearer, the direction to the nearest
      // sample is itself noise across the sampled surface.)
      ++far;
      const double* p = &c.points[3 * nearest];
      const double g = std::hypot(s.gradient[0], s.gradient[1], s.gradient[2]);
      const double cosine = (s.gradient[0] * (x[0] - p[0]) + s.gradient[1] * (x[1] - p[1]) +
                             s.gradient[2] * (x[2] - p[2])) /
                            (g * truth);
      unitLength += std::abs(g - 1) < 0.15 && cosine > 0.9;
    }
  }
  ASSERT_GT(far, 50u);
  EXPECT_GT(static_cast<double>(unitLength) / static_cast<double>(far), 0.9);
}

TEST(DistanceField, PlaneDistanceHasItsDerivativeAsGradientAndIsFlatAlongTheData)
{
  const Cloud c = tubeCloud(5000);
  const dp::DistanceFieldOptions o = tubeFieldOptions();
  dp::DistanceField field;
  field.build(c.points.data(), c.points.size() / 3, o);
  const double reach = 2 * o.voxelSize;
  const std::vector<double> q = queriesNear(c.points, 0.15, 300, 5);
  const double h = 1e-7;
  for (std::size_t i = 0; i < q.size() / 3; ++i)
  {
    const double* x = &q[3 * i];
    dp::VoxelCell cell;
    const dp::DistanceSample s = field.sampleToPlanes(x, c.normals.data(), reach, &cell);
    // The cached cell gives the same answer as a fresh lookup.
    const dp::DistanceSample again = field.sampleToPlanes(x, c.normals.data(), reach, &cell);
    const dp::DistanceSample fresh = field.sampleToPlanes(x, c.normals.data(), reach);
    EXPECT_EQ(again.distance, fresh.distance);
    EXPECT_EQ(s.distance, fresh.distance);
    for (int k = 0; k < 3; ++k)
    {
      double a[3] = {x[0], x[1], x[2]}, b[3] = {x[0], x[1], x[2]};
      a[k] += h;
      b[k] -= h;
      const double fd = (field.sampleToPlanes(a, c.normals.data(), reach).distance -
                         field.sampleToPlanes(b, c.normals.data(), reach).distance) /
                        (2 * h);
      // The slope of the trilinear weights jumps across voxel faces: where the central
      // difference straddles one, compare with a one-sided difference instead.
      if (std::abs(fd - s.gradient[k]) > 1e-4)
      {
        double a2[3] = {x[0], x[1], x[2]};
        a2[k] += 1e-3 * h;
        const double fdSmall =
            (field.sampleToPlanes(a2, c.normals.data(), reach).distance - s.distance) / (1e-3 * h);
        EXPECT_NEAR(s.gradient[k], fdSmall, 1e-3) << "query " << i << " axis " << k;
      }
    }
  }
  // On the data itself the point distance is up to half a sample spacing, the plane distance
  // much less: the mesh is not pulled toward individual samples.
  double points = 0, planes = 0;
  const dp::BendingTube tube;
  const std::vector<double> surface = tube.positions(7);
  for (std::size_t v = 0; v < surface.size() / 3; ++v)
  {
    points += field.sample(&surface[3 * v]).distance;
    planes += field.sampleToPlanes(&surface[3 * v], c.normals.data(), reach).distance;
  }
  EXPECT_LT(planes, 0.5 * points);
}

TEST(DistanceField, PlaneQuadricIsTheGaussNewtonModelOfTheSquaredDistance)
{
  // One point: every voxel corner shares it, so D^2 = (n.(x - p))^2 + max(0, |x - p| - reach)^2
  // whatever the weights, and the quadric must reproduce it: value, gradient, and (within
  // reach, where D^2 is a quadratic) every displacement exactly.
  const double p[3] = {0.31, -0.12, 0.07};
  const float n[3] = {0.6f, 0.0f, 0.8f};
  const double voxel = 0.05, reach = 2 * voxel;
  dp::DistanceFieldOptions o;
  o.voxelSize = voxel;
  dp::DistanceField field;
  field.build(p, 1, o);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 50; ++trial)
  {
    const double scale = trial < 25 ? 0.05 : 0.5; // within reach, then far beyond it
    const double x[3] = {p[0] + scale * u(rng), p[1] + scale * u(rng), p[2] + scale * u(rng)};
    dp::PlaneQuadric q;
    const dp::DistanceSample s = field.sampleToPlanes(x, n, reach, nullptr, &q);
    EXPECT_NEAR(q.constant, s.distance * s.distance, 1e-12);
    const double zero[3] = {0, 0, 0};
    EXPECT_NEAR(q(zero), q.constant, 1e-15);
    const double h = 1e-6;
    for (int k = 0; k < 3; ++k)
    {
      double a[3] = {x[0], x[1], x[2]}, b[3] = {x[0], x[1], x[2]};
      a[k] += h;
      b[k] -= h;
      const double da = field.sampleToPlanes(a, n, reach).distance;
      const double db = field.sampleToPlanes(b, n, reach).distance;
      EXPECT_NEAR(2 * q.vector[k], (da * da - db * db) / (2 * h), 1e-6) << trial;
    }
    // The matrix is positive semidefinite: the model never promises an unbounded decrease.
    for (int k = 0; k < 20; ++k)
    {
      const double d[3] = {u(rng), u(rng), u(rng)};
      const double quadratic =
          q(d) - q.constant - 2 * (q.vector[0] * d[0] + q.vector[1] * d[1] + q.vector[2] * d[2]);
      EXPECT_GE(quadratic, -1e-12);
    }
    if (trial < 25 && std::sqrt((x[0] - p[0]) * (x[0] - p[0]) + (x[1] - p[1]) * (x[1] - p[1]) +
                                (x[2] - p[2]) * (x[2] - p[2])) < 0.5 * reach)
    {
      const double d[3] = {0.01 * u(rng), 0.01 * u(rng), 0.01 * u(rng)};
      const double y[3] = {x[0] + d[0], x[1] + d[1], x[2] + d[2]};
      const double at = field.sampleToPlanes(y, n, reach).distance;
      EXPECT_NEAR(q(d), at * at, 1e-12) << trial;
    }
  }
}

TEST(DistanceField, PlaneDistanceHasNoFalseZeroBetweenTwoSheets)
{
  // Two parallel sheets of points 6 voxels apart with opposite normals (the two sides of a
  // thin part): halfway between them, no plane passes, so D must be about the half gap, not 0.
  std::vector<double> points;
  std::vector<float> normals;
  const double voxel = 0.01, gap = 6 * voxel;
  for (int i = -20; i <= 20; ++i)
    for (int j = -20; j <= 20; ++j)
      for (int side = 0; side < 2; ++side)
      {
        points.insert(points.end(), {0.5 * voxel * i, 0.5 * voxel * j, side ? gap : 0.0});
        normals.insert(normals.end(), {0.0f, 0.0f, side ? 1.0f : -1.0f});
      }
  dp::DistanceFieldOptions o;
  o.voxelSize = voxel;
  o.bandWidth = 4 * voxel;
  dp::DistanceField field;
  field.build(points.data(), points.size() / 3, o);
  for (double z : {0.45 * gap, 0.5 * gap, 0.55 * gap})
  {
    const double x[3] = {0.0123, -0.0077, z};
    const double d = field.sampleToPlanes(x, normals.data(), 10 * voxel).distance;
    EXPECT_NEAR(d, std::min(z, gap - z), 0.6 * voxel) << z;
  }
  // On a sheet, D is ~0.
  const double on[3] = {0.0123, -0.0077, 0.0};
  EXPECT_LT(field.sampleToPlanes(on, normals.data(), 10 * voxel).distance, 1e-9);
}

TEST(DistanceField, IsContinuousAcrossVoxelFaces)
{
  const Cloud c = randomCloud(500, 5);
  dp::DistanceFieldOptions o;
  o.voxelSize = 0.1;
  o.bandWidth = 0.3;
  dp::DistanceField field;
  field.build(c.points.data(), 500, o);
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  const double eps = 1e-9;
  for (int trial = 0; trial < 3000; ++trial)
  {
    double x[3] = {u(rng), u(rng), u(rng)};
    const int axis = trial % 3;
    x[axis] = o.voxelSize * std::round(x[axis] / o.voxelSize); // on a face between cells
    double a[3] = {x[0], x[1], x[2]}, b[3] = {x[0], x[1], x[2]};
    a[axis] -= eps;
    b[axis] += eps;
    EXPECT_NEAR(field.sample(a).distance, field.sample(b).distance, 10 * eps) << "trial " << trial;
  }
}

TEST(DistanceField, OutsideTheBandItStillPullsTowardTheData)
{
  const Cloud c = tubeCloud(5000);
  dp::DistanceFieldOptions o;
  o.voxelSize = 0.02;
  o.bandWidth = 0.06;
  dp::DistanceField field;
  field.build(c.points.data(), c.points.size() / 3, o);
  for (const auto& far :
       std::vector<std::array<double, 3>>{{2.0, 0.3, 0.5}, {-1, -1, -1}, {0, 0, 3}})
  {
    const dp::DistanceSample s = field.sample(far.data());
    EXPECT_FALSE(s.inBand);
    std::int64_t nearest = -1;
    const double truth = bruteForce(c.points, far.data(), &nearest);
    EXPECT_NEAR(s.distance, truth, o.voxelSize);
    const double g = std::hypot(s.gradient[0], s.gradient[1], s.gradient[2]);
    EXPECT_NEAR(g, 1.0, 0.01);
    // Descending the gradient moves toward the nearest data point.
    const double* p = &c.points[3 * nearest];
    const double toData[3] = {p[0] - far[0], p[1] - far[1], p[2] - far[2]};
    EXPECT_LT(s.gradient[0] * toData[0] + s.gradient[1] * toData[1] + s.gradient[2] * toData[2], 0);
  }
  // The edge of the band is no cliff either: along a line from inside the band to far
  // outside, the field changes no faster than a distance can (1-Lipschitz, with slack).
  const double* start = &c.points[0];
  const double step = 0.002;
  double previous = field.sample(start).distance;
  for (int i = 1; i < 300; ++i)
  {
    const double x[3] = {start[0] + 0.6 * i * step, start[1] - 0.5 * i * step,
                         start[2] + 0.62 * i * step};
    const double d = field.sample(x).distance;
    EXPECT_LE(std::abs(d - previous), 1.05 * step) << "step " << i;
    previous = d;
  }
  EXPECT_GT(previous, o.bandWidth) << "the line left the band";
}

TEST(DistanceField, WorksAtAnyScale)
{
  // The same cloud in metres and in micrometres-sized units: the same field, scaled.
  const Cloud c = randomCloud(500, 11);
  for (double scale : {1e-4, 1.0, 1e4})
  {
    std::vector<double> scaled(c.points);
    for (double& x : scaled)
      x *= scale;
    dp::DistanceFieldOptions o;
    o.voxelSize = 0.05 * scale;
    dp::DistanceField field;
    field.build(scaled.data(), 500, o);
    const double unit[3] = {0.1, 0.2, -0.3};
    const double x[3] = {unit[0] * scale, unit[1] * scale, unit[2] * scale};
    EXPECT_NEAR(field.sample(x).distance / scale, bruteForce(c.points, unit), 0.75 * 0.05)
        << "scale " << scale;
  }
}

TEST(DistanceField, LazyModeGivesTheSameFieldAsTheGrid)
{
  const Cloud c = tubeCloud(5000);
  dp::DistanceFieldOptions o;
  o.voxelSize = 0.02;
  o.bandWidth = 0.06;
  dp::DistanceField eager, lazy;
  eager.build(c.points.data(), c.points.size() / 3, o);
  o.lazy = true;
  lazy.build(c.points.data(), c.points.size() / 3, o);
  EXPECT_EQ(lazy.activeVoxelCount(), 0u);
  // Lazy mode has no grid: its memory is the kd-tree and points until voxels are filled.
  const std::size_t bytesBefore = lazy.memoryBytes();
  EXPECT_GE(bytesBefore, c.points.size() * sizeof(double));
  const std::vector<double> q = queriesNear(c.points, 0.1, 3000, 12);
  std::vector<dp::DistanceSample> many(q.size() / 3);
  lazy.sampleMany(q.data(), many.size(), many.data()); // concurrent first uses
  for (std::size_t i = 0; i < many.size(); ++i)
  {
    const dp::DistanceSample a = eager.sample(&q[3 * i]), b = lazy.sample(&q[3 * i]);
    ASSERT_EQ(a.distance, b.distance) << i;
    ASSERT_EQ(a.nearest, b.nearest);
    ASSERT_EQ(a.inBand, b.inBand);
    ASSERT_EQ(many[i].distance, b.distance);
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(a.gradient[k], b.gradient[k]);
  }
  EXPECT_GT(lazy.activeVoxelCount(), 100u);
  EXPECT_LT(lazy.activeVoxelCount(), eager.activeVoxelCount() * 2);
  EXPECT_EQ(lazy.voxelNearest(0, 0, 0), eager.voxelNearest(0, 0, 0));
  // Filled voxels live in blocks: at least a 4-byte slot each.
  EXPECT_GE(lazy.memoryBytes(), bytesBefore + 4 * lazy.activeVoxelCount());
}

TEST(DistanceField, ParallelSamplingEqualsSerialSampling)
{
  const Cloud c = tubeCloud(4000);
  dp::DistanceFieldOptions o;
  o.voxelSize = 0.02;
  dp::DistanceField field;
  field.build(c.points.data(), c.points.size() / 3, o);
  const std::vector<double> q = queriesNear(c.points, 0.3, 20000, 8);
  std::vector<dp::DistanceSample> many(q.size() / 3);
  field.sampleMany(q.data(), many.size(), many.data());
  for (std::size_t i = 0; i < many.size(); i += 7)
  {
    const dp::DistanceSample one = field.sample(&q[3 * i]);
    EXPECT_EQ(one.distance, many[i].distance);
    EXPECT_EQ(one.nearest, many[i].nearest);
  }
}

TEST(DistanceField, BadInputIsRefusedClearly)
{
  dp::DistanceField field;
  dp::DistanceFieldOptions o;
  o.voxelSize = 0.1;
  const double one[3] = {0, 0, 0};
  EXPECT_THROW(field.build(one, 0, o), std::invalid_argument);
  const double nan[6] = {0, 0, 0, 1, std::numeric_limits<double>::quiet_NaN(), 0};
  try
  {
    field.build(nan, 2, o);
    ADD_FAILURE() << "NaN accepted";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("point 1"), std::string::npos) << e.what();
  }
  for (double voxel : {0.0, -1.0, std::numeric_limits<double>::infinity()})
  {
    o.voxelSize = voxel;
    EXPECT_THROW(field.build(one, 1, o), std::invalid_argument) << voxel;
  }
  o.voxelSize = 0.1;
  o.bandWidth = -2;
  EXPECT_THROW(field.build(one, 1, o), std::invalid_argument);
  EXPECT_TRUE(field.empty());
  EXPECT_THROW(field.sample(one), std::logic_error);

  // A band so wide the grid would not fit: refused up front, quickly, with the numbers.
  const Cloud c = randomCloud(10000, 9);
  o.voxelSize = 0.001;
  o.bandWidth = 1.0;
  const auto start = std::chrono::steady_clock::now();
  try
  {
    field.build(c.points.data(), 10000, o);
    ADD_FAILURE() << "runaway grid accepted";
  }
  catch (const dp::GridTooLarge& e)
  {
    EXPECT_NE(std::string(e.what()).find("larger voxel size"), std::string::npos) << e.what();
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  o.voxelSize = 1e-12;
  o.bandWidth = 0;
  EXPECT_THROW(field.build(c.points.data(), 10000, o), dp::GridTooLarge);
  EXPECT_TRUE(field.empty()) << "a failed build leaves the field as it was";
}

} // namespace
