// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FrameSamples.h
 * @brief The points the points -> mesh term (CoverageTerm) reads: a frame's well-spread
 *        subsample with its oriented unit normals.
 *
 * SampleView looks at them where they are: inside the frame's data while the frame is tracked
 * (FrameData::spreadSamples(), through the subsample's indices), or in a FrameSamples that holds
 * a copy. The tracker keeps that copy in every FrameResult, so that a take's fit to its data can
 * be measured once every frame is tracked (dp::measureDataFit, the compression judged against
 * the data) without the frames' distance fields: about 4 points a vertex, 144 kB a frame at 1000
 * vertices.
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dp
{

/** Samples seen in place; the viewed arrays must outlive the view. */
struct SampleView
{
  const double* points = nullptr;       // x y z per point
  const float* normals = nullptr;       // nx ny nz per point, unit, oriented
  const std::uint32_t* index = nullptr; // sample i is point index[i]; null: point i
  std::size_t count = 0;                // samples
  double voxel = 0;                     // the frame's voxel (world units): the terms' unit

  const double* point(std::size_t i) const { return points + 3 * (index ? index[i] : i); }
  const float* normal(std::size_t i) const { return normals + 3 * (index ? index[i] : i); }
};

/** Samples held on their own (a copy of a frame's subsample). */
struct FrameSamples
{
  std::vector<double> points;
  std::vector<float> normals;
  double voxel = 0;

  std::size_t size() const { return points.size() / 3; }
  bool empty() const { return points.empty(); }
  SampleView view() const { return {points.data(), normals.data(), nullptr, size(), voxel}; }
};

} // namespace dp
