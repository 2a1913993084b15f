// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/FrameData.h"

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/NormalEstimation.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace dp
{
namespace
{
// One point per grid cell, the one nearest the cell's centre; cells of size `cell`.
std::vector<std::uint32_t> spreadSubsample(const double* points, std::size_t count, double cell)
{
  struct Best
  {
    std::uint32_t index;
    double d2;
  };
  std::unordered_map<std::uint64_t, Best> cells;
  cells.reserve(count);
  for (std::size_t i = 0; i < count; ++i)
  {
    std::int64_t c[3];
    double d2 = 0;
    for (int k = 0; k < 3; ++k)
    {
      // Clamped so the cast below is defined for any finite coordinate (cells this far out
      // only ever share a key with each other).
      const double u = std::clamp(points[3 * i + k] / cell, -1e18, 1e18);
      c[k] = static_cast<std::int64_t>(std::floor(u));
      const double offset = u - (static_cast<double>(c[k]) + 0.5);
      d2 += offset * offset;
    }
    const std::uint64_t key = (static_cast<std::uint64_t>(c[0] & 0x1FFFFF) << 42) |
                              (static_cast<std::uint64_t>(c[1] & 0x1FFFFF) << 21) |
                              static_cast<std::uint64_t>(c[2] & 0x1FFFFF);
    const auto [it, added] = cells.try_emplace(key, Best{static_cast<std::uint32_t>(i), d2});
    // Ties go to the lower index, so the choice does not depend on the map's order.
    if (!added && (d2 < it->second.d2 || (d2 == it->second.d2 && i < it->second.index)))
      it->second = {static_cast<std::uint32_t>(i), d2};
  }
  std::vector<std::uint32_t> out;
  out.reserve(cells.size());
  for (const auto& entry : cells)
    out.push_back(entry.second.index);
  std::sort(out.begin(), out.end());
  return out;
}

// Indices of at most `limit` points spread evenly over the frame (see the file comment).
std::vector<std::size_t> thinnedFrame(const double* points, std::size_t count, double area,
                                      std::size_t limit)
{
  // Every k-th point first, so the grid's map holds at most 8 x limit cells.
  const std::size_t stride = (count + 8 * limit - 1) / (8 * limit);
  std::vector<double> strided;
  if (stride > 1)
    for (std::size_t i = 0; i < count; i += stride)
      strided.insert(strided.end(), points + 3 * i, points + 3 * i + 3);
  const double* source = stride > 1 ? strided.data() : points;
  const std::size_t n = stride > 1 ? strided.size() / 3 : count;
  double cell = std::sqrt(area / static_cast<double>(limit));
  std::vector<std::uint32_t> kept;
  for (;;)
  {
    kept = spreadSubsample(source, n, cell);
    if (kept.size() <= limit)
      break;
    cell *=
        std::max(1.05, std::sqrt(static_cast<double>(kept.size()) / static_cast<double>(limit)));
  }
  std::vector<std::size_t> indices(kept.begin(), kept.end());
  for (std::size_t& i : indices)
    i *= stride;
  return indices;
}
} // namespace

FrameData::FrameData(const double* points, std::size_t count, const float* normals,
                     const FrameDataOptions& options)
    : Count(count), OriginalCount(count), Voxel(options.voxelSize)
{
  if (count == 0)
    return;
  std::vector<double> thinPoints;
  std::vector<float> thinNormals;
  // (A frame with a NaN is not thinned: the field refuses it with its own message.)
  if (options.maxPoints > 0 && count > options.maxPoints &&
      std::all_of(points, points + 3 * count, [](double c) { return std::isfinite(c); }))
  {
    const double area = options.surfaceArea > 0 ? options.surfaceArea
                                                : std::pow(boundingBoxDiagonal(points, count), 2);
    for (const std::size_t i : thinnedFrame(points, count, area, options.maxPoints))
    {
      thinPoints.insert(thinPoints.end(), points + 3 * i, points + 3 * i + 3);
      if (normals)
        thinNormals.insert(thinNormals.end(), normals + 3 * i, normals + 3 * i + 3);
    }
    points = thinPoints.data();
    normals = normals ? thinNormals.data() : nullptr;
    count = Count = thinPoints.size() / 3;
  }
  DistanceFieldOptions field;
  field.voxelSize = options.voxelSize;
  field.bandWidth = options.bandWidth > 0 ? options.bandWidth : 4 * options.voxelSize;
  field.lazy = true; // only the voxels around the mesh are ever needed
  Field.build(points, count, field);
  if (normals)
    Normals.assign(normals, normals + 3 * count);
  else
  {
    std::vector<std::uint32_t> parts;
    Normals = estimateNormals(points, count, 16, &parts);
    Parts = std::move(parts);
    PartCount = Parts.empty() ? 0 : *std::max_element(Parts.begin(), Parts.end()) + 1;
  }
  if (options.spreadCount > 0 && options.surfaceArea > 0)
  {
    // A surface of area A meets about A / cell^2 cells of a grid (fewer where it is flat along an
    // axis, more where it is not): start there and shrink the cell until enough are kept.
    double cell = std::sqrt(options.surfaceArea / static_cast<double>(options.spreadCount));
    for (int attempt = 0; attempt < 4; ++attempt)
    {
      Spread = spreadSubsample(points, count, cell);
      if (Spread.size() >= options.spreadCount * 3 / 4 || Spread.size() == count)
        break;
      cell *=
          std::sqrt(static_cast<double>(Spread.size()) / static_cast<double>(options.spreadCount));
    }
  }
}

} // namespace dp
