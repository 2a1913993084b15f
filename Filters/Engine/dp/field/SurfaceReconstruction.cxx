// SPDX-License-Identifier: BSD-3-Clause
#include "dp/field/SurfaceReconstruction.h"

#include "dp/detail/KdTree.h"
#include "dp/detail/Vec3.h"
#include "dp/field/PointBand.h"
#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/IsotropicRemesher.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace dp
{
namespace
{
using detail::cross;
using detail::norm;
using detail::operator+;
using detail::operator-;
using detail::operator*;
using Vec3 = detail::Vec3;
// The fine surface: the zero crossing of the field, the reference of the remeshing.
using FineMesh = detail::IndexedMesh;

struct Input
{
  const double* points;
  const float* normals;
  std::size_t count;
  const detail::KdTree& tree;
  double spacing; // median distance from a point to its nearest neighbour
};

// Signed distance from x to the data's tangent planes: the Gaussian-weighted mean over its k
// nearest points (Hoppe et al.), and the squared distances to those points.
double planeDistance(const Input& in, const double x[3], std::size_t k, double sigma2,
                     std::uint32_t* ids, double* d2)
{
  const std::size_t found = in.tree.nearest(x, k, ids, d2);
  double sum = 0, weights = 0;
  for (std::size_t j = 0; j < found; ++j)
  {
    const double* p = in.points + 3 * ids[j];
    const float* n = in.normals + 3 * ids[j];
    const double w = std::exp(-(d2[j] - d2[0]) / sigma2);
    sum += w * (n[0] * (x[0] - p[0]) + n[1] * (x[1] - p[1]) + n[2] * (x[2] - p[2]));
    weights += w;
  }
  return sum / weights;
}

// ---------------------------------------------------------------------------------------------
// The signed field and its zero crossing at a fine voxel size.

constexpr double NarrowBand = 3.0;      // half-width of the band around the points, in voxels
constexpr int CoarseRatio = 4;          // coarse voxel / fine voxel, for finding the holes
constexpr double VoxelPerSpacing = 1.5; // the fine voxel, in median point spacings

using detail::voxelOf;

// The value of hole voxels until interpolateHoles gives them one.
constexpr float Unknown = 1e6f;

// The plane distance in voxels, clamped to the band, at every active voxel of `grid` but those
// of holes.
void evaluate(const Input& in, openvdb::FloatGrid& grid, double h, std::size_t k, double sigma2)
{
  openvdb::tree::LeafManager<openvdb::FloatTree> leaves(grid.tree());
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, leaves.leafCount()),
      [&](const tbb::blocked_range<std::size_t>& range)
      {
        std::vector<std::uint32_t> ids(k);
        std::vector<double> d2(k);
        for (std::size_t l = range.begin(); l != range.end(); ++l)
          for (auto it = leaves.leaf(l).beginValueOn(); it; ++it)
          {
            if (*it == Unknown)
              continue;
            const openvdb::Coord c = it.getCoord();
            const double x[3] = {h * c.x(), h * c.y(), h * c.z()};
            const double distance = planeDistance(in, x, k, sigma2, ids.data(), d2.data()) / h;
            it.setValue(static_cast<float>(std::clamp(distance, -NarrowBand, NarrowBand)));
          }
      });
}

// The voxels of holes get the harmonic interpolation (successive over-relaxation of the mean of
// the six neighbours) of the values around them: the band's, and the pieces' outside it. Across
// a hole, between the inside (band voxels or hole voxels themselves, when the closing filled a
// thin part) and the outside, that is a membrane from rim to rim. A connected part of hole
// voxels that meets pieces of one sign only and whose band neighbours mostly have that sign
// too (a concave corner of the outside, the hollow of a cupped ear) is no hole: it takes that
// sign, so no surface appears there where a few band voxels next to it have the other one (a
// part too thin for the voxels).
// What each hole voxel's six neighbours are: other hole voxels (their index in `around`, else
// -1), and of the others the sum of their values (`fixed`), whether they are pieces outside the
// band of either sign (`meets`: bit 0 an inside piece, bit 1 an outside piece), and their signs
// in the band (`band`: positive ones less negative ones).
struct HoleNeighbours
{
  std::vector<std::array<int, 6>> around;
  std::vector<float> fixed;
  std::vector<std::uint8_t> meets;
  std::vector<int> band;
};

