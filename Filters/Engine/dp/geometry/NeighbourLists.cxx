// SPDX-License-Identifier: BSD-3-Clause
#include "dp/geometry/NeighbourLists.h"

#include "dp/support/KdTree.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <utility>

namespace dp
{
namespace
{
// A search's candidates (squared distance to the query, point index) and what it chose.
struct Candidates
{
  std::vector<double> distance2;
  std::vector<std::uint32_t> ids;
  std::vector<double> scratch;
  std::vector<std::uint32_t> chosen;

  void clear()
  {
    distance2.clear();
    ids.clear();
  }
  void add(double d2, std::uint32_t id)
  {
    distance2.push_back(d2);
    ids.push_back(id);
  }
  // The k nearest candidates into `chosen` (ties at the k-th distance to the lower indices; the
  // rest in the candidates' order); returns the k-th squared distance. Needs k <= candidates.
  double choose(std::size_t k)
  {
    scratch.assign(distance2.begin(), distance2.end());
    std::nth_element(scratch.begin(), scratch.begin() + static_cast<std::ptrdiff_t>(k - 1),
                     scratch.end());
    const double kth = scratch[k - 1];
    chosen.clear();
    for (std::size_t i = 0; i < ids.size(); ++i)
      if (distance2[i] < kth)
        chosen.push_back(ids[i]);
    const std::size_t ties = chosen.size();
    for (std::size_t i = 0; i < ids.size(); ++i)
      if (distance2[i] == kth)
        chosen.push_back(ids[i]);
    if (chosen.size() > k)
    {
      std::sort(chosen.begin() + static_cast<std::ptrdiff_t>(ties), chosen.end());
      chosen.resize(k);
    }
    return kth;
  }
};

// A point's search tries the first radius, twice and four times it, then asks the kd-tree.
constexpr int Attempts = 3;
// The first radius in typical k-th neighbour distances (the ball then holds about 1.7 k points):
// 1.15, 1.3 and 1.45 took 22.9, 22.1 and 24.4 ms a frame of jumping (20 000 points, k = 16, one
// thread). The cells a radius spans, unless the grid would need more than 8 cells a point.
constexpr double RadiusPerNeighbourDistance = 1.3;
constexpr double CellsPerRadius = 2.0;

// The points stored cell by cell (x fastest) in a box of dims[0] x dims[1] x dims[2] cells.
struct PointGrid
{
  double lo[3] = {0, 0, 0};
  double cell = 1;
  std::int64_t dims[3] = {1, 1, 1};
  std::vector<std::uint32_t> first; // per cell, and one past the last: its first entry
  std::vector<std::uint32_t> ids;   // point indices, cell by cell (ascending within a cell)
  std::vector<double> xyz;          // their coordinates, 3 an entry

