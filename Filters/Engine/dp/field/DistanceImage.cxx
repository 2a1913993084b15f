// SPDX-License-Identifier: BSD-3-Clause
#include "dp/field/DistanceImage.h"

#include "dp/support/KdTree.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
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
constexpr double Infinity = std::numeric_limits<double>::infinity();
constexpr float FarAway = std::numeric_limits<float>::infinity();
constexpr std::uint32_t NoPoint = std::numeric_limits<std::uint32_t>::max();

// The grid's checks (before anything is sized from it), then the points' and the band's.
void validateGrid(const ImageGrid& grid)
{
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
}

void validate(const double* points, std::size_t count, const ImageGrid& grid, double bandWidth)
{
  if (count == 0 || !points)
    throw std::invalid_argument("distance image: no points");
  if (count > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("distance image: " + std::to_string(count) +
                                " points, more than 2^32 - 1");
  validateGrid(grid);
  if (!(bandWidth >= 0) || !std::isfinite(bandWidth))
    throw std::invalid_argument("distance image: band width " + std::to_string(bandWidth) +
                                " (>= 0 wanted)");
  for (std::size_t i = 0; i < 3 * count; ++i)
    if (!std::isfinite(points[i]))
      throw std::invalid_argument("distance image: point " + std::to_string(i / 3) +
                                  " has a non-finite coordinate");
}

// Per-voxel arrays are filled in parallel: their pages are first touched by both threads (fresh
// memory's page faults are a large part of a big image's time), and only once (not as a vector's
// initialisation and then again by its filling).
template <class T>
void fillInParallel(T* a, std::size_t n, T value)
{
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 65536),
                    [&](const tbb::blocked_range<std::size_t>& r)
                    { std::fill(a + r.begin(), a + r.end(), value); });
}

template <class T>
std::unique_ptr<T[]> filledArray(std::size_t n, T value)
{
  std::unique_ptr<T[]> a(new T[n]);
  fillInParallel(a.get(), n, value);
  return a;
}

// The points grouped by the image row (y, z) they are nearest (clamped into the image: a point
// beyond it is only ever nearer to the rows than it is counted), by a counting sort, as a copy in
// that order: the band's pass reads the rows around each slice, contiguously. Also the seeds (the
// voxels the points fall in: their nearest point is exact, within half a diagonal) and the points
// outside the image (no seed: a kd-tree finds them beyond the band).
struct RowPoint
{
  double x, y, z;
  std::uint32_t index; // in the input
  std::int32_t column; // the voxel nearest along x, clamped into the image
};
struct PlacedPoints
{
  std::vector<std::size_t> first; // points of row r: [first[r], first[r + 1])
  std::vector<RowPoint> rows;     // in row order
  std::vector<std::size_t> seeds;
  std::vector<double> outside; // x y z of the points outside the image
  std::vector<std::uint32_t> outsideIndex;
};

// Where a point falls: its image row (y, z) and column (x), clamped into the image, and whether
// it lies inside the image.
struct PointPlace
{
  std::uint32_t row;
  std::int32_t column;
  bool inside;
};

std::vector<PointPlace> placeEachPoint(const double* points, std::size_t count,
                                       const ImageGrid& grid)
{
  const auto& dim = grid.dimensions;
  const std::size_t ny = static_cast<std::size_t>(dim[1]);
  std::vector<PointPlace> place(count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 4096),
                    [&](const tbb::blocked_range<std::size_t>& r)
                    {
                      for (std::size_t p = r.begin(); p < r.end(); ++p)
                      {
                        std::size_t index[3];
                        bool inside = true;
                        for (int a = 0; a < 3; ++a)
                        {
                          const double c =
                              std::round((points[3 * p + a] - grid.origin[a]) / grid.spacing[a]);
                          inside = inside && c >= 0 && c <= dim[a] - 1;
                          index[a] = static_cast<std::size_t>(std::clamp(c, 0.0, dim[a] - 1.0));
                        }
                        place[p] = {static_cast<std::uint32_t>(index[1] + index[2] * ny),
                                    static_cast<std::int32_t>(index[0]), inside};
                      }
                    });
  return place;
}

