// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/FrameData.h"

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/NormalEstimation.h"
#include "dp/track/ColourTerm.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
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

// Sorts point indices along a Morton (Z-order) curve over their bounding box, 2^20 cells an
// axis; ties by index, so the order is the same on every platform.
void sortAlongCurve(const double* points, std::vector<std::size_t>& indices)
{
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (const std::size_t i : indices)
    for (int k = 0; k < 3; ++k)
    {
      lo[k] = std::min(lo[k], points[3 * i + k]);
      hi[k] = std::max(hi[k], points[3 * i + k]);
    }
  const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-300});
  const double scale = ((1 << 20) - 1) / extent;
  // Bit b of axis k lands at bit 3b + k of the code.
  auto spreadBits = [](std::uint64_t v)
  {
    std::uint64_t out = 0;
    for (int b = 0; b < 20; ++b)
      out |= ((v >> b) & 1u) << (3 * b);
    return out;
  };
  std::vector<std::pair<std::uint64_t, std::size_t>> keyed(indices.size());
  for (std::size_t j = 0; j < indices.size(); ++j)
  {
    const std::size_t i = indices[j];
    std::uint64_t code = 0;
    for (int k = 0; k < 3; ++k)
      code |= spreadBits(static_cast<std::uint64_t>((points[3 * i + k] - lo[k]) * scale)) << k;
    keyed[j] = {code, i};
  }
  std::sort(keyed.begin(), keyed.end());
  for (std::size_t j = 0; j < indices.size(); ++j)
    indices[j] = keyed[j].second;
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

// The indices of the points kept (all, or an evenly thinned share when there are more than
// options.maxPoints), in space-filling-curve order.
std::vector<std::size_t> pointsKept(const double* points, std::size_t count,
                                    const FrameDataOptions& options)
{
  std::vector<std::size_t> kept;
  if (options.maxPoints > 0 && count > options.maxPoints)
  {
    const double area = options.surfaceArea > 0 ? options.surfaceArea
                                                : std::pow(boundingBoxDiagonal(points, count), 2);
    kept = thinnedFrame(points, count, area, options.maxPoints);
  }
  else
  {
    kept.resize(count);
    std::iota(kept.begin(), kept.end(), std::size_t{0});
  }
  sortAlongCurve(points, kept);
  return kept;
}

// The RGB of the kept points (of `components` bytes each: RGB or RGBA) as floats in [0, 1].
std::vector<float> coloursInZeroOne(const std::uint8_t* colours, int components,
                                    const std::vector<std::size_t>& kept)
{
  std::vector<float> out(3 * kept.size());
  for (std::size_t j = 0; j < kept.size(); ++j)
    for (int k = 0; k < 3; ++k)
      out[3 * j + k] =
          static_cast<float>(colours[static_cast<std::size_t>(components) * kept[j] + k]) / 255.0f;
  return out;
}
} // namespace

FrameData::FrameData(const double* points, std::size_t count, const float* normals,
                     const std::uint8_t* colours, int colourComponents,
                     const FrameDataOptions& options)
    : Count(count), OriginalCount(count), Voxel(options.voxelSize), SurfaceArea(options.surfaceArea)
{
  if (colours && colourComponents != 3 && colourComponents != 4)
    throw std::invalid_argument("colours have " + std::to_string(colourComponents) +
                                " components a point (3 or 4: RGB, RGBA)");
  if (count == 0)
    return;
  requireFinitePoints(points, count); // the field's message, before anything reads them
  // The points kept (all, or an evenly thinned share), in space-filling-curve order: points
  // near one another in space are then near in memory too, so the searches below and the energy
  // terms' per-point loops stay in cache (a scanner's or a sampler's order can be anything).
  const std::vector<std::size_t> kept = pointsKept(points, count, options);
  std::vector<double> keptPoints(3 * kept.size());
  std::vector<float> keptNormals(normals ? 3 * kept.size() : 0);
  for (std::size_t j = 0; j < kept.size(); ++j)
    for (int k = 0; k < 3; ++k)
    {
      keptPoints[3 * j + k] = points[3 * kept[j] + k];
      if (normals)
        keptNormals[3 * j + k] = normals[3 * kept[j] + k];
    }
  if (colours)
    Colours = coloursInZeroOne(colours, colourComponents, kept);
  points = keptPoints.data();
  normals = normals ? keptNormals.data() : nullptr;
  count = Count = kept.size();
  DistanceFieldOptions field;
  field.voxelSize = options.voxelSize;
  field.bandWidth = options.bandWidth > 0 ? options.bandWidth : 4 * options.voxelSize;
  field.lazy = true; // only the voxels around the mesh are ever needed
  // The field, the normals and the subsample read the points and nothing of each other: built
  // side by side (the normals' serial orientation leaves a core free).
  tbb::parallel_invoke([&] { Field.build(points, count, field); },
                       [&] { takeOrEstimateNormals(points, count, normals); },
                       [&] { chooseSpread(points, count, options); });
  if (!Colours.empty())
    Colour = std::make_unique<ColourField>(Field.points(), Colours.data(), Count, spacing(), Voxel);
  judgeSpread();
}

