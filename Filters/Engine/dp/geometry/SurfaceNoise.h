// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file SurfaceNoise.h
 * @brief How noisy a cloud's surface is, measured in the cloud itself: what a reconstruction's
 *        smoothing and a frame's judgement of its fit must follow, rather than the point spacing
 *        alone.
 *
 * A real sensor's surface is a layer: each camera's noise, and the cameras' small
 * misalignments stacked. Around a sample of the points (at most 2000, spread evenly), the
 * `neighbours` nearest points are fitted with a plane (PCA); the layer's *thickness* is the
 * median over the sample of the RMS distance of those points from their plane, and the
 * *surface spacing* the spacing the points would have on one surface, sqrt(pi r^2 / k) for the
 * k-th neighbour's distance r (a layer's points crowd closer in 3D than that).
 *
 * Limits: curvature within a neighbourhood counts as thickness (about r^2 / (4 R) on a sphere of
 * radius R: 0.1 mm on an arm sampled every 5 mm), as does a second surface within it (two
 * fingers touching).
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace dp
{

struct SurfaceNoise
{
  double thickness = 0;      // RMS distance from the local plane, the sample's median
  double surfaceSpacing = 0; // the points' spacing along the surface
  double pointSpacing = 0;   // the median distance to the nearest other point
};

/** The k nearest points to x (indices, squared distances, nearest first); returns how many. */
using NearestPoints =
    std::function<std::size_t(const double* x, std::size_t k, std::uint32_t* ids, double* d2)>;

/** The neighbours that judge a point stray. */
constexpr std::size_t StrayNeighbours = 16;

/** The noise measured around `samples` (indices into `points`, x y z each), their neighbours
 *  found by `nearest`; and per sample whether it is stray: isolated (its `neighbours`-th
 *  neighbour over three times as far as the samples' median: a flying pixel's trail behind a
 *  silhouette, a stray return) or off the layer (farther than four thicknesses and a surface
 *  spacing from its neighbours' plane). */
struct NoiseAtSamples
{
  SurfaceNoise noise;
  std::vector<char> stray;
  double usualReach = 0; // the samples' median distance to their `neighbours`-th neighbour
};
NoiseAtSamples measureNoiseAt(const double* points, const std::vector<std::uint32_t>& samples,
                              const NearestPoints& nearest,
                              std::size_t neighbours = StrayNeighbours);

/** Whether the point at `x` is stray by the measures of `judged` (its neighbours found by
 *  `nearest`, `neighbours` of them as for the samples): any point of the cloud, judged alike. */
bool isStrayPoint(const double* points, const double* x, const NearestPoints& nearest,
                  const NoiseAtSamples& judged, std::size_t neighbours = StrayNeighbours);

/** The noise of `count` points (x y z each), measured around at most 2000 of them spread
 *  evenly; std::invalid_argument for fewer than 8 points or points that all coincide. */
SurfaceNoise measureSurfaceNoise(const double* points, std::size_t count,
                                 std::size_t neighbours = 24);

/** The points that are not stray (measureNoiseAt over every point), by index. */
std::vector<std::uint32_t> pointsOnTheSurface(const double* points, std::size_t count);

} // namespace dp