PlacedPoints placePoints(const double* points, std::size_t count, const ImageGrid& grid)
{
  const auto& dim = grid.dimensions;
  const std::size_t nx = static_cast<std::size_t>(dim[0]), ny = static_cast<std::size_t>(dim[1]);
  const std::vector<PointPlace> place = placeEachPoint(points, count, grid);
  PlacedPoints out;
  out.first.assign(ny * static_cast<std::size_t>(dim[2]) + 1, 0);
  for (const PointPlace& q : place)
    ++out.first[q.row + 1];
  for (std::size_t r = 1; r < out.first.size(); ++r)
    out.first[r] += out.first[r - 1];
  std::vector<std::size_t> next(out.first.begin(), out.first.end() - 1);
  out.rows.resize(count);
  for (std::size_t p = 0; p < count; ++p)
  {
    const double* x = points + 3 * p;
    const PointPlace& q = place[p];
    out.rows[next[q.row]++] = {x[0], x[1], x[2], static_cast<std::uint32_t>(p), q.column};
    if (q.inside)
      out.seeds.push_back(static_cast<std::size_t>(q.column) + nx * q.row);
    else
    {
      out.outside.insert(out.outside.end(), x, x + 3);
      out.outsideIndex.push_back(static_cast<std::uint32_t>(p));
    }
  }
  return out;
}

// The nearest point within the band so far of each voxel of one slice (z) of the image: the
// squared distance starts at the band's, so a voxel only takes points within the band.
struct SliceBest
{
  // Per voxel, the pair (squared distance in single precision, point index) as one integer
  // whose order is the pair's (a non-negative float's bits grow with its value): one comparison
  // keeps the nearer point, ties to the lower index.
  std::vector<std::uint64_t> key;
  bool any = false;

  static std::uint64_t keyOf(double distance2, std::uint32_t index)
  {
    const float d = static_cast<float>(distance2);
    std::uint32_t bits;
    std::memcpy(&bits, &d, sizeof bits);
    return (static_cast<std::uint64_t>(bits) << 32) | index;
  }
  void reset(std::size_t voxels, double band2)
  {
    key.assign(voxels, keyOf(band2, NoPoint)); // beyond the band: no point
    any = false;
  }
  std::uint32_t pointOf(std::size_t voxel) const
  {
    return static_cast<std::uint32_t>(key[voxel] & 0xffffffffu);
  }

  // Offers q to the voxels of row `first` (at x = xs) from q's own column outward, while within
  // the band: the distance grows either way from there (no square root or rounding to find the
  // ends). The order of the offers does not matter.
  void offerToRow(const RowPoint& q, double dyz, double band2, const std::vector<double>& xs,
                  std::size_t first)
  {
    const int nx = static_cast<int>(xs.size());
    std::uint64_t* row = key.data() + first;
    auto offer = [&](int i)
    {
      const double dx = xs[i] - q.x;
      const double d2 = dx * dx + dyz;
      if (d2 > band2)
        return false;
      const std::uint64_t k = keyOf(d2, q.index);
      if (k < row[i])
      {
        row[i] = k;
        any = true;
      }
      return true;
    };
    for (int i = q.column; i < nx && offer(i); ++i)
    {
    }
    for (int i = q.column - 1; i >= 0 && offer(i); --i)
    {
    }
  }
};

// Step 1, the exact band: each slice of voxels takes, voxel by voxel, the nearest of the points
// within `band` (ties to the lower index), reading the point rows whose band can reach it: a
// point is read once per slice it reaches, and one task writes each slice, so the result does not
// depend on the threads. NoPoint beyond the band.
void bandPoints(const PlacedPoints& placed, const ImageGrid& grid, double band, std::uint32_t* out)
{
  const auto& dim = grid.dimensions;
  const std::size_t nx = static_cast<std::size_t>(dim[0]);
  const std::size_t sliceSize = nx * static_cast<std::size_t>(dim[1]);
  fillInParallel(out, grid.voxelCount(), NoPoint);
  const double band2 = band * band;
  // A point's row is its nearest one, so it reaches rows within band / spacing + 1/2 of it.
  const int reachY = static_cast<int>(band / grid.spacing[1] + 0.5 + 1e-6);
  const int reachZ = static_cast<int>(band / grid.spacing[2] + 0.5 + 1e-6);
  std::vector<double> xs(nx); // the voxels' x
  for (std::size_t i = 0; i < nx; ++i)
    xs[i] = grid.origin[0] + static_cast<double>(i) * grid.spacing[0];
  tbb::parallel_for(
      tbb::blocked_range<int>(0, dim[2], 1),
      [&](const tbb::blocked_range<int>& r)
      {
        SliceBest slice;
        for (int k = r.begin(); k < r.end(); ++k)
        {
          if (slice.any || slice.key.empty())
            slice.reset(sliceSize, band2); // a slice no point improved is still as reset
          const double z = grid.origin[2] + k * grid.spacing[2];
          for (int sk = std::max(0, k - reachZ); sk <= std::min(dim[2] - 1, k + reachZ); ++sk)
            for (int sj = 0; sj < dim[1]; ++sj)
            {
              const std::size_t sourceRow = static_cast<std::size_t>(sk) * dim[1] + sj;
              const int fromJ = std::max(0, sj - reachY), toJ = std::min(dim[1] - 1, sj + reachY);
              for (std::size_t at = placed.first[sourceRow]; at < placed.first[sourceRow + 1]; ++at)
              {
                const RowPoint& q = placed.rows[at];
                const double dz2 = (z - q.z) * (z - q.z);
                if (dz2 > band2)
                  continue;
                for (int j = fromJ; j <= toJ; ++j)
                {
                  const double dy = grid.origin[1] + j * grid.spacing[1] - q.y;
                  const double dyz = dy * dy + dz2;
                  if (dyz <= band2)
                    slice.offerToRow(q, dyz, band2, xs, static_cast<std::size_t>(j) * nx);
                }
              }
            }
          if (slice.any)
            for (std::size_t v = 0; v < sliceSize; ++v)
              out[static_cast<std::size_t>(k) * sliceSize + v] = slice.pointOf(v);
        }
      });
}