HoleNeighbours holeNeighbours(const openvdb::FloatGrid& grid,
                              const std::vector<openvdb::Coord>& holes)
{
  openvdb::Int32Grid::Ptr index = openvdb::Int32Grid::create(-1);
  {
    auto acc = index->getAccessor();
    for (std::size_t i = 0; i < holes.size(); ++i)
      acc.setValueOn(holes[i], static_cast<int>(i));
  }
  const std::size_t n = holes.size();
  HoleNeighbours h{std::vector<std::array<int, 6>>(n), std::vector<float>(n, 0.0f),
                   std::vector<std::uint8_t>(n, 0), std::vector<int>(n, 0)};
  auto acc = index->getConstAccessor();
  auto values = grid.getConstAccessor();
  for (std::size_t i = 0; i < n; ++i)
  {
    int e = 0;
    for (int axis = 0; axis < 3; ++axis)
      for (int side = -1; side <= 1; side += 2)
      {
        openvdb::Coord v = holes[i];
        v[axis] += side;
        const int j = acc.getValue(v);
        h.around[i][e++] = j;
        if (j >= 0)
          continue;
        const float neighbour = values.getValue(v);
        h.fixed[i] += neighbour;
        if (!values.isValueOn(v))
          h.meets[i] |= neighbour < 0 ? 1 : 2;
        else
          h.band[i] += neighbour < 0 ? -1 : 1;
      }
  }
  return h;
}

// Which hole voxels are free to take the interpolation: not those of a connected part that
// meets pieces of one sign only and whose band neighbours mostly have that sign too; those get
// that sign's background value in `value`.
std::vector<char> freeHoleVoxels(const HoleNeighbours& h, float background,
                                 std::vector<float>& value)
{
  const std::size_t n = h.around.size();
  std::vector<int> part(n, -1);
  std::vector<std::uint8_t> partMeets;
  std::vector<long> partBand;
  std::vector<std::size_t> stack;
  for (std::size_t seed = 0; seed < n; ++seed)
  {
    if (part[seed] >= 0)
      continue;
    const int p = static_cast<int>(partMeets.size());
    partMeets.push_back(0);
    partBand.push_back(0);
    part[seed] = p;
    stack.push_back(seed);
    while (!stack.empty())
    {
      const std::size_t i = stack.back();
      stack.pop_back();
      partMeets[p] |= h.meets[i];
      partBand[p] += h.band[i];
      for (int j : h.around[i])
        if (j >= 0 && part[j] < 0)
        {
          part[j] = p;
          stack.push_back(static_cast<std::size_t>(j));
        }
    }
  }
  std::vector<char> free(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    const std::uint8_t m = partMeets[part[i]];
    const long b = partBand[part[i]];
    free[i] = !((m == 1 && b < 0) || (m == 2 && b > 0));
    if (!free[i])
      value[i] = m == 1 ? -background : background;
  }
  return free;
}

void interpolateHoles(openvdb::FloatGrid& grid, const std::vector<openvdb::Coord>& holes,
                      float background)
{
  if (holes.empty())
    return;
  const HoleNeighbours h = holeNeighbours(grid, holes);
  std::vector<float> value(holes.size(), 0.0f);
  const std::vector<char> free = freeHoleVoxels(h, background, value);
  const int rounds = 200;
  const float omega = 1.9f;
  for (int round = 0; round < rounds; ++round)
    for (std::size_t i = 0; i < holes.size(); ++i)
    {
      if (!free[i])
        continue;
      float sum = h.fixed[i];
      for (int j : h.around[i])
        if (j >= 0)
          sum += value[j];
      value[i] += omega * (sum / 6 - value[i]);
    }
  auto acc = grid.getAccessor();
  for (std::size_t i = 0; i < holes.size(); ++i)
    acc.setValue(holes[i], value[i]);
}

// The space outside the band, in cells of Ratio^3 voxels. Its connected pieces (the outside,
// the inside of each closed part) each take the sign that most of the band's voxels along their
// border have; settle() sets the border voxels that disagree to it and gives every value
// outside the band its piece's sign. A patch of wrong normals then makes at worst a blister at
// the patch, where openvdb's signedFloodFill (which takes the sign of whichever band voxel its
// scan meets first) would carry the wrong sign far from the data, and a surface with it.
class OutsideBand
{
public:
  static constexpr int Ratio = 2;

