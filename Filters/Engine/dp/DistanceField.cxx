// SPDX-License-Identifier: BSD-3-Clause
#include "dp/DistanceField.h"

#include "dp/detail/KdTree.h"

#include <openvdb/openvdb.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <queue>
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
  IndexGrid::Ptr Grid;
  std::unique_ptr<detail::KdTree> Tree;
  std::size_t Active = 0;

  double squaredDistanceToCentre(std::int32_t index, const Coord& c) const
  {
    const double* p = &Points[3 * static_cast<std::size_t>(index)];
    const double dx = p[0] - Voxel * c.x(), dy = p[1] - Voxel * c.y(), dz = p[2] - Voxel * c.z();
    return dx * dx + dy * dy + dz * dz;
  }
};

namespace
{
void initializeOpenVDB()
{
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// The 26 neighbour offsets of a voxel.
const std::vector<Coord>& neighbourhood()
{
  static const std::vector<Coord> offsets = []
  {
    std::vector<Coord> o;
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j)
        for (int k = -1; k <= 1; ++k)
          if (i || j || k)
            o.emplace_back(i, j, k);
    return o;
  }();
  return offsets;
}
void sortUnique(std::vector<Coord>& coords)
{
  std::sort(coords.begin(), coords.end());
  coords.erase(std::unique(coords.begin(), coords.end()), coords.end());
}

// An upper bound on the voxels within `band` of some point, computed on blocks `band` wide:
// every such voxel lies in a block that touches (26-neighbourhood) a block holding a point.
// O(N log N), no allocation proportional to the grid, so absurd settings fail at once.
double bandVoxelUpperBound(const double* points, std::size_t count, double voxel, double band)
{
  std::vector<std::array<std::int64_t, 3>> blocks;
  blocks.reserve(count);
  for (std::size_t i = 0; i < count; ++i)
    blocks.push_back({static_cast<std::int64_t>(std::floor(points[3 * i] / band)),
                      static_cast<std::int64_t>(std::floor(points[3 * i + 1] / band)),
                      static_cast<std::int64_t>(std::floor(points[3 * i + 2] / band))});
  std::sort(blocks.begin(), blocks.end());
  blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
  std::vector<std::array<std::int64_t, 3>> dilated;
  dilated.reserve(blocks.size() * 27);
  for (const auto& b : blocks)
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j)
        for (int k = -1; k <= 1; ++k)
          dilated.push_back({b[0] + i, b[1] + j, b[2] + k});
  std::sort(dilated.begin(), dilated.end());
  const auto unique = std::unique(dilated.begin(), dilated.end()) - dilated.begin();
  const double perBlock = std::pow(band / voxel + 1, 3);
  return static_cast<double>(unique) * perBlock;
}

} // namespace

