// SPDX-License-Identifier: BSD-3-Clause
#include "dp/DistanceImage.h"

#include "dp/detail/KdTree.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

namespace dp
{
namespace
{
constexpr std::uint64_t NoKey = std::numeric_limits<std::uint64_t>::max();
constexpr double Infinity = std::numeric_limits<double>::infinity();

void validate(const double* points, std::size_t count, const ImageGrid& grid, double bandWidth)
{
  if (count == 0 || !points)
    throw std::invalid_argument("distance image: no points");
  if (count > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("distance image: " + std::to_string(count) +
                                " points, more than 2^32 - 1");
  for (int k = 0; k < 3; ++k)
  {
    if (grid.dimensions[k] < 1)
      throw std::invalid_argument("distance image: dimension " + std::to_string(k) + " is " +
                                  std::to_string(grid.dimensions[k]) + " (at least 1)");
    if (!(grid.spacing[k] > 0) || !std::isfinite(grid.spacing[k]) || !std::isfinite(grid.origin[k]))
      throw std::invalid_argument("distance image: spacing " + std::to_string(grid.spacing[k]) +
                                  " or origin along axis " + std::to_string(k) +
                                  " is not a positive finite number");
  }
  if (grid.voxelCount() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw std::invalid_argument("distance image: " + std::to_string(grid.voxelCount()) +
                                " voxels, more than 2^31 - 1");
  if (!(bandWidth >= 0) || !std::isfinite(bandWidth))
    throw std::invalid_argument("distance image: band width " + std::to_string(bandWidth) +
                                " (>= 0 wanted)");
  for (std::size_t i = 0; i < 3 * count; ++i)
    if (!std::isfinite(points[i]))
      throw std::invalid_argument("distance image: point " + std::to_string(i / 3) +
                                  " has a non-finite coordinate");
}

// (distance, index) as one integer whose order is the pair's: a non-negative float's bits grow
// with its value, so an atomic minimum of keys keeps the nearest point, ties to the lower index.
std::uint64_t keyOf(double distance, std::uint32_t index)
{
  const float d = static_cast<float>(distance);
  std::uint32_t bits;
  std::memcpy(&bits, &d, sizeof bits);
  return (static_cast<std::uint64_t>(bits) << 32) | index;
}

void atomicMin(std::atomic<std::uint64_t>& slot, std::uint64_t key)
{
  std::uint64_t current = slot.load(std::memory_order_relaxed);
  while (key < current && !slot.compare_exchange_weak(current, key, std::memory_order_relaxed))
  {
  }
}

// Step 1: every point offers itself to the voxels within the band around it.
std::unique_ptr<std::atomic<std::uint64_t>[]> splatBand(const double* points, std::size_t count,
                                                        const ImageGrid& grid, double band)
{
  const std::size_t n = grid.voxelCount();
  std::unique_ptr<std::atomic<std::uint64_t>[]> keys(new std::atomic<std::uint64_t>[n]);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 65536),
                    [&](const tbb::blocked_range<std::size_t>& r)
                    {
                      for (std::size_t v = r.begin(); v < r.end(); ++v)
                        keys[v].store(NoKey, std::memory_order_relaxed);
                    });
  const auto& dim = grid.dimensions;
  const std::size_t nx = static_cast<std::size_t>(dim[0]);
  const std::size_t nxy = nx * static_cast<std::size_t>(dim[1]);
  const double band2 = band * band;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 256),
                    [&](const tbb::blocked_range<std::size_t>& r)
                    {
                      for (std::size_t p = r.begin(); p < r.end(); ++p)
                      {
                        const double* x = points + 3 * p;
                        int lo[3], hi[3];
                        bool empty = false;
                        for (int a = 0; a < 3; ++a)
                        {
                          const double from =
                              std::ceil((x[a] - band - grid.origin[a]) / grid.spacing[a]);
                          const double to =
                              std::floor((x[a] + band - grid.origin[a]) / grid.spacing[a]);
                          lo[a] = static_cast<int>(std::max(from, 0.0));
                          hi[a] = static_cast<int>(std::min(to, static_cast<double>(dim[a] - 1)));
                          empty = empty || from > dim[a] - 1 || to < 0;
                        }
                        if (empty)
                          continue;
                        for (int k = lo[2]; k <= hi[2]; ++k)
                        {
                          const double dz = grid.origin[2] + k * grid.spacing[2] - x[2];
                          for (int j = lo[1]; j <= hi[1]; ++j)
                          {
                            const double dy = grid.origin[1] + j * grid.spacing[1] - x[1];
                            const double dyz = dy * dy + dz * dz;
                            if (dyz > band2)
                              continue;
                            const std::size_t row = static_cast<std::size_t>(k) * nxy + j * nx;
                            for (int i = lo[0]; i <= hi[0]; ++i)
                            {
                              const double dx = grid.origin[0] + i * grid.spacing[0] - x[0];
                              const double d2 = dx * dx + dyz;
                              if (d2 <= band2)
                                atomicMin(keys[row + static_cast<std::size_t>(i)],
                                          keyOf(std::sqrt(d2), static_cast<std::uint32_t>(p)));
                            }
                          }
                        }
                      }
                    });
  return keys;
}