  /** Cells over the band's bounding box and one more around it; every voxel of a cell that
   *  the band touches is made active, so that what lies outside the band is whole cells. */
  explicit OutsideBand(openvdb::FloatGrid& grid)
  {
    const openvdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
    for (int c = 0; c < 3; ++c)
    {
      Low[c] = floorDiv(box.min()[c]) - 1;
      Size[c] = floorDiv(box.max()[c]) + 2 - Low[c];
    }
    Label.assign(static_cast<std::size_t>(Size[0]) * Size[1] * Size[2], Free);
    std::vector<openvdb::Coord> cells;
    for (auto it = grid.cbeginValueOn(); it; ++it)
    {
      const openvdb::Coord c = cellOf(it.getCoord());
      if (Label[index(c)] == Free)
      {
        Label[index(c)] = Band;
        cells.push_back(c);
      }
    }
    auto acc = grid.getAccessor();
    for (const openvdb::Coord& c : cells)
      for (int i = 0; i < Ratio; ++i)
        for (int j = 0; j < Ratio; ++j)
          for (int l = 0; l < Ratio; ++l)
            acc.setActiveState(openvdb::Coord(Ratio * (c.x() + Low[0]) + i,
                                              Ratio * (c.y() + Low[1]) + j,
                                              Ratio * (c.z() + Low[2]) + l),
                               true);
  }

  /** The connected pieces of free cells (sharing faces) and their signs, from the band's
   *  values. */
  void findPieces(const openvdb::FloatGrid& grid)
  {
    for (int& l : Label)
      if (l != Band)
        l = Free;
    Inside.clear();
    std::vector<std::int64_t> votes, count;
    std::vector<std::size_t> stack;
    for (std::size_t seed = 0; seed < Label.size(); ++seed)
    {
      if (Label[seed] != Free)
        continue;
      const int piece = static_cast<int>(votes.size());
      votes.push_back(0);
      count.push_back(0);
      Label[seed] = piece;
      stack.push_back(seed);
      while (!stack.empty())
      {
        const std::size_t i = stack.back();
        stack.pop_back();
        forFaces(i,
                 [&](std::size_t j, int, int)
                 {
                   if (Label[j] == Free)
                   {
                     Label[j] = piece;
                     stack.push_back(j);
                   }
                 });
      }
    }
    auto acc = grid.getConstAccessor();
    border(
        [&](int piece, const openvdb::Coord& v)
        {
          const float value = acc.getValue(v);
          if (value != Unknown)
          {
            votes[piece] += value < 0 ? -1 : 1;
            ++count[piece];
          }
        });
    Mixed.clear();
    for (std::size_t p = 0; p < votes.size(); ++p)
    {
      Inside.push_back(votes[p] < 0);
      // Minority = (count - |votes|) / 2; a quarter of the border or more: open data.
      Mixed.push_back(count[p] >= 64 && count[p] - std::abs(votes[p]) >= count[p] / 2);
    }
  }

  /** Whether a piece's border has both signs in large parts: the data are open there (a sheet,
   *  a scan from one side) rather than closed with a few wrong normals. */
  bool open() const { return std::find(Mixed.begin(), Mixed.end(), true) != Mixed.end(); }

  /** -1 inside, +1 outside, 0 in the band, for a voxel. */
  int side(const openvdb::Coord& voxel) const
  {
    const openvdb::Coord c = cellOf(voxel);
    for (int axis = 0; axis < 3; ++axis)
      if (c[axis] < 0 || c[axis] >= Size[axis])
        return Inside[Label[0]] ? -1 : 1;
    const int l = Label[index(c)];
    return l < 0 ? 0 : (Inside[l] ? -1 : 1);
  }

  /** The border voxels of the pieces whose border mostly agrees, and whether their piece is
   *  inside. */
  void borderOfSettledPieces(std::vector<std::pair<openvdb::Coord, bool>>& out) const
  {
    border(
        [&](int piece, const openvdb::Coord& v)
        {
          if (!Mixed[piece])
            out.push_back({v, Inside[piece]});
        });
  }

