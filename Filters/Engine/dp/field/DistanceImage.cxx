// SPDX-License-Identifier: BSD-3-Clause
#include "dp/field/DistanceImage.h"

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
constexpr float FarAway = std::numeric_limits<float>::infinity();
constexpr std::uint32_t NoPoint = std::numeric_limits<std::uint32_t>::max();

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

// (squared distance, index) as one integer whose order is the pair's: a non-negative float's
// bits grow with its value, so an atomic minimum of keys keeps the nearest point, ties to the
// lower index.
std::uint64_t keyOf(double distance2, std::uint32_t index)
{
  const float d = static_cast<float>(distance2);
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

// Seeds: the voxels the points fall in (their nearest point is exact: within half a diagonal).
// Points outside the image have no seed; a kd-tree finds them beyond the band.
struct PointsByVoxel
{
  std::vector<std::size_t> seeds;
  std::vector<double> outside; // x y z of the points outside the image
  std::vector<std::uint32_t> outsideIndex;
};

PointsByVoxel sortPoints(const double* points, std::size_t count, const ImageGrid& grid)
{
  PointsByVoxel out;
  for (std::size_t p = 0; p < count; ++p)
  {
    std::size_t voxel = 0, stride = 1;
    bool inside = true;
    for (int a = 0; a < 3; ++a)
    {
      const double c = std::round((points[3 * p + a] - grid.origin[a]) / grid.spacing[a]);
      inside = inside && c >= 0 && c <= grid.dimensions[a] - 1;
      voxel += inside ? static_cast<std::size_t>(c) * stride : 0;
      stride *= static_cast<std::size_t>(grid.dimensions[a]);
    }
    if (inside)
      out.seeds.push_back(voxel);
    else
    {
      out.outside.insert(out.outside.end(), points + 3 * p, points + 3 * p + 3);
      out.outsideIndex.push_back(static_cast<std::uint32_t>(p));
    }
  }
  return out;
}

// One axis of the separable transform on one line, in place: g[p] <- min_q g[q] + w (p - q)^2
// over the line's finite g (the lower envelope of parabolas), carrying the winner's point. In
// single precision and voxel units: it only picks each voxel's seed, whose point's distance is
// then computed exactly.
struct LineScratch
{
  std::vector<float> f, h, z;
  std::vector<int> v;
  std::vector<std::uint32_t> point;
};

void transformLine(float* g, std::uint32_t* point, int length, float w, LineScratch& s)
{
  s.f.resize(length);
  s.h.resize(length);
  s.v.resize(length);
  s.z.resize(length + 1);
  s.point.assign(point, point + length);
  const float inverse = 1.0f / w;
  int k = -1;
  for (int q = 0; q < length; ++q)
  {
    if (g[q] == FarAway)
      continue;
    s.f[q] = g[q] * inverse;
    s.h[q] = s.f[q] + static_cast<float>(q) * static_cast<float>(q); // where the cuts come from
    float cut = -FarAway;
    while (k >= 0)
    {
      const int r = s.v[k];
      cut = (s.h[q] - s.h[r]) / static_cast<float>(2 * (q - r));
      if (cut > s.z[k])
        break;
      --k;
      cut = -FarAway;
    }
    ++k;
    s.v[k] = q;
    s.z[k] = cut;
  }
  if (k < 0)
    return; // no seed on this line yet: everything stays far away
  s.z[k + 1] = FarAway;
  int j = 0;
  for (int p = 0; p < length; ++p)
  {
    while (s.z[j + 1] < static_cast<float>(p))
      ++j;
    const int q = s.v[j];
    const float step = static_cast<float>(p - q);
    g[p] = w * (s.f[q] + step * step);
    point[p] = s.point[q];
  }
}

// Lines along y or z are strided: a block of Block neighbouring lines (along x) is copied into
// contiguous buffers, transformed and copied back, so each cache line read serves all of them.
constexpr std::size_t Block = 16;

void transformStridedAxis(std::vector<float>& g, std::vector<std::uint32_t>& point,
                          const std::size_t dim[3], int axis, float w)
{
  const std::size_t nx = dim[0], stride = axis == 1 ? dim[0] : dim[0] * dim[1];
  const std::size_t length = dim[axis], other = axis == 1 ? dim[2] : dim[1];
  const std::size_t blocks = (nx + Block - 1) / Block;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, other * blocks, 4),
                    [&](const tbb::blocked_range<std::size_t>& r)
                    {
                      LineScratch scratch;
                      std::vector<float> lineG(Block * length);
                      std::vector<std::uint32_t> linePoint(Block * length);
                      for (std::size_t task = r.begin(); task < r.end(); ++task)
                      {
                        const std::size_t o = task / blocks, x0 = (task % blocks) * Block;
                        const std::size_t width = std::min(Block, nx - x0);
                        // The first voxel of the block's lines: x0 in row o of the other axis.
                        const std::size_t first = x0 + o * (axis == 1 ? dim[0] * dim[1] : dim[0]);
                        for (std::size_t q = 0; q < length; ++q)
                          for (std::size_t b = 0; b < width; ++b)
                          {
                            lineG[b * length + q] = g[first + q * stride + b];
                            linePoint[b * length + q] = point[first + q * stride + b];
                          }
                        for (std::size_t b = 0; b < width; ++b)
                          transformLine(&lineG[b * length], &linePoint[b * length],
                                        static_cast<int>(length), w, scratch);
                        for (std::size_t q = 0; q < length; ++q)
                          for (std::size_t b = 0; b < width; ++b)
                          {
                            g[first + q * stride + b] = lineG[b * length + q];
                            point[first + q * stride + b] = linePoint[b * length + q];
                          }
                      }
                    });
}