DistanceField::DistanceField() : P(std::make_unique<Impl>()) {}
DistanceField::~DistanceField() = default;
DistanceField::DistanceField(DistanceField&&) noexcept = default;
DistanceField& DistanceField::operator=(DistanceField&&) noexcept = default;

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

  double largest = 0;
  for (std::size_t i = 0; i < 3 * count; ++i)
  {
    if (!std::isfinite(points[i]))
      throw std::invalid_argument("point " + std::to_string(i / 3) +
                                  " has a NaN or infinite coordinate");
    largest = std::max(largest, std::abs(points[i]));
  }
  if ((largest + band) / voxel > 1e9)
    throw GridTooLarge("VoxelSize " + std::to_string(voxel) +
                       " is too small for coordinates up to " + std::to_string(largest) +
                       " (voxel indices would overflow)");

  const double band2 = band * band;
  auto tooLarge = [&](double voxels)
  {
    return GridTooLarge("a distance field with VoxelSize " + std::to_string(voxel) +
                        " and BandWidth " + std::to_string(band) + " needs up to " +
                        std::to_string(static_cast<unsigned long long>(voxels)) +
                        " voxels, over the limit of " + std::to_string(options.maxActiveVoxels) +
                        ": use a larger voxel size or a narrower band");
  };
  const double bound = bandVoxelUpperBound(points, count, voxel, band);
  if (bound > static_cast<double>(options.maxActiveVoxels))
    throw tooLarge(bound);

  initializeOpenVDB();
  Impl next;
  next.Points.assign(points, points + 3 * count);
  next.Voxel = voxel;
  next.Band = band;
  next.Grid = IndexGrid::create(-1);
  next.Grid->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
  next.Grid->setName("NearestPointIndex");
  auto acc = next.Grid->getAccessor();

  // Offers point `index` to voxel c: taken when c is new (and within the band) or when the
  // point is closer to c's centre than what c holds. Returns whether c changed.
  auto offer = [&](std::int32_t index, const Coord& c)
  {
    const double d2 = next.squaredDistanceToCentre(index, c);
    if (d2 > band2)
      return false;
    std::int32_t current = -1;
    if (acc.probeValue(c, current))
    {
      if (current == index || d2 >= next.squaredDistanceToCentre(current, c))
        return false;
    }
    else if (++next.Active > options.maxActiveVoxels)
    {
      throw tooLarge(static_cast<double>(next.Active));
    }
    acc.setValue(c, index);
    return true;
  };

  // Seeds: each point is offered to the 27 voxels around it. (Offering it only to its own
  // voxel would lose every point that is not the closest to its voxel's centre, although it
  // may be the nearest point of the next voxel.)
  std::vector<Coord> front;
  front.reserve(count);
  for (std::size_t i = 0; i < count; ++i)
  {
    const double* p = &next.Points[3 * i];
    const Coord centre(static_cast<int>(std::lround(p[0] / voxel)),
                       static_cast<int>(std::lround(p[1] / voxel)),
                       static_cast<int>(std::lround(p[2] / voxel)));
    if (offer(static_cast<std::int32_t>(i), centre))
      front.push_back(centre);
    for (const Coord& offset : neighbourhood())
      if (offer(static_cast<std::int32_t>(i), centre + offset))
        front.push_back(centre + offset);
  }
  sortUnique(front);

  // Propagation (vector distance transform): each changed voxel offers its nearest point to
  // its 26 neighbours, until nothing changes.
  std::vector<Coord> following;
  while (!front.empty())
  {
    following.clear();
    for (const Coord& c : front)
    {
      const std::int32_t index = acc.getValue(c);
      for (const Coord& offset : neighbourhood())
        if (offer(index, c + offset))
          following.push_back(c + offset);
    }
    sortUnique(following);
    front.swap(following);
  }
  next.Tree = std::make_unique<detail::KdTree>(next.Points.data(), count);
  *P = std::move(next);
  // The kd-tree's adaptor points at next.Points' buffer, which moved along with the vector.
}

bool DistanceField::empty() const
{
  return !P->Grid;
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
  return P->Active;
}

std::size_t DistanceField::memoryBytes() const
{
  if (empty())
    return 0;
  return static_cast<std::size_t>(P->Grid->memUsage()) + P->Tree->memoryBytes() +
         P->Points.capacity() * sizeof(double);
}

std::int64_t DistanceField::nearestPoint(const double x[3], double* squaredDistance) const
{
  if (empty())
    throw std::logic_error("DistanceField::nearestPoint before build()");
  return P->Tree->nearest(x, squaredDistance);
}

std::int64_t DistanceField::voxelNearest(int i, int j, int k) const
{
  if (empty())
    return -1;
  std::int32_t value = -1;
  return P->Grid->tree().probeValue(Coord(i, j, k), value) ? value : -1;
}