  /** Border voxels to their piece's sign; every value outside the band (voxels of partly active
   *  leaves, tiles, the background) to its piece's sign. */
  void settle(openvdb::FloatGrid& grid, float background) const
  {
    auto acc = grid.getAccessor();
    border(
        [&](int piece, const openvdb::Coord& v)
        {
          const float value = acc.getValue(v);
          if (value != Unknown && !Mixed[piece] && (value < 0) != Inside[piece])
            acc.setValue(v, Inside[piece] ? -background : background);
        });
    for (auto it = grid.tree().beginValueOff(); it; ++it)
    {
      const openvdb::CoordBBox box = it.getBoundingBox();
      it.setValue(side((box.min() + box.max()) >> 1) < 0 ? -background : background);
    }
    // Outside the cells is the outermost piece (cell 0 is in it).
    grid.tree().root().setBackground(Inside[Label[0]] ? -background : background, false);
  }

private:
  static constexpr int Free = -2, Band = -1;
  int Low[3] = {0, 0, 0}, Size[3] = {0, 0, 0};
  std::vector<int> Label;   // per cell: Free, Band, or its piece
  std::vector<bool> Inside; // per piece
  std::vector<bool> Mixed;  // per piece: its border is of both signs in large parts

  static int floorDiv(int i) { return i >= 0 ? i / Ratio : -((-i + Ratio - 1) / Ratio); }
  openvdb::Coord cellOf(const openvdb::Coord& v) const
  {
    return openvdb::Coord(floorDiv(v.x()) - Low[0], floorDiv(v.y()) - Low[1],
                          floorDiv(v.z()) - Low[2]);
  }
  std::size_t index(const openvdb::Coord& c) const
  {
    return static_cast<std::size_t>(c.x()) +
           static_cast<std::size_t>(Size[0]) *
               (static_cast<std::size_t>(c.y()) + static_cast<std::size_t>(Size[1]) * c.z());
  }
  openvdb::Coord coordOf(std::size_t i) const
  {
    const auto nx = static_cast<std::size_t>(Size[0]), ny = static_cast<std::size_t>(Size[1]);
    return openvdb::Coord(static_cast<int>(i % nx), static_cast<int>((i / nx) % ny),
                          static_cast<int>(i / (nx * ny)));
  }
  // visit(j, axis, side) for each cell j sharing a face with cell i.
  template <typename Visit>
  void forFaces(std::size_t i, Visit visit) const
  {
    const openvdb::Coord c = coordOf(i);
    const std::int64_t stride[3] = {1, Size[0], static_cast<std::int64_t>(Size[0]) * Size[1]};
    for (int axis = 0; axis < 3; ++axis)
      for (int side = -1; side <= 1; side += 2)
      {
        const int n = c[axis] + side;
        if (n >= 0 && n < Size[axis])
          visit(static_cast<std::size_t>(static_cast<std::int64_t>(i) + side * stride[axis]), axis,
                side);
      }
  }
  // visit(piece, voxel) for each band voxel that shares a face with a free cell.
  template <typename Visit>
  void border(Visit visit) const
  {
    for (std::size_t i = 0; i < Label.size(); ++i)
    {
      if (Label[i] < 0)
        continue;
      const openvdb::Coord c = coordOf(i);
      forFaces(i,
               [&](std::size_t j, int axis, int side)
               {
                 if (Label[j] != Band)
                   return;
                 // The layer of the band cell's voxels next to cell i.
                 openvdb::Coord first(Ratio * (c.x() + Low[0]), Ratio * (c.y() + Low[1]),
                                      Ratio * (c.z() + Low[2]));
                 first[axis] += side > 0 ? Ratio : -1;
                 const int u = (axis + 1) % 3, w = (axis + 2) % 3;
                 for (int a = 0; a < Ratio; ++a)
                   for (int b = 0; b < Ratio; ++b)
                   {
                     openvdb::Coord v = first;
                     v[u] += a;
                     v[w] += b;
                     visit(Label[i], v);
                   }
               });
    }
  }
};