// One axis of the separable transform on one line: out[p] = min_q f[q] + w (p - q)^2 over the
// line's finite f (the lower envelope of parabolas), carrying the winner's seed.
struct LineScratch
{
  std::vector<double> f, z;
  std::vector<int> v;
  std::vector<std::int32_t> seed;
};

void transformLine(double* g, std::int32_t* seed, std::size_t stride, int length, double w,
                   LineScratch& s)
{
  s.f.resize(length);
  s.seed.resize(length);
  s.v.resize(length);
  s.z.resize(length + 1);
  for (int q = 0; q < length; ++q)
  {
    s.f[q] = g[q * stride];
    s.seed[q] = seed[q * stride];
  }
  int k = -1;
  for (int q = 0; q < length; ++q)
  {
    if (s.f[q] == Infinity)
      continue;
    double cut = -Infinity;
    while (k >= 0)
    {
      const int r = s.v[k];
      cut = ((s.f[q] + w * q * q) - (s.f[r] + w * r * r)) / (2.0 * w * (q - r));
      if (cut > s.z[k])
        break;
      --k;
      cut = -Infinity;
    }
    ++k;
    s.v[k] = q;
    s.z[k] = cut;
  }
  if (k < 0)
    return; // no seed on this line yet: everything stays infinite
  s.z[k + 1] = Infinity;
  int j = 0;
  for (int p = 0; p < length; ++p)
  {
    while (s.z[j + 1] < p)
      ++j;
    const int q = s.v[j];
    g[p * stride] = s.f[q] + w * (p - q) * (p - q);
    seed[p * stride] = s.seed[q];
  }
}

// Step 2: the exact distance transform of the seeds, axis by axis; each voxel ends with the
// index of its nearest seed voxel (-1 when there is none).
std::vector<std::int32_t> nearestSeeds(const std::vector<std::int32_t>& seeds,
                                       const ImageGrid& grid)
{
  const std::size_t n = grid.voxelCount();
  std::vector<double> g(n, Infinity);
  std::vector<std::int32_t> seed(n, -1);
  for (std::int32_t v : seeds)
  {
    g[static_cast<std::size_t>(v)] = 0;
    seed[static_cast<std::size_t>(v)] = v;
  }
  const std::size_t dim[3] = {static_cast<std::size_t>(grid.dimensions[0]),
                              static_cast<std::size_t>(grid.dimensions[1]),
                              static_cast<std::size_t>(grid.dimensions[2])};
  const std::size_t stride[3] = {1, dim[0], dim[0] * dim[1]};
  for (int axis = 0; axis < 3; ++axis)
  {
    // Lines along `axis`: indexed by the other two coordinates.
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    const std::size_t lines = dim[a] * dim[b];
    const double w = grid.spacing[axis] * grid.spacing[axis];
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lines, 64),
                      [&](const tbb::blocked_range<std::size_t>& r)
                      {
                        LineScratch scratch;
                        for (std::size_t line = r.begin(); line < r.end(); ++line)
                        {
                          const std::size_t first =
                              (line % dim[a]) * stride[a] + (line / dim[a]) * stride[b];
                          transformLine(&g[first], &seed[first], stride[axis],
                                        static_cast<int>(dim[axis]), w, scratch);
                        }
                      });
  }
  return seed;
}