void FrameData::judgeSpread()
{
  SpreadOnSurface = Spread;
  if (Spread.size() < 8)
    return;
  Judged = measureNoiseAt(Field.points(), Spread,
                          [this](const double* x, std::size_t k, std::uint32_t* ids, double* d2)
                          { return Field.nearestPoints(x, k, ids, d2); });
  SpreadOnSurface.clear();
  for (std::size_t i = 0; i < Spread.size(); ++i)
    if (!Judged.stray[i])
      SpreadOnSurface.push_back(Spread[i]);
  StrayKnown = std::make_unique<std::atomic<std::uint8_t>[]>(Count);
}

bool FrameData::isStray(std::size_t i) const
{
  if (!StrayKnown)
    return false;
  std::uint8_t known = StrayKnown[i].load(std::memory_order_relaxed);
  if (known == 0)
  {
    // A pure function of the point: threads that judge it at once agree.
    known = isStrayPoint(
                Field.points(), point(i),
                [this](const double* x, std::size_t k, std::uint32_t* ids, double* d2)
                { return Field.nearestPoints(x, k, ids, d2); },
                Judged)
                ? 2
                : 1;
    StrayKnown[i].store(known, std::memory_order_relaxed);
  }
  return known == 2;
}

FrameData::~FrameData() = default;

double FrameData::spacing() const
{
  // Points spread over the surface: each has about area / count around it.
  const double area =
      SurfaceArea > 0 ? SurfaceArea : std::pow(boundingBoxDiagonal(points(), Count), 2);
  return std::sqrt(area / static_cast<double>(std::max<std::size_t>(Count, 1)));
}

void FrameData::takeOrEstimateNormals(const double* points, std::size_t count, const float* normals)
{
  if (normals)
  {
    Normals.assign(normals, normals + 3 * count);
    return;
  }
  std::vector<std::uint32_t> parts;
  Normals = estimateNormals(points, count, 16, &parts, &Tree);
  Parts = std::move(parts);
  PartCount = Parts.empty() ? 0 : *std::max_element(Parts.begin(), Parts.end()) + 1;
}

std::size_t FrameData::mendOrientation(const std::vector<std::int8_t>& spreadVotes)
{
  if (Tree.order.empty() || spreadVotes.size() != Spread.size())
    return 0;
  std::vector<std::int8_t> votes(Count, NotAsked);
  for (std::size_t i = 0; i < Spread.size(); ++i)
    votes[Spread[i]] = spreadVotes[i];
  return dp::mendOrientation(Tree, Parts, votes, Normals.data());
}

void FrameData::chooseSpread(const double* points, std::size_t count,
                             const FrameDataOptions& options)
{
  if (options.spreadCount == 0 || !(options.surfaceArea > 0))
    return;
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

FrameSamples FrameData::copySamples() const
{
  FrameSamples samples;
  samples.voxel = Voxel;
  samples.points.reserve(3 * Spread.size());
  samples.normals.reserve(3 * Spread.size());
  for (std::uint32_t i : Spread)
  {
    samples.points.insert(samples.points.end(), point(i), point(i) + 3);
    samples.normals.insert(samples.normals.end(), normal(i), normal(i) + 3);
  }
  return samples;
}

} // namespace dp