// One axis of the separable transform on one line, in place: g[p] <- min_q g[q] + w (p - q)^2
// over the line's finite g (the lower envelope of parabolas), carrying the winner's point. In
// single precision and voxel units: it only picks each voxel's seed, whose point's distance is
// then computed exactly.
struct LineScratch
{
  std::vector<float> f, h, z;
  std::vector<int> v;
  std::vector<std::uint32_t> winner; // the point of the envelope's parabola k
};

void transformLine(float* g, std::uint32_t* point, int length, float w, LineScratch& s)
{
  s.f.resize(length);
  s.h.resize(length);
  s.v.resize(length);
  s.z.resize(length + 1);
  s.winner.resize(length);
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
    s.winner[k] = point[q];
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
    point[p] = s.winner[j];
  }
}

// Lines along y or z are strided: a block of Block neighbouring lines (along x) is copied into
// contiguous buffers, transformed and copied back, so each cache line read serves all of them.
constexpr std::size_t Block = 32;

// With `band` (the transform's last axis, whose distances are not needed after it), the voxels in
// the band take their band point instead of their seed's: the nearest point they know of.
void transformStridedAxis(float* g, std::uint32_t* point, const std::size_t dim[3], int axis,
                          float w, const std::uint32_t* band = nullptr)
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
                        bool seeded = false;
                        for (std::size_t q = 0; q < length; ++q)
                          for (std::size_t b = 0; b < width; ++b)
                          {
                            lineG[b * length + q] = g[first + q * stride + b];
                            linePoint[b * length + q] = point[first + q * stride + b];
                            seeded = seeded || lineG[b * length + q] != FarAway;
                          }
                        if (!seeded && !band)
                          continue; // no seed reaches these lines yet: they stay far away
                        for (std::size_t b = 0; seeded && b < width; ++b)
                          transformLine(&lineG[b * length], &linePoint[b * length],
                                        static_cast<int>(length), w, scratch);
                        for (std::size_t q = 0; q < length; ++q)
                          for (std::size_t b = 0; b < width; ++b)
                          {
                            const std::size_t v = first + q * stride + b;
                            if (band)
                              point[v] = band[v] != NoPoint ? band[v] : linePoint[b * length + q];
                            else
                            {
                              g[v] = lineG[b * length + q];
                              point[v] = linePoint[b * length + q];
                            }
                          }
                      }
                    });
}

// Step 2: the exact distance transform of the seed voxels (in voxel-centre distances), axis by
// axis, in `g` (one float per voxel, the caller's scratch); each voxel ends with the point of its
// nearest seed (NoPoint when there is none), or its band point in the band.
std::unique_ptr<std::uint32_t[]> nearestSeedPoints(const std::vector<std::size_t>& seeds,
                                                   const std::uint32_t* band, const ImageGrid& grid,
                                                   float* g)
{
  const std::size_t n = grid.voxelCount();
  fillInParallel(g, n, FarAway);
  std::unique_ptr<std::uint32_t[]> point = filledArray(n, NoPoint);
  for (std::size_t v : seeds)
  {
    g[v] = 0;
    point[v] = band[v];
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
                        transformLine(g + line * dim[0], &point[line * dim[0]],
                                      static_cast<int>(dim[0]), w0, scratch);
                    });
  transformStridedAxis(g, point.get(), dim, 1,
                       static_cast<float>(grid.spacing[1] * grid.spacing[1]));
  transformStridedAxis(g, point.get(), dim, 2,
                       static_cast<float>(grid.spacing[2] * grid.spacing[2]), band);
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

