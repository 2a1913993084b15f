// SPDX-License-Identifier: BSD-3-Clause
// A cloud's noise measured in itself (dp/geometry/SurfaceNoise.h).
#include "dp/geometry/DeterministicRandom.h"
#include "dp/geometry/SurfaceNoise.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace
{

// A square of points on a grid `spacing` apart in z = 0, each moved across by noise of `sigma`;
// `strays` more points scattered far above and below.
std::vector<double> noisyPlane(double spacing, double sigma, std::size_t strays = 0)
{
  dp::DeterministicRandom random(3, 0);
  std::vector<double> p;
  for (int i = 0; i < 150; ++i)
    for (int j = 0; j < 150; ++j)
      p.insert(p.end(), {i * spacing, j * spacing, sigma * random.gaussian()});
  for (std::size_t s = 0; s < strays; ++s)
    p.insert(p.end(), {150 * spacing * random.uniform(), 150 * spacing * random.uniform(),
                       (random.uniform() < 0.5 ? -1 : 1) * (0.05 + random.uniform())});
  return p;
}

} // namespace

// The layer's thickness is the noise across it; the spacing, the grid's; a clean plane has none.
TEST(SurfaceNoise, TheThicknessIsTheNoiseAcrossTheSurfaceAndTheSpacingTheGrids)
{
  for (double sigma : {0.0005, 0.002, 0.004})
  {
    const std::vector<double> p = noisyPlane(0.005, sigma);
    const dp::SurfaceNoise n = dp::measureSurfaceNoise(p.data(), p.size() / 3);
    // The plane fitted to 24 points takes a little of their noise with it.
    EXPECT_NEAR(n.thickness / sigma, 0.93, 0.1) << sigma;
    EXPECT_NEAR(n.surfaceSpacing / 0.005, 1.0, 0.15) << sigma;
  }
  const std::vector<double> clean = noisyPlane(0.005, 0);
  EXPECT_LT(dp::measureSurfaceNoise(clean.data(), clean.size() / 3).thickness, 1e-9);
  // Units: the same cloud in millimetres, the same figures in millimetres.
  std::vector<double> p = noisyPlane(0.005, 0.002), mm = p;
  for (double& v : mm)
    v *= 1000;
  const dp::SurfaceNoise a = dp::measureSurfaceNoise(p.data(), p.size() / 3);
  const dp::SurfaceNoise b = dp::measureSurfaceNoise(mm.data(), mm.size() / 3);
  EXPECT_NEAR(b.thickness, 1000 * a.thickness, 1e-9 * b.thickness);
  EXPECT_THROW(dp::measureSurfaceNoise(p.data(), 5), std::invalid_argument);
}

// Stray points far off the layer are left out; the layer's own points, noise and all, are kept.
TEST(SurfaceNoise, StrayPointsAreLeftOutAndTheLayerKept)
{
  const std::size_t strays = 200, layer = 150 * 150;
  const std::vector<double> p = noisyPlane(0.005, 0.002, strays);
  const std::vector<std::uint32_t> kept = dp::pointsOnTheSurface(p.data(), p.size() / 3);
  const std::size_t keptStrays = static_cast<std::size_t>(
      std::count_if(kept.begin(), kept.end(), [&](std::uint32_t i) { return i >= layer; }));
  EXPECT_EQ(keptStrays, 0u);
  EXPECT_GT(kept.size() - keptStrays, layer - layer / 200) << "at most 0.5 % of the layer lost";
}