  std::int64_t coordinate(double x, int axis) const
  {
    const double u = std::floor((x - lo[axis]) / cell);
    return static_cast<std::int64_t>(std::clamp(u, 0.0, static_cast<double>(dims[axis] - 1)));
  }
  std::int64_t index(std::int64_t x, std::int64_t y, std::int64_t z) const
  {
    return x + dims[0] * (y + dims[1] * z);
  }
};

// The cells of size `cell` a grid over the box [lo, hi] has.
double cellsFor(const double lo[3], const double hi[3], double cell)
{
  double cells = 1;
  for (int a = 0; a < 3; ++a)
    cells *= std::floor((hi[a] - lo[a]) / cell) + 1;
  return cells;
}

// False when the box [lo, hi] needs more than maxCells cells of size `cell`.
bool buildGrid(PointGrid& grid, const double* points, std::size_t count, const double lo[3],
               const double hi[3], double cell, std::size_t maxCells)
{
  const double cells = cellsFor(lo, hi, cell);
  if (!(cells <= static_cast<double>(maxCells)))
    return false;
  for (int a = 0; a < 3; ++a)
  {
    grid.dims[a] = static_cast<std::int64_t>(std::floor((hi[a] - lo[a]) / cell) + 1);
    grid.lo[a] = lo[a];
  }
  grid.cell = cell;
  const auto total = static_cast<std::size_t>(cells);
  std::vector<std::uint32_t> cellOf(count);
  grid.first.assign(total + 1, 0);
  for (std::size_t i = 0; i < count; ++i)
  {
    const double* p = points + 3 * i;
    cellOf[i] = static_cast<std::uint32_t>(
        grid.index(grid.coordinate(p[0], 0), grid.coordinate(p[1], 1), grid.coordinate(p[2], 2)));
    ++grid.first[cellOf[i] + 1];
  }
  for (std::size_t c = 0; c < total; ++c)
    grid.first[c + 1] += grid.first[c];
  std::vector<std::uint32_t> next(grid.first.begin(), grid.first.end() - 1);
  grid.ids.resize(count);
  grid.xyz.resize(3 * count);
  for (std::size_t i = 0; i < count; ++i)
  {
    const std::uint32_t entry = next[cellOf[i]]++;
    grid.ids[entry] = static_cast<std::uint32_t>(i);
    std::copy(points + 3 * i, points + 3 * i + 3, &grid.xyz[3 * entry]);
  }
  return true;
}

// The points within `radius` of p into `out` (squared distance to p, index): those of the cells
// the cube p +- radius overlaps, filtered.
void gatherBall(const PointGrid& grid, const double p[3], double radius, Candidates& out)
{
  // A margin for the rounding of cell coordinates: a point on the cube's wall may be filed in
  // the cell beyond it.
  const double reach = radius + 1e-9 * grid.cell;
  std::int64_t from[3], to[3];
  for (int a = 0; a < 3; ++a)
  {
    from[a] = grid.coordinate(p[a] - reach, a);
    to[a] = grid.coordinate(p[a] + reach, a);
  }
  const double radius2 = radius * radius;
  out.clear();
  for (std::int64_t z = from[2]; z <= to[2]; ++z)
    for (std::int64_t y = from[1]; y <= to[1]; ++y)
    {
      // One row of cells is one run of entries.
      const std::uint32_t begin = grid.first[static_cast<std::size_t>(grid.index(from[0], y, z))];
      const std::uint32_t end = grid.first[static_cast<std::size_t>(grid.index(to[0], y, z)) + 1];
      for (std::uint32_t e = begin; e < end; ++e)
      {
        const double dx = grid.xyz[3 * e] - p[0], dy = grid.xyz[3 * e + 1] - p[1],
                     dz = grid.xyz[3 * e + 2] - p[2];
        const double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 <= radius2)
          out.add(d2, grid.ids[e]);
      }
    }
}

// The k nearest of p by the grid (into found.chosen, their k-th squared distance into *kth2),
// within `radius` or, failing that, twice and four times it: false when that is not enough.
// (Every point within the radius is gathered, so k of them found are the k nearest.)
bool searchGrid(const PointGrid& grid, const double p[3], std::size_t k, double radius,
                int attempts, Candidates& found, double* kth2 = nullptr)
{
  for (int attempt = 0; attempt < attempts; ++attempt, radius *= 2)
  {
    gatherBall(grid, p, radius, found);
    if (found.ids.size() < k)
      continue;
    const double kth = found.choose(k);
    if (kth2)
      *kth2 = kth;
    return true;
  }
  return false;
}

// The search's first radius (about the typical k-th neighbour distance: the median of 64 points
// spread through the cloud, found on a first grid of about one cell a point) and its cell.
struct GridSize
{
  double radius = 0; // 0: no grid of at most maxCells cells suits the points (far outliers)
  double cell = 0;
};
GridSize chooseSize(const double* points, std::size_t count, std::size_t k, const double lo[3],
                    const double hi[3], std::size_t maxCells)
{
  double extent = 0;
  for (int a = 0; a < 3; ++a)
    extent = std::max(extent, hi[a] - lo[a]);
  if (!std::isfinite(extent))
    return {};
  if (extent == 0)
    return {1, 1}; // one point, repeated: a grid of one cell
  double volume = 1;
  for (int a = 0; a < 3; ++a)
    volume *= std::max(hi[a] - lo[a], 1e-3 * extent);
  const double rough = std::cbrt(volume / static_cast<double>(count));
  PointGrid grid;
  if (!buildGrid(grid, points, count, lo, hi, rough, maxCells))
    return {};
  // Radii doubling from `rough` until one holds the whole box.
  const int attempts = 2 + static_cast<int>(std::ceil(std::log2(2 * extent / rough)));
  const std::size_t samples = std::min<std::size_t>(64, count);
  std::vector<double> distances;
  Candidates found;
  double kth2 = 0;
  for (std::size_t s = 0; s < samples; ++s)
    if (searchGrid(grid, points + 3 * (s * count / samples), k, rough, attempts, found, &kth2))
      distances.push_back(std::sqrt(kth2));
  if (distances.empty())
    return {};
  std::nth_element(distances.begin(), distances.begin() + distances.size() / 2, distances.end());
  const double radius = RadiusPerNeighbourDistance * distances[distances.size() / 2];
  if (!(radius > 0))
    return {rough, rough}; // mostly repeated points: any radius finds them
  // As fine as the grid may be: at most maxCells cells (a cell too coarse for the radius would
  // give each point most of the cloud to sort through).
  const double wanted = radius / CellsPerRadius;
  double cell = wanted;
  while (cellsFor(lo, hi, cell) > static_cast<double>(maxCells))
    cell *= 1.1;
  if (cell > 4 * wanted)
    return {};
  return {radius, cell};
}

// The points' bounding box; false when a coordinate is NaN or infinite.
bool finiteBounds(const double* points, std::size_t count, double lo[3], double hi[3])
{
  bool finite = true;
  for (int a = 0; a < 3; ++a)
    lo[a] = HUGE_VAL, hi[a] = -HUGE_VAL;
  for (std::size_t i = 0; i < count; ++i)
    for (int a = 0; a < 3; ++a)
    {
      finite = finite && std::isfinite(points[3 * i + a]);
      lo[a] = std::min(lo[a], points[3 * i + a]);
      hi[a] = std::max(hi[a], points[3 * i + a]);
    }
  return finite;
}

// Every point's k nearest from the grid, in the grid's order (neighbouring queries read the same
// cells: cache); `unresolved` marks the points whose search did not settle within the radius.
void searchGridForAll(const PointGrid& grid, std::size_t k, double radius, NeighbourLists& lists,
                      std::vector<char>& unresolved)
{
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, grid.ids.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& range)
                    {
                      Candidates found;
                      for (std::size_t e = range.begin(); e != range.end(); ++e)
                      {
                        const std::uint32_t point = grid.ids[e];
                        if (searchGrid(grid, &grid.xyz[3 * e], k, radius, Attempts, found))
                          std::copy(found.chosen.begin(), found.chosen.end(),
                                    lists.ids.begin() + point * k);
                        else
                          unresolved[point] = 1;
                      }
                    });
}