DistanceSample DistanceField::sample(const double x[3]) const
{
  if (empty())
    throw std::logic_error("DistanceField::sample before build()");
  // An unregistered accessor: no locking, one per call, safe for concurrent readers.
  openvdb::tree::ValueAccessor<const IndexTree, false> acc(P->Grid->tree());
  const double v = P->Voxel;
  double t[3];
  int base[3];
  for (int k = 0; k < 3; ++k)
  {
    const double g = x[k] / v;
    base[k] = static_cast<int>(std::floor(g));
    t[k] = g - base[k];
  }
  DistanceSample s;
  s.inBand = true;
  double best = std::numeric_limits<double>::infinity();
  for (int corner = 0; corner < 8; ++corner)
  {
    const int bit[3] = {corner & 1, (corner >> 1) & 1, (corner >> 2) & 1};
    const Coord c(base[0] + bit[0], base[1] + bit[1], base[2] + bit[2]);
    std::int32_t index = -1;
    if (!acc.probeValue(c, index))
    {
      // Outside the band: the exact nearest point of this voxel centre.
      s.inBand = false;
      const double centre[3] = {v * c.x(), v * c.y(), v * c.z()};
      index = static_cast<std::int32_t>(P->Tree->nearest(centre));
    }
    const double* p = &P->Points[3 * static_cast<std::size_t>(index)];
    const double d[3] = {x[0] - p[0], x[1] - p[1], x[2] - p[2]};
    const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    // Trilinear weight of this corner, and its derivatives along each axis.
    double w[3], dw[3];
    for (int k = 0; k < 3; ++k)
    {
      w[k] = bit[k] ? t[k] : 1 - t[k];
      dw[k] = (bit[k] ? 1.0 : -1.0) / v;
    }
    const double weight = w[0] * w[1] * w[2];
    const double dweight[3] = {dw[0] * w[1] * w[2], w[0] * dw[1] * w[2], w[0] * w[1] * dw[2]};
    s.distance += weight * length;
    for (int k = 0; k < 3; ++k)
      s.gradient[k] += dweight[k] * length + (length > 0 ? weight * d[k] / length : 0.0);
    if (length < best)
    {
      best = length;
      s.nearest = index;
    }
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

std::vector<float> estimateNormals(const double* points, std::size_t count, std::size_t neighbours)
{
  std::vector<float> normals(3 * count, 0.0f);
  if (count == 0)
    return normals;
  const std::size_t k = std::max<std::size_t>(3, std::min(neighbours, count));
  const detail::KdTree tree(points, count);
  std::vector<std::uint32_t> graph(count * k);
  std::vector<std::size_t> degree(count);

  // Local PCA: the normal is the eigenvector of the smallest eigenvalue of the covariance.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 256),
                    [&](const tbb::blocked_range<std::size_t>& range)
                    {
                      std::vector<double> d2(k);
                      for (std::size_t i = range.begin(); i != range.end(); ++i)
                      {
                        std::uint32_t* ids = &graph[i * k];
                        degree[i] = tree.nearest(points + 3 * i, k, ids, d2.data());
                        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
                        for (std::size_t j = 0; j < degree[i]; ++j)
                          mean += Eigen::Vector3d(points + 3 * ids[j]);
                        mean /= static_cast<double>(degree[i]);
                        Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
                        for (std::size_t j = 0; j < degree[i]; ++j)
                        {
                          const Eigen::Vector3d d = Eigen::Vector3d(points + 3 * ids[j]) - mean;
                          covariance += d * d.transpose();
                        }
                        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
                        const Eigen::Vector3d n = solver.eigenvectors().col(0);
                        for (int c = 0; c < 3; ++c)
                          normals[3 * i + c] = static_cast<float>(n[c]);
                      }
                    });

  // Orientation: Prim's spanning tree on the neighbour graph with weight 1 - |n_i . n_j|, so
  // orientation crosses the flattest, most reliable edges first.
  auto dot = [&](std::size_t a, std::size_t b)
  {
    return normals[3 * a] * normals[3 * b] + normals[3 * a + 1] * normals[3 * b + 1] +
           normals[3 * a + 2] * normals[3 * b + 2];
  };
  std::vector<char> done(count, 0);
  // Seeds in order of decreasing x, so each connected part starts at its largest-x point.
  std::vector<std::uint32_t> order(count);
  for (std::size_t i = 0; i < count; ++i)
    order[i] = static_cast<std::uint32_t>(i);
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return points[3 * a] > points[3 * b]; });
  using Edge = std::pair<float, std::pair<std::uint32_t, std::uint32_t>>; // weight, (from, to)
  std::priority_queue<Edge, std::vector<Edge>, std::greater<Edge>> queue;
  for (std::uint32_t seed : order)
  {
    if (done[seed])
      continue;
    if (normals[3 * seed] < 0)
      for (int c = 0; c < 3; ++c)
        normals[3 * seed + c] = -normals[3 * seed + c];
    done[seed] = 1;
    auto push = [&](std::uint32_t from)
    {
      for (std::size_t j = 0; j < degree[from]; ++j)
      {
        const std::uint32_t to = graph[from * k + j];
        if (!done[to])
          queue.push({1.0f - std::abs(dot(from, to)), {from, to}});
      }
    };
    push(seed);
    while (!queue.empty())
    {
      const auto [from, to] = queue.top().second;
      queue.pop();
      if (done[to])
        continue;
      if (dot(from, to) < 0)
        for (int c = 0; c < 3; ++c)
          normals[3 * to + c] = -normals[3 * to + c];
      done[to] = 1;
      push(to);
    }
  }
  return normals;
}

} // namespace dp