// Step 2: the exact distance transform of the seed voxels (in voxel-centre distances), axis by
// axis; each voxel ends with the point of its nearest seed (NoPoint when there is none).
std::vector<std::uint32_t> nearestSeedPoints(const std::vector<std::size_t>& seeds,
                                             const std::atomic<std::uint64_t>* keys,
                                             const ImageGrid& grid)
{
  const std::size_t n = grid.voxelCount();
  std::vector<float> g(n, FarAway);
  std::vector<std::uint32_t> point(n, NoPoint);
  for (std::size_t v : seeds)
  {
    g[v] = 0;
    point[v] = static_cast<std::uint32_t>(keys[v].load(std::memory_order_relaxed) & 0xffffffffu);
  }
  const std::size_t dim[3] = {static_cast<std::size_t>(grid.dimensions[0]),
                              static_cast<std::size_t>(grid.dimensions[1]),
                              static_cast<std::size_t>(grid.dimensions[2])};
  const float w0 = static_cast<float>(grid.spacing[0] * grid.spacing[0]);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, dim[1] * dim[2], 16),
                    [&](const tbb::blocked_range<std::size_t>& r)
                    {
                      LineScratch scratch;
                      for (std::size_t line = r.begin(); line < r.end(); ++line)
                        transformLine(&g[line * dim[0]], &point[line * dim[0]],
                                      static_cast<int>(dim[0]), w0, scratch);
                    });
  transformStridedAxis(g, point, dim, 1, static_cast<float>(grid.spacing[1] * grid.spacing[1]));
  transformStridedAxis(g, point, dim, 2, static_cast<float>(grid.spacing[2] * grid.spacing[2]));
  return point;
}

// The nearest point found for a voxel so far, by squared distance in single precision (the
// output's; twice the throughput), ties to the lower index, so the result does not depend on the
// order candidates come in.
struct Candidate
{
  std::uint32_t index = NoPoint;
  float distance2 = std::numeric_limits<float>::infinity();

  void offer(const float* points, std::uint32_t p, const float x[3])
  {
    const float* q = points + 3 * static_cast<std::size_t>(p);
    const float dx = x[0] - q[0], dy = x[1] - q[1], dz = x[2] - q[2];
    const float d2 = dx * dx + dy * dy + dz * dz;
    if (d2 < distance2 || (d2 == distance2 && p < index))
    {
      index = p;
      distance2 = d2;
    }
  }
};

// Calls visit(v, x, around) for every voxel v of the image, x its centre and around its six
// face neighbours (v itself where the image ends), rows in parallel: no division per voxel.
template <class Visit>
void forEachVoxel(const ImageGrid& grid, Visit&& visit)
{
  const std::size_t nx = static_cast<std::size_t>(grid.dimensions[0]);
  const std::size_t ny = static_cast<std::size_t>(grid.dimensions[1]);
  const std::size_t nz = static_cast<std::size_t>(grid.dimensions[2]);
  const std::size_t slice = nx * ny;
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, ny * nz, 8),
      [&](const tbb::blocked_range<std::size_t>& r)
      {
        for (std::size_t row = r.begin(); row < r.end(); ++row)
        {
          const std::size_t j = row % ny, k = row / ny, first = row * nx;
          float x[3] = {0.0f, static_cast<float>(grid.origin[1] + j * grid.spacing[1]),
                        static_cast<float>(grid.origin[2] + k * grid.spacing[2])};
          for (std::size_t i = 0; i < nx; ++i)
          {
            const std::size_t v = first + i;
            x[0] = static_cast<float>(grid.origin[0] + i * grid.spacing[0]);
            const std::size_t around[6] = {i > 0 ? v - 1 : v,     i + 1 < nx ? v + 1 : v,
                                           j > 0 ? v - nx : v,    j + 1 < ny ? v + nx : v,
                                           k > 0 ? v - slice : v, k + 1 < nz ? v + slice : v};
            visit(v, x, around);
          }
        }
      });
}