// Throws when the grid at voxel size h would hold more voxels than the options allow.
void checkGridSize(double voxels, double h, const ReconstructionOptions& options)
{
  if (voxels > static_cast<double>(options.maxActiveVoxels))
    throw std::runtime_error("surface reconstruction: the grid at voxel size " + std::to_string(h) +
                             " would exceed " + std::to_string(options.maxActiveVoxels) +
                             " voxels");
}

// The band: every voxel within NarrowBand voxels of a point, active, with no value yet.
openvdb::FloatGrid::Ptr pointBand(const Input& in, double h, const ReconstructionOptions& options)
{
  const float background = static_cast<float>(NarrowBand);
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(background);
  detail::seedPointVoxels(grid->tree(), in.points, in.count, h, background);
  const int reach = static_cast<int>(NarrowBand);
  checkGridSize(detail::bandVoxelBound(grid->tree(), reach), h, options);
  detail::dilateBand(grid->tree(), reach);
  return grid;
}

// Holes: on a coarse grid, the cells that a morphological closing of the points' cells adds
// (gaps in the data narrower than about twice `reach`, and concave corners). Their voxels
// outside the band are made active with the value Unknown and returned: the plane distance far
// from the data is unreliable (a wrongly oriented patch, or data passing through itself, would
// grow sheets there), so they are interpolated later, harmonically, between the band and the
// pieces outside it.
std::vector<openvdb::Coord> addHoleVoxels(openvdb::FloatGrid& grid, const Input& in, double h,
                                          double reach, const ReconstructionOptions& options)
{
  std::vector<openvdb::Coord> holes;
  const double H = CoarseRatio * h;
  const int closing = static_cast<int>(std::ceil(reach / H));
  if (closing <= 0)
    return holes;
  openvdb::MaskGrid::Ptr cells = openvdb::MaskGrid::create();
  detail::seedPointVoxels(cells->tree(), in.points, in.count, H, true);
  // The closing's dilation is bounded before it is built: a tiny voxel makes `closing` huge.
  // (The fine voxels it adds are counted after, with the band's.)
  checkGridSize(detail::bandVoxelBound(cells->tree(), closing), h, options);
  openvdb::MaskGrid::Ptr closed = cells->deepCopy();
  detail::dilateBand(closed->tree(), closing);
  openvdb::tools::erodeActiveValues(closed->tree(), closing, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                    openvdb::tools::IGNORE_TILES);
  closed->tree().topologyDifference(cells->tree());
  auto acc = grid.getAccessor();
  const int half = CoarseRatio / 2;
  for (auto it = closed->cbeginValueOn(); it; ++it)
  {
    // The cell's voxels (the cell of coarse voxel c is centred on CoarseRatio c).
    const openvdb::Coord c = it.getCoord();
    for (int i = -half; i < CoarseRatio - half; ++i)
      for (int j = -half; j < CoarseRatio - half; ++j)
        for (int l = -half; l < CoarseRatio - half; ++l)
        {
          const openvdb::Coord v(CoarseRatio * c.x() + i, CoarseRatio * c.y() + j,
                                 CoarseRatio * c.z() + l);
          if (!acc.isValueOn(v))
          {
            acc.setValueOn(v, Unknown);
            holes.push_back(v);
          }
        }
  }
  return holes;
}

// Normals against the pieces: each border voxel of the band (next to a piece whose border
// mostly agrees) asks the three points nearest to it whether their planes put it on its
// piece's side (the nearest only: beyond a thin part, those of its far side answer). A point
// that most of its voxels find on the wrong side has its normal the wrong way round (a patch
// oriented against the rest); those points are returned.
std::vector<std::uint32_t> wronglyOrientedPoints(const Input& in, const OutsideBand& outside,
                                                 double h, std::size_t k)
{
  std::vector<std::pair<openvdb::Coord, bool>> voxels; // border voxel, its piece inside
  outside.borderOfSettledPieces(voxels);
  std::vector<std::atomic<int>> support(in.count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, voxels.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& range)
                    {
                      std::vector<std::uint32_t> ids(k);
                      std::vector<double> d2(k);
                      for (std::size_t b = range.begin(); b != range.end(); ++b)
                      {
                        const auto& [v, inside] = voxels[b];
                        const double x[3] = {h * v.x(), h * v.y(), h * v.z()};
                        const std::size_t found =
                            in.tree.nearest(x, std::min<std::size_t>(k, 3), ids.data(), d2.data());
                        for (std::size_t j = 0; j < found; ++j)
                        {
                          const double* p = in.points + 3 * ids[j];
                          const float* n = in.normals + 3 * ids[j];
                          const double along =
                              n[0] * (x[0] - p[0]) + n[1] * (x[1] - p[1]) + n[2] * (x[2] - p[2]);
                          support[ids[j]] += (along < 0) == inside ? 1 : -1;
                        }
                      }
                    });
  std::vector<std::uint32_t> flipped;
  for (std::size_t i = 0; i < in.count; ++i)
    if (support[i] < 0)
      flipped.push_back(static_cast<std::uint32_t>(i));
  return flipped;
}

