// SPDX-License-Identifier: BSD-3-Clause
#include "dp/field/DistanceField.h"

#include "dp/field/PointBand.h"
#include "dp/support/KdTree.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/concurrent_unordered_map.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <string>

namespace dp
{

using IndexTree = openvdb::Int32Tree;
using IndexGrid = openvdb::Int32Grid;
using openvdb::Coord;

struct DistanceField::Impl
{
  std::vector<double> Points;
  double Voxel = 0;
  double Band = 0;
  IndexGrid::Ptr Grid; // eager mode: the band's voxels
  std::unique_ptr<support::KdTree> Tree;
  std::size_t Active = 0;
  bool Lazy = false;
  // Lazy mode: each voxel's nearest point, filled on first use, in blocks of 8^3 voxels made
  // when a voxel of theirs is first needed (-1: not yet). Thread-safe without locks on the
  // lookups (the tracker samples 8 voxels per vertex and evaluation): two threads filling one
  // voxel store the same value. A voxel costs 4 bytes and a block lookup, not a hash map
  // entry and its insertion.
  static constexpr int BlockBits = 3;
  static constexpr int BlockVoxels = 1 << (3 * BlockBits);
  struct LazyBlock
  {
    std::array<std::atomic<std::int32_t>, BlockVoxels> nearest;
    LazyBlock()
    {
      for (auto& n : nearest)
        n.store(-1, std::memory_order_relaxed);
    }
  };
  mutable tbb::concurrent_unordered_map<std::uint64_t, std::unique_ptr<LazyBlock>> Blocks;
  mutable std::atomic<std::size_t> Filled{0}; // voxels filled so far

  static std::uint64_t key(const Coord& c)
  {
    constexpr std::uint64_t mask = (1u << 21) - 1; // 21 bits a coordinate, offset to be positive
    return ((static_cast<std::uint64_t>(c.x() + (1 << 20)) & mask) << 42) |
           ((static_cast<std::uint64_t>(c.y() + (1 << 20)) & mask) << 21) |
           (static_cast<std::uint64_t>(c.z() + (1 << 20)) & mask);
  }

  // Lazy mode: voxel c's slot, in its block (made if needed). `last` remembers the block of the
  // previous call (a cell's 8 corners mostly share one).
  std::atomic<std::int32_t>& slotOf(const Coord& c, LazyBlock** last, Coord* lastBlock) const
  {
    const Coord b(c.x() >> BlockBits, c.y() >> BlockBits, c.z() >> BlockBits);
    constexpr int mask = (1 << BlockBits) - 1;
    const int local =
        (c.x() & mask) | ((c.y() & mask) << BlockBits) | ((c.z() & mask) << (2 * BlockBits));
    if (*last && *lastBlock == b)
      return (*last)->nearest[static_cast<std::size_t>(local)];
    const std::uint64_t k = key(b);
    auto found = Blocks.find(k);
    if (found == Blocks.end())
      found = Blocks.emplace(k, std::make_unique<LazyBlock>()).first;
    *last = found->second.get();
    *lastBlock = b;
    return (*last)->nearest[static_cast<std::size_t>(local)];
  }

  // The nearest point of voxel centre c, and whether it lies within the band. `last` and
  // `lastBlock` (lazy mode; may be null) carry the block of the previous call.
  template <typename Accessor>
  std::int32_t nearestOf(const Coord& c, Accessor* acc, bool& inBand, LazyBlock** last = nullptr,
                         Coord* lastBlock = nullptr) const
  {
    std::int32_t index = -1;
    if (acc && acc->probeValue(c, index))
    {
      inBand = true;
      return index;
    }
    const double centre[3] = {Voxel * c.x(), Voxel * c.y(), Voxel * c.z()};
    if (Lazy)
    {
      LazyBlock* none = nullptr; // no block carried over: this call's own
      Coord noneBlock;
      if (!last)
      {
        last = &none;
        lastBlock = &noneBlock;
      }
      std::atomic<std::int32_t>& slot = slotOf(c, last, lastBlock);
      index = slot.load(std::memory_order_relaxed);
      if (index < 0)
      {
        index = static_cast<std::int32_t>(Tree->nearest(centre));
        std::int32_t empty = -1;
        if (slot.compare_exchange_strong(empty, index, std::memory_order_relaxed))
          Filled.fetch_add(1, std::memory_order_relaxed);
      }
    }
    else
      index = static_cast<std::int32_t>(Tree->nearest(centre));
    const double* p = &Points[3 * static_cast<std::size_t>(index)];
    const double d2 = (centre[0] - p[0]) * (centre[0] - p[0]) +
                      (centre[1] - p[1]) * (centre[1] - p[1]) +
                      (centre[2] - p[2]) * (centre[2] - p[2]);
    inBand = Lazy && d2 <= Band * Band;
    return index;
  }