// Step 3: each voxel's nearest point: from the band (exact), else its nearest seed's point, or
// a point outside the image when nearer.
void assignVoxels(const float* points, const ImageGrid& grid,
                  const std::atomic<std::uint64_t>* keys, const std::vector<std::uint32_t>& seed,
                  const detail::KdTree* outsideTree, const std::vector<std::uint32_t>& outsideIndex,
                  DistanceImage& out)
{
  forEachVoxel(grid,
               [&](std::size_t v, const float* x, const std::size_t*)
               {
                 Candidate c;
                 const std::uint64_t key = keys[v].load(std::memory_order_relaxed);
                 out.exact[v] = key != NoKey ? 1 : 0;
                 if (key != NoKey)
                   c.offer(points, static_cast<std::uint32_t>(key & 0xffffffffu), x);
                 else
                 {
                   if (seed[v] != NoPoint)
                     c.offer(points, seed[v], x);
                   if (outsideTree)
                   {
                     const double q[3] = {x[0], x[1], x[2]};
                     c.offer(points, outsideIndex[outsideTree->nearest(q)], x);
                   }
                 }
                 out.nearest[v] = c.index;
                 out.distance[v] = static_cast<float>(std::sqrt(c.distance2));
               });
}

// Step 4: beyond the band, each voxel also tries the points its six neighbours found (read from
// a copy, so the order of the voxels does not matter): the seed nearest to a voxel's centre need
// not hold the point nearest to it, and a neighbour's often does.
void refineBeyondBand(const float* points, const ImageGrid& grid, DistanceImage& out)
{
  const std::vector<std::uint32_t> found = out.nearest;
  forEachVoxel(grid,
               [&](std::size_t v, const float* x, const std::size_t* around)
               {
                 if (out.exact[v])
                   return;
                 Candidate c;
                 c.offer(points, found[v], x);
                 for (int a = 0; a < 6; ++a)
                   if (found[around[a]] != c.index)
                     c.offer(points, found[around[a]], x);
                 out.nearest[v] = c.index;
                 out.distance[v] = static_cast<float>(std::sqrt(c.distance2));
               });
}

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

  const PointsByVoxel sorted = sortPoints(points, count, grid);
  const std::vector<std::uint32_t> seed = nearestSeedPoints(sorted.seeds, keys.get(), grid);
  std::unique_ptr<detail::KdTree> outsideTree;
  if (!sorted.outsideIndex.empty())
    outsideTree =
        std::make_unique<detail::KdTree>(sorted.outside.data(), sorted.outsideIndex.size());

  const std::size_t n = grid.voxelCount();
  out.distance.resize(n);
  out.nearest.resize(n);
  out.exact.resize(n);
  const std::vector<float> single(points, points + 3 * count);
  assignVoxels(single.data(), grid, keys.get(), seed, outsideTree.get(), sorted.outsideIndex, out);
  refineBeyondBand(single.data(), grid, out);
  for (std::uint8_t e : out.exact)
    out.bandVoxels += e;
  return out;
}

void distanceGradient(const double* points, const ImageGrid& grid, const DistanceImage& image,
                      float* out)
{
  forEachVoxel(grid,
               [&](std::size_t v, const float* x, const std::size_t*)
               {
                 const double* p = points + 3 * image.nearest[v];
                 const double d = image.distance[v];
                 for (int c = 0; c < 3; ++c)
                   out[3 * v + c] = d > 0 ? static_cast<float>((x[c] - p[c]) / d) : 0.0f;
               });
}

void gatherNearest(const DistanceImage& image, const float* perPoint, int components, float* out)
{
  const std::size_t m = static_cast<std::size_t>(components);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, image.nearest.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& r)
                    {
                      for (std::size_t v = r.begin(); v < r.end(); ++v)
                        std::copy_n(perPoint + m * static_cast<std::size_t>(image.nearest[v]), m,
                                    out + m * v);
                    });
}

void gatherNearest(const DistanceImage& image, const long long* perPoint, long long* out)
{
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, image.nearest.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& r)
                    {
                      for (std::size_t v = r.begin(); v < r.end(); ++v)
                        out[v] = perPoint[image.nearest[v]];
                    });
}

} // namespace dp