// The field evaluated again (with `corrected`, the normals after flipping) on the band's voxels
// whose neighbours may include a flipped point.
void reevaluateAround(openvdb::FloatGrid& grid, const Input& corrected,
                      const std::vector<std::uint32_t>& flipped, double h, std::size_t k,
                      double sigma2)
{
  openvdb::MaskGrid::Ptr touched = openvdb::MaskGrid::create();
  {
    auto acc = touched->getAccessor();
    for (std::uint32_t i : flipped)
      acc.setValueOn(voxelOf(corrected.points + 3 * i, h));
  }
  openvdb::tools::dilateActiveValues(touched->tree(), static_cast<int>(NarrowBand) + 2,
                                     openvdb::tools::NN_FACE_EDGE_VERTEX,
                                     openvdb::tools::IGNORE_TILES);
  auto acc = grid.getAccessor();
  std::vector<std::uint32_t> ids(k);
  std::vector<double> d2(k);
  for (auto it = touched->cbeginValueOn(); it; ++it)
  {
    const openvdb::Coord c = it.getCoord();
    if (!acc.isValueOn(c) || acc.getValue(c) == Unknown)
      continue;
    const double x[3] = {h * c.x(), h * c.y(), h * c.z()};
    const double distance = planeDistance(corrected, x, k, sigma2, ids.data(), d2.data()) / h;
    acc.setValue(c, static_cast<float>(std::clamp(distance, -NarrowBand, NarrowBand)));
  }
}

// The field's zero crossing as triangles in world units (quads split along their shorter
// diagonal, degenerate triangles dropped).
FineMesh zeroCrossing(const openvdb::FloatGrid& grid, double h)
{
  std::vector<openvdb::Vec3s> vertices;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(grid, vertices, triangles, quads, 0.0, 0.0);

  FineMesh mesh;
  mesh.positions.reserve(vertices.size());
  for (const auto& v : vertices)
    mesh.positions.push_back({h * v[0], h * v[1], h * v[2]});
  auto add = [&](unsigned a, unsigned b, unsigned c)
  {
    if (a != b && b != c && a != c)
      mesh.triangles.push_back({static_cast<int>(a), static_cast<int>(b), static_cast<int>(c)});
  };
  for (const auto& t : triangles)
    add(t[0], t[1], t[2]);
  for (const auto& q : quads)
  {
    // Split along the shorter diagonal: better-shaped triangles.
    const auto& p = mesh.positions;
    if (norm(p[q[0]] - p[q[2]]) <= norm(p[q[1]] - p[q[3]]))
    {
      add(q[0], q[1], q[2]);
      add(q[0], q[2], q[3]);
    }
    else
    {
      add(q[0], q[1], q[3]);
      add(q[1], q[2], q[3]);
    }
  }
  return mesh;
}