double distanceTo(const double* point, const double x[3])
{
  const double dx = x[0] - point[0], dy = x[1] - point[1], dz = x[2] - point[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// The nearest point found for a voxel so far (ties to the lower index: deterministic).
struct Candidate
{
  std::int64_t index = -1;
  double distance = Infinity;
  bool exact = false;

  void offer(std::int64_t point, double d)
  {
    if (d < distance || (d == distance && point < index))
    {
      index = point;
      distance = d;
    }
  }
};

// Step 3: each voxel's nearest point from the band, else from the transform's seeds.
struct VoxelLookup
{
  const ImageGrid& grid;
  const double* points;
  const std::atomic<std::uint64_t>* keys;
  const std::vector<std::int32_t>& seed;

  Candidate nearest(std::size_t v, const detail::KdTree* outsideTree,
                    const std::vector<std::uint32_t>& outsideIndex) const
  {
    const std::size_t nx = static_cast<std::size_t>(grid.dimensions[0]);
    const std::size_t ny = static_cast<std::size_t>(grid.dimensions[1]);
    const std::size_t nz = static_cast<std::size_t>(grid.dimensions[2]);
    const std::size_t i = v % nx, j = (v / nx) % ny, k = v / (nx * ny);
    const double x[3] = {grid.origin[0] + static_cast<double>(i) * grid.spacing[0],
                         grid.origin[1] + static_cast<double>(j) * grid.spacing[1],
                         grid.origin[2] + static_cast<double>(k) * grid.spacing[2]};
    Candidate c;
    const std::uint64_t key = keys[v].load(std::memory_order_relaxed);
    if (key != NoKey)
    {
      c.exact = true;
      c.offer(static_cast<std::int64_t>(key & 0xffffffffu),
              distanceTo(points + 3 * (key & 0xffffffffu), x));
      return c;
    }
    // The nearest seed's point, or a neighbour's nearest seed's point when nearer: the seed
    // nearest to the voxel's centre need not hold the point nearest to it.
    const std::size_t around[7] = {v,
                                   i > 0 ? v - 1 : v,
                                   i + 1 < nx ? v + 1 : v,
                                   j > 0 ? v - nx : v,
                                   j + 1 < ny ? v + nx : v,
                                   k > 0 ? v - nx * ny : v,
                                   k + 1 < nz ? v + nx * ny : v};
    for (std::size_t u : around)
      if (seed[u] >= 0)
      {
        const std::uint64_t p =
            keys[static_cast<std::size_t>(seed[u])].load(std::memory_order_relaxed) & 0xffffffffu;
        c.offer(static_cast<std::int64_t>(p), distanceTo(points + 3 * p, x));
      }
    if (outsideTree)
    {
      double d2 = 0;
      const std::uint32_t o = outsideTree->nearest(x, &d2);
      c.offer(outsideIndex[o], std::sqrt(d2));
    }
    return c;
  }
};

} // namespace

DistanceImage computeDistanceImage(const double* points, std::size_t count, const ImageGrid& grid,
                                   double bandWidth)
{
  validate(points, count, grid, bandWidth);
  const auto& h = grid.spacing;
  const double halfDiagonal = 0.5 * std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
  DistanceImage out;
  out.bandWidth = std::max(bandWidth, halfDiagonal * (1 + 1e-9));
  const std::unique_ptr<std::atomic<std::uint64_t>[]> keys =
      splatBand(points, count, grid, out.bandWidth);

  // Seeds: the voxels points fall in (their nearest point is exact, within half a diagonal).
  // Points outside the image have no seed; a kd-tree finds them beyond the band.
  const std::size_t n = grid.voxelCount();
  std::vector<std::int32_t> seeds;
  std::vector<double> outside;
  std::vector<std::uint32_t> outsideIndex;
  for (std::size_t p = 0; p < count; ++p)
  {
    std::size_t voxel = 0, stride = 1;
    bool inside = true;
    for (int a = 0; a < 3; ++a)
    {
      const double c = std::round((points[3 * p + a] - grid.origin[a]) / h[a]);
      inside = inside && c >= 0 && c <= grid.dimensions[a] - 1;
      voxel += inside ? static_cast<std::size_t>(c) * stride : 0;
      stride *= static_cast<std::size_t>(grid.dimensions[a]);
    }
    if (inside)
      seeds.push_back(static_cast<std::int32_t>(voxel));
    else
    {
      outside.insert(outside.end(), points + 3 * p, points + 3 * p + 3);
      outsideIndex.push_back(static_cast<std::uint32_t>(p));
    }
  }
  std::sort(seeds.begin(), seeds.end());
  seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
  const std::vector<std::int32_t> seed = nearestSeeds(seeds, grid);
  std::unique_ptr<detail::KdTree> outsideTree;
  if (!outsideIndex.empty())
    outsideTree = std::make_unique<detail::KdTree>(outside.data(), outsideIndex.size());

  out.distance.resize(n);
  out.nearest.resize(n);
  out.exact.resize(n);
  const VoxelLookup lookup{grid, points, keys.get(), seed};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                    [&](const tbb::blocked_range<std::size_t>& r)
                    {
                      for (std::size_t v = r.begin(); v < r.end(); ++v)
                      {
                        const Candidate c = lookup.nearest(v, outsideTree.get(), outsideIndex);
                        out.exact[v] = c.exact ? 1 : 0;
                        out.nearest[v] = c.index;
                        out.distance[v] = static_cast<float>(c.distance);
                      }
                    });
  for (std::uint8_t e : out.exact)
    out.bandVoxels += e;
  return out;
}

} // namespace dp