  /** Eager mode: the band's voxels with their nearest points (and the kd-tree). Throws
   *  GridTooLarge, before allocating the band, when it would exceed `maxActiveVoxels`. */
  void buildGrid(std::size_t count, std::size_t maxActiveVoxels);
  /** Sets every active voxel's nearest point; switches off those beyond the band. */
  void fillNearest();
};

namespace
{
void initializeOpenVDB()
{
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

} // namespace

DistanceField::DistanceField() : P(std::make_unique<Impl>()) {}
DistanceField::~DistanceField() = default;
DistanceField::DistanceField(DistanceField&&) noexcept = default;
DistanceField& DistanceField::operator=(DistanceField&&) noexcept = default;

namespace
{
// The largest |coordinate| of the points; throws naming the first point with a NaN or infinite
// coordinate.
double largestCoordinate(const double* points, std::size_t count)
{
  requireFinitePoints(points, count);
  double largest = 0;
  for (std::size_t i = 0; i < 3 * count; ++i)
    largest = std::max(largest, std::abs(points[i]));
  return largest;
}
} // namespace

void requireFinitePoints(const double* points, std::size_t count)
{
  for (std::size_t i = 0; i < 3 * count; ++i)
    if (!std::isfinite(points[i]))
      throw std::invalid_argument("point " + std::to_string(i / 3) +
                                  " has a NaN or infinite coordinate");
}

void DistanceField::Impl::buildGrid(std::size_t count, std::size_t maxActiveVoxels)
{
  // A voxel whose centre is within the band of a point p lies at most `reach` voxels
  // (Chebyshev) from the voxel holding p: a point is at least (k - 1/2) voxels from a centre
  // k voxels away.
  const int reach = static_cast<int>(std::floor(Band / Voxel + 0.5));
  initializeOpenVDB();
  Grid = IndexGrid::create(-1);
  // The grid keeps OpenVDB's identity transform: coordinates are mapped to voxels here, and
  // OpenVDB refuses linear transforms whose scale cubed is below 1e-8 (a 2 mm voxel).
  Grid->setName("NearestPointIndex");
  IndexTree& tree = Grid->tree();

  // Topology: the voxels holding a point, dilated (26-neighbourhood) by `reach`.
  support::seedPointVoxels(tree, Points.data(), count, Voxel, 0);
  // Memory guard before dilating: nothing proportional to the band is allocated when the
  // settings are absurd.
  const double bound = support::bandVoxelBound(tree, reach);
  if (bound > static_cast<double>(maxActiveVoxels))
    throw GridTooLarge("a distance field with VoxelSize " + std::to_string(Voxel) +
                       " and BandWidth " + std::to_string(Band) + " needs up to " +
                       std::to_string(static_cast<unsigned long long>(bound)) +
                       " voxels, over the limit of " + std::to_string(maxActiveVoxels) +
                       ": use a larger voxel size or a narrower band");
  // The kd-tree builds while the band is dilated.
  tbb::task_group kdBuild;
  kdBuild.run([&] { Tree = std::make_unique<support::KdTree>(Points.data(), count); });
  support::dilateBand(tree, reach);
  kdBuild.wait();
  fillNearest();
}

void DistanceField::Impl::fillNearest()
{
  // The exact nearest point of every voxel centre (kd-tree), in parallel over leaves; voxels
  // farther than the band from every point are switched off and pruned.
  IndexTree& tree = Grid->tree();
  const double band2 = Band * Band;
  openvdb::tree::LeafManager<IndexTree> leaves(tree);
  leaves.foreach (
      [&](IndexTree::LeafNodeType& leaf, std::size_t)
      {
        const auto active = leaf.getValueMask(); // a copy: the loop switches voxels off
        for (auto it = active.beginOn(); it; ++it)
        {
          const openvdb::Index offset = it.pos();
          const Coord c = leaf.offsetToGlobalCoord(offset);
          const double centre[3] = {Voxel * c.x(), Voxel * c.y(), Voxel * c.z()};
          double d2 = 0;
          const auto index = static_cast<std::int32_t>(Tree->nearest(centre, &d2));
          if (d2 <= band2)
            leaf.setValueOnly(offset, index);
          else
            leaf.setValueOff(offset, -1);
        }
      });
  openvdb::tools::pruneInactive(tree);
  Active = static_cast<std::size_t>(tree.activeVoxelCount());
}

void DistanceField::build(const double* points, std::size_t count,
                          const DistanceFieldOptions& options)
{
  if (count == 0 || !points)
    throw std::invalid_argument("the distance field needs at least one point");
  if (count > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw std::invalid_argument("too many points for one distance field (at most 2^31 - 1)");
  const double voxel = options.voxelSize;
  if (!(voxel > 0) || !std::isfinite(voxel))
    throw std::invalid_argument("VoxelSize must be a positive number, got " +
                                std::to_string(voxel));
  const double band = options.bandWidth == 0 ? 3 * voxel : options.bandWidth;
  if (!(band > 0) || !std::isfinite(band))
    throw std::invalid_argument("BandWidth must be a positive number, got " + std::to_string(band));
  const double largest = largestCoordinate(points, count);
  if ((largest + band) / voxel > 1e9)
    throw GridTooLarge("VoxelSize " + std::to_string(voxel) +
                       " is too small for coordinates up to " + std::to_string(largest) +
                       " (voxel indices would overflow)");
  if (options.lazy && (largest + band) / voxel > (1 << 20) - 2)
    throw GridTooLarge("VoxelSize " + std::to_string(voxel) +
                       " is too small for coordinates up to " + std::to_string(largest) +
                       " in lazy mode (voxel indices limited to 2^20)");

  // Built aside, then adopted: a build that throws leaves the field as it was.
  auto next = std::make_unique<Impl>();
  next->Points.assign(points, points + 3 * count);
  next->Voxel = voxel;
  next->Band = band;
  next->Lazy = options.lazy;
  if (options.lazy)
    next->Tree = std::make_unique<support::KdTree>(next->Points.data(), count);
  else
    next->buildGrid(count, options.maxActiveVoxels);
  // The kd-tree's adaptor points into next->Points' buffer, which moves along with the Impl.
  P = std::move(next);
}

bool DistanceField::empty() const
{
  return !P->Tree;
}
double DistanceField::voxelSize() const
{
  return P->Voxel;
}
double DistanceField::bandWidth() const
{
  return P->Band;
}
std::size_t DistanceField::numberOfPoints() const
{
  return P->Points.size() / 3;
}
const double* DistanceField::points() const
{
  return P->Points.data();
}
std::size_t DistanceField::activeVoxelCount() const
{
  return P->Lazy ? P->Filled.load() : P->Active;
}

std::size_t DistanceField::memoryBytes() const
{
  if (empty())
    return 0;
  // Lazy mode has no grid: its blocks, each with a map entry (key, pointer and the map's node
  // and bucket pointers, about 40 bytes).
  const std::size_t voxels = P->Grid ? static_cast<std::size_t>(P->Grid->memUsage())
                                     : P->Blocks.size() * (sizeof(Impl::LazyBlock) + 40);
  return voxels + P->Tree->memoryBytes() + P->Points.capacity() * sizeof(double);
}

std::int64_t DistanceField::nearestPoint(const double x[3], double* squaredDistance) const
{
  if (empty())
    throw std::logic_error("DistanceField::nearestPoint before build()");
  return P->Tree->nearest(x, squaredDistance);
}

std::size_t DistanceField::nearestPoints(const double x[3], std::size_t k, std::uint32_t* indices,
                                         double* squaredDistances) const
{
  if (empty())
    throw std::logic_error("DistanceField::nearestPoints before build()");
  return P->Tree->nearest(x, k, indices, squaredDistances);
}

std::int64_t DistanceField::voxelNearest(int i, int j, int k) const
{
  if (empty())
    return -1;
  bool inBand = false;
  openvdb::tree::ValueAccessor<const IndexTree, false>* none = nullptr;
  if (P->Grid)
  {
    std::int32_t value = -1;
    return P->Grid->tree().probeValue(Coord(i, j, k), value) ? value : -1;
  }
  const std::int32_t index = P->nearestOf(Coord(i, j, k), none, inBand);
  return inBand ? index : -1;
}

const VoxelCell& DistanceField::locate(const double x[3], VoxelCell* cell, double t[3]) const
{
  if (empty())
    throw std::logic_error("DistanceField::sample before build()");
  const double v = P->Voxel;
  int base[3];
  for (int k = 0; k < 3; ++k)
  {
    const double g = x[k] / v;
    base[k] = static_cast<int>(std::floor(g));
    t[k] = g - base[k];
  }
  if (!cell->valid || cell->base[0] != base[0] || cell->base[1] != base[1] ||
      cell->base[2] != base[2])
  {
    // An unregistered accessor: no locking, one per call, safe for concurrent readers.
    using Accessor = openvdb::tree::ValueAccessor<const IndexTree, false>;
    std::unique_ptr<Accessor> acc = P->Grid ? std::make_unique<Accessor>(P->Grid->tree()) : nullptr;
    cell->inBand = true;
    Impl::LazyBlock* lastBlock = nullptr;
    Coord lastBlockCoord;
    for (int corner = 0; corner < 8; ++corner)
    {
      const Coord c(base[0] + (corner & 1), base[1] + ((corner >> 1) & 1),
                    base[2] + ((corner >> 2) & 1));
      bool cornerInBand = false;
      cell->nearest[corner] = P->nearestOf(c, acc.get(), cornerInBand, &lastBlock, &lastBlockCoord);
      cell->inBand = cell->inBand && cornerInBand;
    }
    std::copy(base, base + 3, cell->base);
    cell->valid = true;
  }
  return *cell;
}

namespace
{
// Trilinear weight of a corner (bits i j k) at fractional position t, and its gradient.
inline double cornerWeight(int corner, const double t[3], double voxel, double gradient[3])
{
  double w[3], dw[3];
  for (int k = 0; k < 3; ++k)
  {
    const bool bit = (corner >> k) & 1;
    w[k] = bit ? t[k] : 1 - t[k];
    dw[k] = (bit ? 1.0 : -1.0) / voxel;
  }
  gradient[0] = dw[0] * w[1] * w[2];
  gradient[1] = w[0] * dw[1] * w[2];
  gradient[2] = w[0] * w[1] * dw[2];
  return w[0] * w[1] * w[2];
}
} // namespace

template <typename CornerValue>
DistanceSample DistanceField::interpolate(const double x[3], VoxelCell* cell,
                                          CornerValue cornerValue) const
{
  VoxelCell local;
  double t[3];
  const VoxelCell& corners = locate(x, cell ? cell : &local, t);
  const double v = P->Voxel;
  DistanceSample s;
  s.inBand = corners.inBand;
  double best = std::numeric_limits<double>::infinity();
  for (int corner = 0; corner < 8; ++corner)
  {
    const double centre[3] = {v * (corners.base[0] + (corner & 1)),
                              v * (corners.base[1] + ((corner >> 1) & 1)),
                              v * (corners.base[2] + ((corner >> 2) & 1))};
    const std::int32_t index = corners.nearest[corner];
    const double* p = &P->Points[3 * static_cast<std::size_t>(index)];
    double valueGradient[3] = {0, 0, 0}, dWeight[3];
    const double weight = cornerWeight(corner, t, v, dWeight);
    const double value = cornerValue(centre, index, p, weight, valueGradient);
    s.distance += weight * value;
    for (int k = 0; k < 3; ++k)
      s.gradient[k] += dWeight[k] * value + weight * valueGradient[k];
    const double toX = (x[0] - p[0]) * (x[0] - p[0]) + (x[1] - p[1]) * (x[1] - p[1]) +
                       (x[2] - p[2]) * (x[2] - p[2]);
    if (toX < best)
    {
      best = toX;
      s.nearest = index;
    }
  }
  return s;
}

DistanceSample DistanceField::sample(const double x[3], VoxelCell* cell) const
{
  // Each corner: the exact distance from the voxel centre to its nearest point (a constant).
  return interpolate(x, cell,
                     [](const double* centre, std::int32_t, const double* p, double, double*)
                     {
                       return std::sqrt((centre[0] - p[0]) * (centre[0] - p[0]) +
                                        (centre[1] - p[1]) * (centre[1] - p[1]) +
                                        (centre[2] - p[2]) * (centre[2] - p[2]));
                     });
}

DistanceSample DistanceField::sampleToPlanes(const double x[3], const float* normals, double reach,
                                             VoxelCell* cell, PlaneQuadric* quadric) const
{
  // D^2 = sum_c w_c [ (n_c.(x - p_c))^2 + max(0, |x - p_c| - reach)^2 ] over the 8 corners c
  // (trilinear weights w_c, p_c a corner's nearest point, n_c its normal): the mean squared
  // distance to the corners' tangent planes, plus, far from the points, the squared distance
  // beyond `reach`. Squared, the planes need no orientation; averaged, they have no false zero
  // between two sheets whose planes disagree; and with the weights held, each term is a linear
  // residual, so D^2 near x is exactly the quadric a Gauss-Newton step wants.
  PlaneQuadric q;
  DistanceSample s = interpolate(
      x, cell,
      [&](const double*, std::int32_t index, const double* p, double w, double* valueGradient)
      {
        const float* normal = normals + 3 * static_cast<std::size_t>(index);
        const double n[3] = {normal[0], normal[1], normal[2]};
        const double r[3] = {x[0] - p[0], x[1] - p[1], x[2] - p[2]};
        // The corner's residuals: a along n (the plane), f along u (beyond reach).
        const double a = n[0] * r[0] + n[1] * r[1] + n[2] * r[2];
        const double length = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        const double f = std::max(0.0, length - reach);
        const double u[3] = {f > 0 ? r[0] / length : 0.0, f > 0 ? r[1] / length : 0.0,
                             f > 0 ? r[2] / length : 0.0};
        for (int k = 0; k < 3; ++k)
          valueGradient[k] = 2 * (a * n[k] + f * u[k]);
        if (quadric)
        {
          int m = 0;
          for (int i = 0; i < 3; ++i)
          {
            q.vector[i] += w * (a * n[i] + f * u[i]);
            for (int j = i; j < 3; ++j)
              q.matrix[m++] += w * (n[i] * n[j] + u[i] * u[j]);
          }
        }
        return a * a + f * f;
      });
  // s holds D^2 and its gradient: D and dD = dD^2 / (2 D).
  const double squared = s.distance;
  s.distance = std::sqrt(squared);
  for (int k = 0; k < 3; ++k)
    s.gradient[k] = s.distance > 0 ? s.gradient[k] / (2 * s.distance) : 0.0;
  if (quadric)
  {
    q.constant = squared;
    *quadric = q;
  }
  return s;
}

void DistanceField::sampleMany(const double* positions, std::size_t count,
                               DistanceSample* out) const
{
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1024),
                    [&](const tbb::blocked_range<std::size_t>& range)
                    {
                      for (std::size_t i = range.begin(); i != range.end(); ++i)
                        out[i] = sample(positions + 3 * i);
                    });
}

} // namespace dp