// The zero crossing of the band-limited signed field at voxel size h, as triangles. The band:
// every voxel within NarrowBand voxels of a point (the plane distance), plus the voxels of holes
// (interpolated). Outside the band, each piece of space takes the sign of most of its border
// (OutsideBand), so no crossing appears where the band ends; points whose normals most of
// their piece's border contradicts are flipped first. `open` tells whether some piece's border
// has both signs in large parts (open data: the crossings at the band's end there are to be
// dropped).
FineMesh meshField(const Input& in, double h, double reach, std::size_t k,
                   const ReconstructionOptions& options, bool& open)
{
  const float background = static_cast<float>(NarrowBand);
  openvdb::FloatGrid::Ptr grid = pointBand(in, h, options);
  const double sigma2 = std::pow(std::max(h, in.spacing), 2);
  const std::vector<openvdb::Coord> holes = addHoleVoxels(*grid, in, h, reach, options);
  checkGridSize(static_cast<double>(grid->activeVoxelCount()), h, options);

  OutsideBand outside(*grid);
  evaluate(in, *grid, h, k, sigma2);
  outside.findPieces(*grid);
  const std::vector<std::uint32_t> flipped = wronglyOrientedPoints(in, outside, h, k);
  if (!flipped.empty())
  {
    std::vector<float> corrected(in.normals, in.normals + 3 * in.count);
    for (std::uint32_t i : flipped)
      for (int c = 0; c < 3; ++c)
        corrected[3 * i + c] = -corrected[3 * i + c];
    Input again = in;
    again.normals = corrected.data();
    reevaluateAround(*grid, again, flipped, h, k, sigma2);
    outside.findPieces(*grid);
  }
  outside.settle(*grid, background);
  open = outside.open();
  interpolateHoles(*grid, holes, background);
  return zeroCrossing(*grid, h);
}

// Keeps the triangles of the largest edge-connected piece and drops unused vertices.
void keepLargestPiece(FineMesh& mesh)
{
  const std::size_t nt = mesh.triangles.size();
  std::unordered_map<std::uint64_t, int> edgeOwner;
  edgeOwner.reserve(3 * nt);
  std::vector<int> parent(nt);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int t)
  {
    while (parent[t] != t)
      t = parent[t] = parent[parent[t]];
    return t;
  };
  for (std::size_t t = 0; t < nt; ++t)
    for (int e = 0; e < 3; ++e)
    {
      const auto a = static_cast<std::uint64_t>(mesh.triangles[t][e]);
      const auto b = static_cast<std::uint64_t>(mesh.triangles[t][(e + 1) % 3]);
      const std::uint64_t key = std::min(a, b) << 32 | std::max(a, b);
      auto [it, inserted] = edgeOwner.emplace(key, static_cast<int>(t));
      if (!inserted)
        parent[find(static_cast<int>(t))] = find(it->second);
    }
  std::vector<std::size_t> size(nt, 0);
  for (std::size_t t = 0; t < nt; ++t)
    ++size[find(static_cast<int>(t))];
  const int largest =
      nt == 0 ? -1 : static_cast<int>(std::max_element(size.begin(), size.end()) - size.begin());
  std::vector<int> index(mesh.positions.size(), -1);
  FineMesh kept;
  for (std::size_t t = 0; t < nt; ++t)
  {
    if (find(static_cast<int>(t)) != largest)
      continue;
    std::array<int, 3> tri{};
    for (int e = 0; e < 3; ++e)
    {
      int& i = index[mesh.triangles[t][e]];
      if (i < 0)
      {
        i = static_cast<int>(kept.positions.size());
        kept.positions.push_back(mesh.positions[mesh.triangles[t][e]]);
      }
      tri[e] = i;
    }
    kept.triangles.push_back(tri);
  }
  mesh = std::move(kept);
}

// Drops the triangles all of whose corners are farther than `reach` from every point: where the
// data end (an open surface), the band's own end, not a surface of the data.
void dropUnsupported(FineMesh& mesh, const Input& in, double reach)
{
  std::vector<char> far(mesh.positions.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.positions.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& range)
                    {
                      for (std::size_t v = range.begin(); v != range.end(); ++v)
                      {
                        double d2 = 0;
                        in.tree.nearest(mesh.positions[v].data(), &d2);
                        far[v] = d2 > reach * reach;
                      }
                    });
  mesh.triangles.erase(std::remove_if(mesh.triangles.begin(), mesh.triangles.end(),
                                      [&](const std::array<int, 3>& t)
                                      { return far[t[0]] && far[t[1]] && far[t[2]]; }),
                       mesh.triangles.end());
}

} // namespace

