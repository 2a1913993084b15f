// SPDX-License-Identifier: BSD-3-Clause
// DetailLevels: the mean edge length against the edges counted by brute force, the levels a
// capture's density suggests against log4 of the ratio, and the automatic choice: a bumpy sphere
// gains its candidate levels (the fine mesh much closer to the data than the tracked mesh, whose
// distance brute force measures), a noisy plane gains none, and too few points ask for none.
#include "FineMeshShapes.h"

#include "dp/detail/DetailLevels.h"
#include "dp/detail/FrameSurface.h"
#include "dp/geometry/FrameSamples.h"
#include "dp/geometry/SurfaceLocator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <utility>

namespace
{

using dp::test::Mesh;

TEST(DetailLevels, TheMeanEdgeLengthCountsEachEdgeOfAClosedMeshOnce)
{
  for (int level = 0; level <= 3; ++level)
  {
    const Mesh m = dp::test::icosphere(level, [](const double* u) { return 1 + 0.2 * u[2]; });
    std::set<std::pair<std::int64_t, std::int64_t>> edges;
    for (std::size_t t = 0; t < m.triangles.size(); t += 3)
      for (int k = 0; k < 3; ++k)
      {
        const std::int64_t a = m.triangles[t + k], b = m.triangles[t + (k + 1) % 3];
        edges.insert({std::min(a, b), std::max(a, b)});
      }
    double sum = 0;
    for (const auto& [a, b] : edges)
      sum += std::hypot(m.positions[3 * a] - m.positions[3 * b],
                        m.positions[3 * a + 1] - m.positions[3 * b + 1],
                        m.positions[3 * a + 2] - m.positions[3 * b + 2]);
    EXPECT_NEAR(dp::meanEdgeLength(m.triangles, m.positions.data()),
                sum / static_cast<double>(edges.size()), 1e-12)
        << "level " << level;
  }
  EXPECT_EQ(dp::meanEdgeLength({}, nullptr), 0.0);
}

TEST(DetailLevels, TheDensityAsksForTheLevelsNearestLog4OfTheRatio)
{
  // Each level multiplies the vertices by about four: the level whose count is nearest the
  // capture's in ratio, none when the capture has no more vertices, three at most.
  for (std::size_t base : {12u, 162u, 1000u})
    for (double ratio : {0.5, 1.0, 1.5, 2.2, 3.0, 7.0, 12.0, 40.0, 64.0, 150.0, 1e4})
    {
      const auto capture = static_cast<std::size_t>(ratio * static_cast<double>(base));
      int expected = 0;
      if (capture > base)
      {
        double best = HUGE_VAL;
        for (int level = 0; level <= 3; ++level)
        {
          const double off =
              std::abs(std::log(static_cast<double>(capture) / static_cast<double>(base)) -
                       level * std::log(4.0));
          if (off < best)
          {
            best = off;
            expected = level;
          }
        }
      }
      EXPECT_EQ(dp::levelsForDensity(base, capture), expected) << base << " -> " << capture;
    }
  EXPECT_EQ(dp::levelsForDensity(0, 1000), 0);
  EXPECT_EQ(dp::levelsForDensity(100, 1600), 2);
  EXPECT_EQ(dp::levelsForDensity(100, 6400), 3);
  EXPECT_EQ(dp::levelsForDensity(100, 1000000), dp::MaximumAutomaticLevels);
}

// The RMS distance from the samples to the mesh, by brute force over its triangles.
double bruteForceRms(const Mesh& mesh, const dp::FrameSamples& samples)
{
  double sum = 0;
  for (std::size_t i = 0; i < samples.size(); ++i)
  {
    double best = HUGE_VAL;
    for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
    {
      double w[3], c[3];
      best = std::min(best, dp::closestPointOnTriangle(
                                &samples.points[3 * i], &mesh.positions[3 * mesh.triangles[t]],
                                &mesh.positions[3 * mesh.triangles[t + 1]],
                                &mesh.positions[3 * mesh.triangles[t + 2]], w, c));
    }
    sum += best;
  }
  return std::sqrt(sum / static_cast<double>(samples.size()));
}

// A mesh's vertices as samples (their normals are not read by the distance).
dp::FrameSamples samplesOf(const std::vector<double>& points)
{
  dp::FrameSamples s;
  s.points = points;
  s.normals.assign(points.size(), 0.0f);
  s.voxel = 0.01;
  return s;
}

TEST(DetailLevels, ABumpySphereGainsItsCandidateLevels)
{
  // The tracked mesh: the unit icosphere of 162 vertices. The data: a bumpy sphere of 2562
  // vertices, whose density asks for 2 levels; the fitted fine mesh follows the bumps the
  // tracked mesh cannot carry, so they are kept.
  const Mesh base = dp::test::icosphere(2);
  const Mesh data =
      dp::test::icosphere(4, [](const double* u) { return dp::test::bumpyRadius(u, 0.03); });
  const dp::FrameSurface surface = dp::FrameSurface::ofMesh(data.surface());
  const dp::FrameSamples samples = samplesOf(data.positions);
  dp::DisplacementFitOptions options;
  options.reach = 0.2;
  const dp::DetailLevelChoice choice = dp::chooseDetailLevels(
      base.triangles, base.positions, surface, samples, data.vertices(), options);
  EXPECT_EQ(choice.candidate, 2);
  EXPECT_EQ(choice.levels, 2);
  EXPECT_NEAR(choice.baseDistance, bruteForceRms(base, samples), 1e-12);
  EXPECT_GT(choice.baseDistance, 0.01);
  EXPECT_LE(choice.fineDistance, (1 - dp::DetailGainThreshold) * choice.baseDistance);
  EXPECT_LT(choice.fineDistance, 0.5 * choice.baseDistance);
  EXPECT_EQ(choice.summary.rfind("2 level(s)", 0), 0u) << choice.summary;
}

TEST(DetailLevels, ANoisyPlaneGainsNothingAndTooFewPointsAskForNothing)
{
  // A plane's points with noise: the finer mesh fits the noise no better than the flat one, so
  // no level is worth its bits.
  const Mesh base = dp::test::grid(6);
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> noise(0, 0.01);
  std::vector<double> points;
  std::vector<float> normals;
  for (int i = 0; i < 4000; ++i)
  {
    points.insert(points.end(), {u(rng), u(rng), noise(rng)});
    normals.insert(normals.end(), {0.0f, 0.0f, 1.0f});
  }
  const dp::FrameSurface surface = dp::FrameSurface::ofPoints(points.data(), 4000, normals.data());
  const dp::FrameSamples samples = samplesOf(points);
  dp::DisplacementFitOptions options;
  options.reach = 0.1;
  const dp::DetailLevelChoice choice =
      dp::chooseDetailLevels(base.triangles, base.positions, surface, samples, 4000, options);
  EXPECT_EQ(choice.candidate, dp::levelsForDensity(base.vertices(), 4000));
  EXPECT_GT(choice.candidate, 0);
  EXPECT_EQ(choice.levels, 0);
  EXPECT_NEAR(choice.baseDistance, bruteForceRms(base, samples), 1e-12);
  EXPECT_GT(choice.fineDistance, (1 - dp::DetailGainThreshold) * choice.baseDistance);
  EXPECT_NE(choice.summary.find("too little gain"), std::string::npos) << choice.summary;

  // As many points as the mesh has vertices: no candidate, nothing measured.
  const dp::DetailLevelChoice none = dp::chooseDetailLevels(base.triangles, base.positions, surface,
                                                            samples, base.vertices(), options);
  EXPECT_EQ(none.candidate, 0);
  EXPECT_EQ(none.levels, 0);
  EXPECT_EQ(none.baseDistance, 0.0);
  EXPECT_EQ(none.fineDistance, 0.0);
  EXPECT_EQ(none.summary.rfind("none: ", 0), 0u) << none.summary;
  // No samples: nothing to measure against either.
  const dp::DetailLevelChoice unsampled = dp::chooseDetailLevels(
      base.triangles, base.positions, surface, dp::FrameSamples{}, 4000, options);
  EXPECT_EQ(unsampled.levels, 0);
  EXPECT_NE(unsampled.summary.find("no samples"), std::string::npos) << unsampled.summary;
}

} // namespace