// Step 3: each voxel's nearest point. In the band, its own (exact; `band` may be out.nearest,
// read at each voxel before it is written). Beyond it, the nearest of the points it and its six
// neighbours know of (`known`: their band point, else their nearest seed's): the seed nearest to
// a voxel's centre need not hold the point nearest to it, and a neighbour's often does; and a
// point outside the image when nearer. Then the distance, and the gradient when asked for.
void assignVoxels(const float* points, const ImageGrid& grid, const std::uint32_t* band,
                  const std::uint32_t* known, const support::KdTree* outsideTree,
                  const std::vector<std::uint32_t>& outsideIndex, const DistanceImageView& out)
{
  forEachVoxel(grid,
               [&](std::size_t v, const float* x, const std::size_t* around)
               {
                 Candidate c;
                 out.exact[v] = band[v] != NoPoint ? 1 : 0;
                 if (known[v] != NoPoint)
                   c.offer(points, known[v], x);
                 if (!out.exact[v])
                 {
                   for (int a = 0; a < 6; ++a)
                   {
                     const std::uint32_t p = known[around[a]];
                     if (p != NoPoint && p != c.index)
                       c.offer(points, p, x);
                   }
                   if (outsideTree)
                   {
                     const double q[3] = {x[0], x[1], x[2]};
                     c.offer(points, outsideIndex[outsideTree->nearest(q)], x);
                   }
                 }
                 const float d = std::sqrt(c.distance2);
                 out.nearest[v] = c.index;
                 out.distance[v] = d;
                 if (!out.gradient)
                   return;
                 const float* p = points + 3 * static_cast<std::size_t>(c.index);
                 const float inverse = d > 0 ? 1.0f / d : 0.0f;
                 for (int k = 0; k < 3; ++k)
                   out.gradient[3 * v + k] = (x[k] - p[k]) * inverse;
               });
}

} // namespace

DistanceImageBand computeDistanceImage(const double* points, std::size_t count,
                                       const ImageGrid& grid, double bandWidth,
                                       const DistanceImageView& out)
{
  validate(points, count, grid, bandWidth);
  if (out.voxels != grid.voxelCount() || !out.distance || !out.nearest || !out.exact)
    throw std::invalid_argument("distance image: the output holds " + std::to_string(out.voxels) +
                                " voxels, the grid " + std::to_string(grid.voxelCount()));
  const auto& h = grid.spacing;
  const double halfDiagonal = 0.5 * std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
  DistanceImageBand result;
  result.bandWidth = std::max(bandWidth, halfDiagonal * (1 + 1e-9));
  const PlacedPoints placed = placePoints(points, count, grid);
  // The caller's arrays hold the band's points and the transform's squared distances until the
  // last pass writes them: no image-sized scratch of their own.
  const std::uint32_t* band = out.nearest;
  bandPoints(placed, grid, result.bandWidth, out.nearest);
  const std::unique_ptr<std::uint32_t[]> known =
      nearestSeedPoints(placed.seeds, band, grid, out.distance);
  std::unique_ptr<support::KdTree> outsideTree;
  if (!placed.outsideIndex.empty())
    outsideTree =
        std::make_unique<support::KdTree>(placed.outside.data(), placed.outsideIndex.size());
  const std::vector<float> single(points, points + 3 * count);
  assignVoxels(single.data(), grid, band, known.get(), outsideTree.get(), placed.outsideIndex, out);
  result.bandVoxels = static_cast<std::size_t>(std::count(out.exact, out.exact + out.voxels, 1));
  return result;
}

DistanceImage computeDistanceImage(const double* points, std::size_t count, const ImageGrid& grid,
                                   double bandWidth)
{
  validateGrid(grid); // before the arrays are sized from it; the rest is checked below
  DistanceImage image;
  image.distance.resize(grid.voxelCount());
  image.nearest.resize(grid.voxelCount());
  image.exact.resize(grid.voxelCount());
  static_cast<DistanceImageBand&>(image) =
      computeDistanceImage(points, count, grid, bandWidth, image.view());
  return image;
}

void gatherNearest(const DistanceImageView& image, const float* perPoint, int components,
                   float* out)
{
  const std::size_t m = static_cast<std::size_t>(components);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, image.voxels, 4096),
                    [&](const tbb::blocked_range<std::size_t>& r)
                    {
                      for (std::size_t v = r.begin(); v < r.end(); ++v)
                        std::copy_n(perPoint + m * static_cast<std::size_t>(image.nearest[v]), m,
                                    out + m * v);
                    });
}

void gatherNearest(const DistanceImageView& image, const long long* perPoint, long long* out)
{
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, image.voxels, 4096),
                    [&](const tbb::blocked_range<std::size_t>& r)
                    {
                      for (std::size_t v = r.begin(); v < r.end(); ++v)
                        out[v] = perPoint[image.nearest[v]];
                    });
}

} // namespace dp