// The k nearest of the unresolved points from a kd-tree: the k-th distance, then every point at
// most that far, ties at it going to the lower indices, as on the grid.
void searchTreeForUnresolved(const double* points, std::size_t count, std::size_t k,
                             const std::vector<char>& unresolved, NeighbourLists& lists)
{
  const support::KdTree tree(points, count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 256),
                    [&](const tbb::blocked_range<std::size_t>& range)
                    {
                      std::vector<std::uint32_t> ids(k);
                      std::vector<double> d2(k);
                      std::vector<std::pair<std::uint32_t, double>> within;
                      Candidates found;
                      for (std::size_t i = range.begin(); i != range.end(); ++i)
                      {
                        if (!unresolved[i])
                          continue;
                        const std::size_t reached =
                            tree.nearest(points + 3 * i, k, ids.data(), d2.data());
                        if (reached < k)
                        {
                          // Only with NaN or infinite coordinates (nothing compares nearer):
                          // what the tree found.
                          lists.degree[i] = reached;
                          std::copy(ids.begin(), ids.begin() + static_cast<std::ptrdiff_t>(reached),
                                    lists.ids.begin() + static_cast<std::ptrdiff_t>(i * k));
                          continue;
                        }
                        // (It holds the k found: their distances are at most the k-th.)
                        tree.within(points + 3 * i, d2[k - 1], within);
                        found.clear();
                        for (const auto& [id, distance2] : within)
                          found.add(distance2, id);
                        found.choose(k);
                        std::copy(found.chosen.begin(), found.chosen.end(),
                                  lists.ids.begin() + static_cast<std::ptrdiff_t>(i * k));
                      }
                    });
}
} // namespace

NeighbourLists nearestNeighbourLists(const double* points, std::size_t count, std::size_t k)
{
  NeighbourLists lists;
  k = std::min(k, count);
  lists.k = k;
  lists.ids.assign(count * k, 0);
  lists.degree.assign(count, k);
  if (count == 0 || k == 0)
    return lists;
  double lo[3], hi[3];
  const bool finite = finiteBounds(points, count, lo, hi);
  // Cells are numbered in 32 bits.
  const std::size_t maxCells = std::min<std::size_t>(8 * count + 64, UINT32_MAX - 1);
  // (A cloud with NaN or infinite coordinates has no cells to file them in: the kd-tree, as
  // before the grid.)
  const GridSize size = finite ? chooseSize(points, count, k, lo, hi, maxCells) : GridSize{};
  PointGrid grid;
  const bool gridded =
      size.radius > 0 && buildGrid(grid, points, count, lo, hi, size.cell, maxCells);
  std::vector<char> unresolved(count, gridded ? 0 : 1);
  if (gridded)
    searchGridForAll(grid, k, size.radius, lists, unresolved);
  if (std::find(unresolved.begin(), unresolved.end(), 1) != unresolved.end())
    searchTreeForUnresolved(points, count, k, unresolved, lists);
  return lists;
}

} // namespace dp