namespace
{
void validateReconstruction(const double* points, const float* normals, std::size_t count,
                            const ReconstructionOptions& options)
{
  if (count < 16)
    throw std::invalid_argument("surface reconstruction needs at least 16 points, not " +
                                std::to_string(count));
  if (options.targetVertices < 20)
    throw std::invalid_argument("surface reconstruction: a target of " +
                                std::to_string(options.targetVertices) +
                                " vertices is too few (at least 20)");
  if (!(options.voxelSize >= 0 && std::isfinite(options.voxelSize)) ||
      !(options.holeReach >= 0 && std::isfinite(options.holeReach)))
    throw std::invalid_argument("surface reconstruction: voxelSize and holeReach must be finite "
                                "and not negative");
  for (std::size_t i = 0; i < 3 * count; ++i)
    if (!std::isfinite(points[i]) || !std::isfinite(normals[i]))
      throw std::invalid_argument("surface reconstruction: point " + std::to_string(i / 3) +
                                  " has a non-finite coordinate or normal");
}

// The typical sample spacing: the median nearest-neighbour distance of a subsample.
double typicalSpacing(const detail::KdTree& tree, const double* points, std::size_t count)
{
  std::vector<double> gaps;
  const std::size_t stride = std::max<std::size_t>(1, count / 2000);
  for (std::size_t i = 0; i < count; i += stride)
  {
    std::uint32_t ids[2];
    double d2[2];
    if (tree.nearest(points + 3 * i, 2, ids, d2) == 2 && d2[1] > 0)
      gaps.push_back(std::sqrt(d2[1]));
  }
  if (gaps.empty())
    throw std::invalid_argument("surface reconstruction: all points coincide");
  std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2),
                   gaps.end());
  return gaps[gaps.size() / 2];
}

// Turns the triangles the way the data's normals face (outward for estimateNormals' and a
// scanner's), by a vote of every triangle for the normal of the point nearest to it. (The
// tracker compares the template's normals with the data's.)
void orientLikeTheData(ReconstructedMesh& mesh, const Input& in)
{
  double vote = 0;
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
  {
    Vec3 corner[3];
    for (int e = 0; e < 3; ++e)
    {
      const double* p = &mesh.positions[3 * static_cast<std::size_t>(mesh.triangles[t + e])];
      corner[e] = {p[0], p[1], p[2]};
    }
    const Vec3 n = cross(corner[1] - corner[0], corner[2] - corner[0]);
    const Vec3 centre = (1.0 / 3.0) * (corner[0] + corner[1] + corner[2]);
    const float* m = in.normals + 3 * in.tree.nearest(centre.data());
    vote += n[0] * m[0] + n[1] * m[1] + n[2] * m[2];
  }
  if (vote < 0)
    for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
      std::swap(mesh.triangles[t + 1], mesh.triangles[t + 2]);
}
} // namespace

ReconstructedMesh reconstructSurface(const double* points, const float* normals, std::size_t count,
                                     const ReconstructionOptions& options)
{
  validateReconstruction(points, normals, count, options);
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });

  const std::vector<double> all(points, points + 3 * count);
  const double diagonal = boundingBoxDiagonal(all);
  if (!(diagonal > 0))
    throw std::invalid_argument("surface reconstruction: all points coincide");

  const detail::KdTree tree(points, count);
  const Input in{points, normals, count, tree, typicalSpacing(tree, points, count)};
  const double h = options.voxelSize > 0 ? options.voxelSize : VoxelPerSpacing * in.spacing;
  const double reach = std::max(options.holeReach * diagonal, 2 * NarrowBand * h);
  const std::size_t k = std::max<std::size_t>(1, std::min(options.neighbours, count));
  bool open = false;
  FineMesh fine = meshField(in, h, reach, k, options, open);
  // Open data: the crossings where the band ends (at least NarrowBand voxels from the points)
  // are no surface of the data.
  dropUnsupported(fine, in, open ? (NarrowBand - 0.5) * h : reach);
  keepLargestPiece(fine);
  if (fine.triangles.size() < 4)
    throw std::runtime_error("surface reconstruction found no surface in " + std::to_string(count) +
                             " points");

  // Isotropic remeshing to the wanted count, every vertex on the fine surface.
  detail::RemeshedSurface remeshed = detail::remeshIsotropic(fine, options.targetVertices);
  ReconstructedMesh mesh;
  mesh.voxelSize = h;
  mesh.positions = std::move(remeshed.positions);
  mesh.triangles = std::move(remeshed.triangles);
  mesh.closed = remeshed.closed;
  orientLikeTheData(mesh, in);
  return mesh;
}

} // namespace dp
