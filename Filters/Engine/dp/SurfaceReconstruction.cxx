// SPDX-License-Identifier: BSD-3-Clause
#include "dp/SurfaceReconstruction.h"

#include "dp/SurfaceSampler.h"
#include "dp/detail/KdTree.h"

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
#include <limits>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace dp
{
namespace
{
using Vec = std::array<double, 3>;

Vec operator+(const Vec& a, const Vec& b)
{
  return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}
Vec operator-(const Vec& a, const Vec& b)
{
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
Vec operator*(double s, const Vec& a)
{
  return {s * a[0], s * a[1], s * a[2]};
}
double dot(const Vec& a, const Vec& b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
Vec cross(const Vec& a, const Vec& b)
{
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double norm(const Vec& a)
{
  return std::sqrt(dot(a, a));
}

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

openvdb::Coord voxelOf(const double* p, double h)
{
  return openvdb::Coord(static_cast<int>(std::floor(p[0] / h + 0.5)),
                        static_cast<int>(std::floor(p[1] / h + 0.5)),
                        static_cast<int>(std::floor(p[2] / h + 0.5)));
}

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
void interpolateHoles(openvdb::FloatGrid& grid, const std::vector<openvdb::Coord>& holes,
                      float background)
{
  if (holes.empty())
    return;
  openvdb::Int32Grid::Ptr index = openvdb::Int32Grid::create(-1);
  {
    auto acc = index->getAccessor();
    for (std::size_t i = 0; i < holes.size(); ++i)
      acc.setValueOn(holes[i], static_cast<int>(i));
  }
  const std::size_t n = holes.size();
  std::vector<std::array<int, 6>> around(n);
  std::vector<float> fixed(n, 0.0f), value(n, 0.0f);
  std::vector<std::uint8_t> meets(n, 0); // bit 0: an inside piece, bit 1: an outside piece
  std::vector<int> band(n, 0);           // band neighbours: positive ones less negative ones
  {
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
          around[i][e++] = j;
          if (j >= 0)
            continue;
          const float neighbour = values.getValue(v);
          fixed[i] += neighbour;
          if (!values.isValueOn(v))
            meets[i] |= neighbour < 0 ? 1 : 2;
          else
            band[i] += neighbour < 0 ? -1 : 1;
        }
    }
  }
  // Connected parts of hole voxels, and what they meet.
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
      partMeets[p] |= meets[i];
      partBand[p] += band[i];
      for (int j : around[i])
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
  const int rounds = 200;
  const float omega = 1.9f;
  for (int round = 0; round < rounds; ++round)
    for (std::size_t i = 0; i < n; ++i)
    {
      if (!free[i])
        continue;
      float sum = fixed[i];
      for (int j : around[i])
        if (j >= 0)
          sum += value[j];
      value[i] += omega * (sum / 6 - value[i]);
    }
  auto acc = grid.getAccessor();
  for (std::size_t i = 0; i < n; ++i)
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

struct FineMesh
{
  std::vector<Vec> positions;
  std::vector<std::array<int, 3>> triangles;
};

// The zero crossing of the band-limited signed field at voxel size h, as triangles. The band:
// every voxel within NarrowBand voxels of a point (the plane distance), plus the voxels of holes
// (interpolated). Outside the band, each piece of space takes the sign of most of its border
// (OutsideBand), so no crossing appears where the band ends. `open` tells whether some piece's
// border has both signs in large parts (open data: the crossings at the band's end there are
// to be dropped).
FineMesh meshField(const Input& in, double h, double reach, std::size_t k,
                   const ReconstructionOptions& options, bool& open)
{
  const float background = static_cast<float>(NarrowBand);
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(background);
  {
    auto acc = grid->getAccessor();
    for (std::size_t i = 0; i < in.count; ++i)
      acc.setValueOn(voxelOf(in.points + 3 * i, h), background);
  }
  const double cube = std::pow(2 * NarrowBand + 1, 3);
  if (static_cast<double>(grid->activeVoxelCount()) * cube / 4 >
      static_cast<double>(options.maxActiveVoxels))
    throw std::runtime_error("surface reconstruction: the grid at voxel size " + std::to_string(h) +
                             " would exceed " + std::to_string(options.maxActiveVoxels) +
                             " voxels");
  openvdb::tools::dilateActiveValues(grid->tree(), static_cast<int>(NarrowBand),
                                     openvdb::tools::NN_FACE_EDGE_VERTEX,
                                     openvdb::tools::IGNORE_TILES);
  const double sigma2 = std::pow(std::max(h, in.spacing), 2);

  // Holes: on a coarse grid, the cells that a morphological closing of the points' cells adds
  // (gaps in the data narrower than about twice `reach`, and concave corners). Their voxels
  // outside the band get no field value (the plane distance far from the data is unreliable:
  // a wrongly oriented patch, or data passing through itself, would grow sheets there); they
  // are interpolated below, harmonically, between the band and the pieces outside it.
  std::vector<openvdb::Coord> holes;
  const double H = CoarseRatio * h;
  const int closing = static_cast<int>(std::ceil(reach / H));
  if (closing > 0)
  {
    openvdb::MaskGrid::Ptr cells = openvdb::MaskGrid::create();
    {
      auto acc = cells->getAccessor();
      for (std::size_t i = 0; i < in.count; ++i)
        acc.setValueOn(voxelOf(in.points + 3 * i, H));
    }
    openvdb::MaskGrid::Ptr closed = cells->deepCopy();
    openvdb::tools::dilateActiveValues(closed->tree(), closing, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                       openvdb::tools::IGNORE_TILES);
    openvdb::tools::erodeActiveValues(closed->tree(), closing, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                      openvdb::tools::IGNORE_TILES);
    closed->tree().topologyDifference(cells->tree());
    auto acc = grid->getAccessor();
    for (auto it = closed->cbeginValueOn(); it; ++it)
    {
      // The cell's voxels (the cell of coarse voxel c is centred on CoarseRatio c).
      const openvdb::Coord c = it.getCoord();
      const int half = CoarseRatio / 2;
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
  }
  if (grid->activeVoxelCount() > options.maxActiveVoxels)
    throw std::runtime_error("surface reconstruction: the grid at voxel size " + std::to_string(h) +
                             " would exceed " + std::to_string(options.maxActiveVoxels) +
                             " voxels");

  OutsideBand outside(*grid);
  evaluate(in, *grid, h, k, sigma2);
  outside.findPieces(*grid);
  // Normals against the pieces: each border voxel of the band (next to a piece whose border
  // mostly agrees) asks the three points nearest to it whether their planes put it on its
  // piece's side (the nearest only: beyond a thin part, those of its far side answer). A point that
  // most of its voxels find on the wrong side has its normal the wrong way round (a patch oriented
  // against the rest): flipped, and the field around it evaluated again.
  std::vector<std::uint32_t> flipped;
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
                          const std::size_t found = in.tree.nearest(x, std::min<std::size_t>(k, 3),
                                                                    ids.data(), d2.data());
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
    for (std::size_t i = 0; i < in.count; ++i)
      if (support[i] < 0)
        flipped.push_back(static_cast<std::uint32_t>(i));
  }
  std::vector<float> corrected;
  Input again = in;
  if (!flipped.empty())
  {
    corrected.assign(in.normals, in.normals + 3 * in.count);
    for (std::uint32_t i : flipped)
      for (int c = 0; c < 3; ++c)
        corrected[3 * i + c] = -corrected[3 * i + c];
    again.normals = corrected.data();
    // The voxels whose neighbours may include a flipped point.
    openvdb::MaskGrid::Ptr touched = openvdb::MaskGrid::create();
    {
      auto acc = touched->getAccessor();
      for (std::uint32_t i : flipped)
        acc.setValueOn(voxelOf(in.points + 3 * i, h));
    }
    openvdb::tools::dilateActiveValues(touched->tree(), static_cast<int>(NarrowBand) + 2,
                                       openvdb::tools::NN_FACE_EDGE_VERTEX,
                                       openvdb::tools::IGNORE_TILES);
    auto acc = grid->getAccessor();
    std::vector<std::uint32_t> ids(k);
    std::vector<double> d2(k);
    for (auto it = touched->cbeginValueOn(); it; ++it)
    {
      const openvdb::Coord c = it.getCoord();
      if (!acc.isValueOn(c) || acc.getValue(c) == Unknown)
        continue;
      const double x[3] = {h * c.x(), h * c.y(), h * c.z()};
      const double distance = planeDistance(again, x, k, sigma2, ids.data(), d2.data()) / h;
      acc.setValue(c, static_cast<float>(std::clamp(distance, -NarrowBand, NarrowBand)));
    }
    outside.findPieces(*grid);
  }
  outside.settle(*grid, background);
  open = outside.open();
  interpolateHoles(*grid, holes, background);

  std::vector<openvdb::Vec3s> vertices;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*grid, vertices, triangles, quads, 0.0, 0.0);

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

// ---------------------------------------------------------------------------------------------
// The closest point on the fine mesh: the reference surface the remeshed vertices stay on.

Vec closestOnTriangle(const Vec& p, const Vec& a, const Vec& b, const Vec& c)
{
  // Regions of the triangle's Voronoi diagram (vertices, edges, face), in turn.
  const Vec ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0)
    return a;
  const Vec bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3)
    return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0)
    return a + (d1 / (d1 - d3)) * ab;
  const Vec cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6)
    return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0)
    return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const double scale = 1.0 / (va + vb + vc);
  return a + (vb * scale) * ab + (vc * scale) * ac;
}

std::vector<double> flatten(const std::vector<Vec>& positions)
{
  std::vector<double> flat;
  flat.reserve(3 * positions.size());
  for (const Vec& p : positions)
    flat.insert(flat.end(), p.begin(), p.end());
  return flat;
}

class Reference
{
public:
  explicit Reference(const FineMesh& mesh)
      : Mesh(mesh), Flat(flatten(mesh.positions)), Tree(Flat.data(), mesh.positions.size()),
        Offsets(mesh.positions.size() + 1, 0)
  {
    for (const auto& t : mesh.triangles)
      for (int v : t)
        ++Offsets[v + 1];
    std::partial_sum(Offsets.begin(), Offsets.end(), Offsets.begin());
    Faces.resize(Offsets.back());
    std::vector<int> fill(Offsets.begin(), Offsets.end() - 1);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int v : mesh.triangles[t])
        Faces[fill[v]++] = static_cast<int>(t);
  }

  /** The closest point to p on the triangles around its nearest vertices whose normals face
   *  the same way as `normal`, so that a vertex does not jump to a nearby sheet facing the other
   *  way (the other side of a thin part); more vertices are searched when none of those do. */
  Vec project(const Vec& p, const Vec& normal) const
  {
    for (std::size_t k : {8, 48})
    {
      std::uint32_t ids[48];
      double d2[48];
      const std::size_t found = Tree.nearest(p.data(), std::min(k, Mesh.positions.size()), ids, d2);
      double best = std::numeric_limits<double>::infinity();
      Vec result = p;
      for (std::size_t j = 0; j < found; ++j)
        for (int f = Offsets[ids[j]]; f < Offsets[ids[j] + 1]; ++f)
        {
          const auto& t = Mesh.triangles[Faces[f]];
          const Vec& a = Mesh.positions[t[0]];
          const Vec& b = Mesh.positions[t[1]];
          const Vec& c = Mesh.positions[t[2]];
          if (dot(cross(b - a, c - a), normal) <= 0)
            continue;
          const Vec q = closestOnTriangle(p, a, b, c);
          const double dd = dot(q - p, q - p);
          if (dd < best)
          {
            best = dd;
            result = q;
          }
        }
      if (best < std::numeric_limits<double>::infinity())
        return result;
    }
    return p;
  }

private:
  const FineMesh& Mesh;
  std::vector<double> Flat;
  detail::KdTree Tree;
  std::vector<int> Offsets, Faces; // the triangles around each vertex
};

// ---------------------------------------------------------------------------------------------
// Isotropic remeshing (Botsch & Kobbelt 2004) on a corner table: corner c = 3 f + i is vertex
// i of triangle f; Opp[c] is the corner facing c across the edge opposite c (-1 on a boundary).

// The squared distance to a set of planes, area-weighted: x^T A x + 2 b.x + c (Garland &
// Heckbert). A collapse puts the merged vertex where the planes around both ends of the edge
// are best kept, so that tips and thin parts (a toe, a horse's leg) do not shrink.
struct Quadric
{
  double a[6] = {0, 0, 0, 0, 0, 0}; // xx xy xz yy yz zz
  double b[3] = {0, 0, 0};
  double c = 0;

  void addPlane(const Vec& normal, double offset, double weight)
  {
    const Vec& n = normal;
    const double w = weight;
    a[0] += w * n[0] * n[0];
    a[1] += w * n[0] * n[1];
    a[2] += w * n[0] * n[2];
    a[3] += w * n[1] * n[1];
    a[4] += w * n[1] * n[2];
    a[5] += w * n[2] * n[2];
    for (int i = 0; i < 3; ++i)
      b[i] += w * offset * n[i];
    c += w * offset * offset;
  }
  Quadric& operator+=(const Quadric& q)
  {
    for (int i = 0; i < 6; ++i)
      a[i] += q.a[i];
    for (int i = 0; i < 3; ++i)
      b[i] += q.b[i];
    c += q.c;
    return *this;
  }
  double operator()(const Vec& x) const
  {
    return a[0] * x[0] * x[0] + 2 * a[1] * x[0] * x[1] + 2 * a[2] * x[0] * x[2] +
           a[3] * x[1] * x[1] + 2 * a[4] * x[1] * x[2] + a[5] * x[2] * x[2] +
           2 * (b[0] * x[0] + b[1] * x[1] + b[2] * x[2]) + c;
  }
};

class Remesher
{
public:
  /** Edges shared by more than two triangles, or by two of the same orientation, become
   *  boundaries; vertices where separate fans of triangles meet are split, one per fan. */
  explicit Remesher(const FineMesh& mesh)
  {
    X = mesh.positions;
    Corner.reserve(3 * mesh.triangles.size());
    for (const auto& t : mesh.triangles)
      Corner.insert(Corner.end(), t.begin(), t.end());
    Opp.assign(Corner.size(), -1);
    std::unordered_map<std::uint64_t, int> directed;
    directed.reserve(Corner.size());
    auto key = [](int a, int b)
    { return static_cast<std::uint64_t>(a) << 32 | static_cast<std::uint32_t>(b); };
    for (int c = 0; c < static_cast<int>(Corner.size()); ++c)
    {
      auto [it, inserted] = directed.emplace(key(Corner[next(c)], Corner[prev(c)]), c);
      if (!inserted)
        it->second = -1; // the same directed edge twice
    }
    for (int c = 0; c < static_cast<int>(Corner.size()); ++c)
    {
      const auto self = directed.find(key(Corner[next(c)], Corner[prev(c)]));
      const auto twin = directed.find(key(Corner[prev(c)], Corner[next(c)]));
      if (self->second == c && twin != directed.end() && twin->second >= 0)
        Opp[c] = twin->second;
    }
    // One fan per vertex: corners not reached from the vertex's first fan get a new vertex.
    Of.assign(X.size(), -1);
    std::vector<char> seen(Corner.size(), 0);
    std::vector<int> ring;
    for (int c = 0; c < static_cast<int>(Corner.size()); ++c)
    {
      if (seen[c])
        continue;
      int v = Corner[c];
      if (Of[v] >= 0)
      {
        v = static_cast<int>(X.size());
        X.push_back(X[Corner[c]]);
        Of.push_back(-1);
      }
      Of[v] = c;
      fan(c, ring);
      for (int r : ring)
      {
        seen[r] = 1;
        Corner[r] = v;
      }
    }
    for (int v : Of)
      Live += v >= 0;
    // Each vertex's quadric: the planes of the fine triangles around it.
    Planes.assign(X.size(), Quadric{});
    for (std::size_t f = 0; f < Corner.size(); f += 3)
    {
      const Vec n = faceNormal(static_cast<int>(f));
      const double area = norm(n);
      if (!(area > 0))
        continue;
      const Vec unit = (1 / area) * n;
      for (int i = 0; i < 3; ++i)
        Planes[Corner[f + i]].addPlane(unit, -dot(unit, X[Corner[f]]), area);
    }
  }

  std::size_t vertices() const { return Live; }

  /** No edge with one triangle only. */
  bool closed() const
  {
    for (std::size_t c = 0; c < Corner.size(); ++c)
      if (Corner[c] >= 0 && Opp[c] < 0)
        return false;
    return true;
  }

  /** Iterations of: split edges longer than 4/3 L, collapse edges shorter than 4/5 L, flip
   *  edges towards valence 6, relax along the surface and project onto the reference. */
  void remesh(double length, int iterations, const Reference& reference)
  {
    for (int i = 0; i < iterations; ++i)
    {
      splitLonger(4.0 / 3.0 * length);
      collapseShorter(0.8 * length, 4.0 / 3.0 * length);
      flipForValence();
      relax(reference);
    }
  }

  /** Collapses the shortest or splits the longest edges until there are `wanted` vertices (as
   *  far as the checks allow), then evens the triangles out again. */
  void adjustCount(std::size_t wanted, double length, const Reference& reference)
  {
    for (int round = 0; round < 4 && Live != wanted; ++round)
    {
      std::vector<std::pair<double, int>> edges;
      for (int c = 0; c < static_cast<int>(Corner.size()); ++c)
        if (Corner[c] >= 0 && (Opp[c] < 0 || c < Opp[c]))
          edges.push_back({edgeLength(c), c});
      if (Live > wanted)
      {
        std::sort(edges.begin(), edges.end());
        for (const auto& [l, c] : edges)
        {
          if (Live <= wanted)
            break;
          if (Corner[c] >= 0)
            collapse(c, 1.6 * length);
        }
      }
      else
      {
        std::sort(edges.rbegin(), edges.rend());
        // Each split adds one vertex; an edge split earlier in this round is not split again.
        std::vector<int> chosen;
        for (const auto& e : edges)
          if (chosen.size() < wanted - Live)
            chosen.push_back(e.second);
        std::vector<char> touched(X.size() + chosen.size(), 0);
        for (int c : chosen)
        {
          const int a = Corner[next(c)], b = Corner[prev(c)];
          if (Corner[c] < 0 || touched[a] || touched[b])
            continue;
          touched[a] = touched[b] = 1;
          split(c);
        }
      }
    }
    for (int i = 0; i < 3; ++i)
    {
      flipForValence();
      relax(reference);
    }
    // Last, the remaining poorly shaped pairs of triangles (where valence and relaxation
    // disagree, at thin parts) get the diagonal that shapes them better; a needle that keeps
    // its short edge loses it (collapsed, and the longest edge split for the count).
    for (int i = 0; i < 3; ++i)
    {
      flipForShape();
      collapseNeedles(length);
      relax(reference);
    }
  }

  /** Live vertices and triangles, renumbered. */
  void extract(ReconstructedMesh& out) const
  {
    std::vector<std::int64_t> index(X.size(), -1);
    out.positions.clear();
    out.triangles.clear();
    for (int c = 0; c < static_cast<int>(Corner.size()); ++c)
    {
      if (Corner[c] < 0)
        continue;
      std::int64_t& i = index[Corner[c]];
      if (i < 0)
      {
        i = static_cast<std::int64_t>(out.positions.size() / 3);
        out.positions.insert(out.positions.end(), X[Corner[c]].begin(), X[Corner[c]].end());
      }
      out.triangles.push_back(i);
    }
  }

private:
  std::vector<Vec> X;          // vertex positions
  std::vector<Quadric> Planes; // of the fine surface around each vertex
  std::vector<int> Corner;     // the vertex of each corner; -1 for a deleted triangle
  std::vector<int> Opp;        // the opposite corner across the edge facing each corner
  std::vector<int> Of;         // a corner of each vertex; -1 for a deleted vertex
  std::size_t Live = 0;        // vertices in use

  static int next(int c) { return c % 3 == 2 ? c - 2 : c + 1; }
  static int prev(int c) { return c % 3 == 0 ? c + 2 : c - 1; }
  void link(int a, int b)
  {
    if (a >= 0)
      Opp[a] = b;
    if (b >= 0)
      Opp[b] = a;
  }
  double edgeLength(int c) const { return norm(X[Corner[next(c)]] - X[Corner[prev(c)]]); }
  Vec faceNormal(int c) const // not normalised
  {
    const int f = c - c % 3;
    return cross(X[Corner[f + 1]] - X[Corner[f]], X[Corner[f + 2]] - X[Corner[f]]);
  }

  // The corners around the vertex of corner `start`, in order; true on a boundary.
  bool fan(int start, std::vector<int>& out) const
  {
    out.clear();
    int c = start;
    for (std::size_t guard = 0; guard <= Corner.size(); ++guard)
    {
      out.push_back(c);
      const int o = Opp[prev(c)];
      if (o < 0)
        break;
      c = prev(o);
      if (c == start)
        return false;
    }
    c = start;
    for (std::size_t guard = 0; guard <= Corner.size(); ++guard)
    {
      const int o = Opp[next(c)];
      if (o < 0)
        break;
      c = next(o);
      out.push_back(c);
    }
    return true;
  }
  bool onBoundary(int v) const
  {
    thread_local std::vector<int> ring;
    return fan(Of[v], ring);
  }
  // The vertices sharing an edge with v, sorted; true on a boundary.
  bool neighbours(int v, std::vector<int>& out) const
  {
    thread_local std::vector<int> ring;
    const bool boundary = fan(Of[v], ring);
    out.clear();
    for (int c : ring)
    {
      out.push_back(Corner[next(c)]);
      out.push_back(Corner[prev(c)]);
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return boundary;
  }
  int valence(int v) const
  {
    thread_local std::vector<int> ring;
    const bool boundary = fan(Of[v], ring);
    return static_cast<int>(ring.size()) + (boundary ? 1 : 0);
  }
  int newFace(int a, int b, int c)
  {
    const int f = static_cast<int>(Corner.size());
    Corner.insert(Corner.end(), {a, b, c});
    Opp.insert(Opp.end(), {-1, -1, -1});
    return f;
  }

  // Splits the edge facing corner c at its midpoint.
  void split(int c)
  {
    const int c1 = next(c), c2 = prev(c), o = Opp[c];
    const int x = Corner[c], a = Corner[c1], b = Corner[c2];
    const int m = static_cast<int>(X.size());
    X.push_back(0.5 * (X[a] + X[b]));
    Of.push_back(c2);
    Quadric q = Planes[a];
    q += Planes[b];
    Planes.push_back(q);
    ++Live;
    const int e = newFace(x, m, b); // corners e (x), e+1 (m), e+2 (b)
    link(e + 1, Opp[c1]);
    Corner[c2] = m;
    link(c1, e + 2);
    Of[b] = e + 2;
    Of[a] = c1;
    if (o >= 0)
    {
      const int o1 = next(o), o2 = prev(o);   // b, a
      const int g = newFace(Corner[o], m, a); // corners g (d), g+1 (m), g+2 (a)
      link(g + 1, Opp[o1]);
      Corner[o2] = m;
      link(o1, g + 2);
      link(c, g);
      link(e, o);
    }
    else
    {
      Opp[c] = -1;
      Opp[e] = -1;
    }
  }

  // Flips the edge facing corner c (which must have an opposite corner).
  void flip(int c)
  {
    const int o = Opp[c], c1 = next(c), c2 = prev(c), o1 = next(o), o2 = prev(o);
    const int x = Corner[c], a = Corner[c1], b = Corner[c2], d = Corner[o];
    const int A = Opp[o1], B = Opp[c1];
    Corner[c2] = d;
    Corner[o2] = x;
    link(c, A);
    link(o, B);
    link(c1, o1);
    Of[x] = c;
    Of[a] = c1;
    Of[d] = c2;
    Of[b] = o1;
  }

  bool canFlip(int c) const
  {
    const int o = Opp[c];
    if (o < 0)
      return false;
    const int x = Corner[c], a = Corner[next(c)], b = Corner[prev(c)], d = Corner[o];
    if (x == d || valence(a) <= 3 || valence(b) <= 3)
      return false;
    thread_local std::vector<int> ring;
    neighbours(x, ring);
    if (std::binary_search(ring.begin(), ring.end(), d))
      return false; // x-d is an edge already
    // Not folded: the new triangles face the way the old ones did, and each other.
    const Vec before = faceNormal(c) + faceNormal(o);
    const Vec n1 = cross(X[a] - X[x], X[d] - X[x]);
    const Vec n2 = cross(X[b] - X[d], X[x] - X[d]);
    const double l1 = norm(n1), l2 = norm(n2), l0 = norm(before);
    if (!(l1 > 0 && l2 > 0 && l0 > 0))
      return false;
    return dot(n1, before) > 0.5 * l1 * l0 && dot(n2, before) > 0.5 * l2 * l0 &&
           dot(n1, n2) > 0.5 * l1 * l2;
  }

  // Collapses the edge facing corner c into one vertex (at the midpoint, or at the endpoint on
  // the boundary), when that keeps the mesh manifold and unfolded and makes no edge longer than
  // maxLength. Returns whether it did.
  bool collapse(int c, double maxLength)
  {
    if (Live <= 4)
      return false;
    const int o = Opp[c];
    int keep = Corner[next(c)], gone = Corner[prev(c)];
    thread_local std::vector<int> ringKeep, ringGone, fanGone, fanKeep;
    const bool keepOnBoundary = neighbours(keep, ringKeep);
    const bool goneOnBoundary = neighbours(gone, ringGone);
    if (o >= 0 && keepOnBoundary && goneOnBoundary)
      return false; // would pinch the surface
    // Link condition: the two ends share exactly the edge's opposite vertices as neighbours.
    std::size_t common = 0;
    for (int v : ringKeep)
      common += std::binary_search(ringGone.begin(), ringGone.end(), v);
    if (common != (o >= 0 ? 2u : 1u))
      return false;
    Quadric merged = Planes[keep];
    merged += Planes[gone];
    Vec target = 0.5 * (X[keep] + X[gone]);
    if (goneOnBoundary && !keepOnBoundary)
    {
      std::swap(keep, gone);
      target = X[keep];
    }
    else if (keepOnBoundary && !goneOnBoundary)
      target = X[keep];
    else
      // The end or the midpoint that keeps the planes around the edge best.
      for (const Vec& candidate : {X[keep], X[gone]})
        if (merged(candidate) < merged(target))
          target = candidate;
    for (const auto* ring : {&ringKeep, &ringGone})
      for (int v : *ring)
        if (v != keep && v != gone && norm(X[v] - target) > maxLength)
          return false;
    // No triangle that stays may turn over or degenerate.
    const int f1 = c - c % 3, f2 = o < 0 ? -1 : o - o % 3;
    fan(Of[gone], fanGone);
    fan(Of[keep], fanKeep);
    for (const auto* ring : {&fanGone, &fanKeep})
      for (int r : *ring)
      {
        const int f = r - r % 3;
        if (f == f1 || f == f2)
          continue;
        const Vec before = faceNormal(r);
        const Vec p = X[Corner[next(r)]], q = X[Corner[prev(r)]];
        const Vec after = cross(p - target, q - target);
        const double lb = norm(before), la = norm(after);
        if (!(la > 1e-12 * lb) || dot(before, after) < 0.3 * la * lb)
          return false;
      }

    // Relink: the two edges of each removed triangle that stay become one.
    const int c1 = next(c), c2 = prev(c);
    const int x = Corner[c];
    const int A1 = Opp[c2], B1 = Opp[c1]; // across x-(next) and (prev)-x
    link(A1, B1);
    int P = -1, Q = -1, d = -1;
    if (o >= 0)
    {
      d = Corner[o];
      P = Opp[next(o)];
      Q = Opp[prev(o)];
      link(P, Q);
    }
    for (int r : fanGone)
      Corner[r] = keep;
    for (int f : {f1, f2})
      if (f >= 0)
        for (int i = 0; i < 3; ++i)
        {
          Corner[f + i] = -1;
          Opp[f + i] = -1;
        }
    X[keep] = target;
    Planes[keep] = merged;
    Of[gone] = -1;
    --Live;
    // Corners of the kept vertex and of the opposite vertices in triangles that remain.
    auto cornerIn = [&](int across, int v)
    {
      const int f = across - across % 3;
      for (int i = 0; i < 3; ++i)
        if (Corner[f + i] == v)
          return f + i;
      return -1;
    };
    const int anyKeep = A1 >= 0 ? cornerIn(A1, keep) : (B1 >= 0 ? cornerIn(B1, keep) : -1);
    Of[keep] = anyKeep >= 0 ? anyKeep : (P >= 0 ? cornerIn(P, keep) : cornerIn(Q, keep));
    Of[x] = A1 >= 0 ? cornerIn(A1, x) : (B1 >= 0 ? cornerIn(B1, x) : -1);
    if (d >= 0)
      Of[d] = P >= 0 ? cornerIn(P, d) : (Q >= 0 ? cornerIn(Q, d) : -1);
    for (int v : {keep, x, d})
      if (v >= 0 && Of[v] < 0)
        --Live; // left without triangles (cannot happen with the link condition)
    return true;
  }

  void splitLonger(double maxLength)
  {
    for (int pass = 0; pass < 8; ++pass)
    {
      bool any = false;
      const int corners = static_cast<int>(Corner.size());
      for (int c = 0; c < corners; ++c)
        if (Corner[c] >= 0 && (Opp[c] < 0 || c < Opp[c]) && edgeLength(c) > maxLength)
        {
          split(c);
          any = true;
        }
      if (!any)
        break;
    }
  }

  void collapseShorter(double minLength, double maxLength)
  {
    for (int pass = 0; pass < 8; ++pass)
    {
      bool any = false;
      for (int c = 0; c < static_cast<int>(Corner.size()); ++c)
        if (Corner[c] >= 0 && (Opp[c] < 0 || c < Opp[c]) && edgeLength(c) < minLength)
          any = collapse(c, maxLength) || any;
      if (!any)
        break;
    }
  }

  // The shape quality 4 sqrt(3) area / (sum of squared edges) of triangle a b c.
  static double quality(const Vec& a, const Vec& b, const Vec& c)
  {
    const double edges = dot(b - a, b - a) + dot(c - b, c - b) + dot(a - c, a - c);
    return edges > 0 ? 2 * std::sqrt(3.0) * norm(cross(b - a, c - a)) / edges : 0;
  }

  void flipForShape()
  {
    for (int c = 0; c < static_cast<int>(Corner.size()); ++c)
    {
      const int o = Opp[c];
      if (Corner[c] < 0 || o < 0 || o < c)
        continue;
      const Vec &x = X[Corner[c]], &a = X[Corner[next(c)]], &b = X[Corner[prev(c)]],
                &d = X[Corner[o]];
      const double before = std::min(quality(x, a, b), quality(d, b, a));
      const double after = std::min(quality(x, a, d), quality(d, b, x));
      if (before < 0.3 && after > before + 0.05 && canFlip(c))
        flip(c);
    }
  }

  void collapseNeedles(double length)
  {
    for (std::size_t f = 0; f < Corner.size(); f += 3)
    {
      if (Corner[f] < 0)
        continue;
      const Vec &a = X[Corner[f]], &b = X[Corner[f + 1]], &c = X[Corner[f + 2]];
      if (quality(a, b, c) >= 0.1)
        continue;
      // The corner facing the shortest edge.
      int shortest = static_cast<int>(f);
      for (int i = 1; i < 3; ++i)
        if (edgeLength(static_cast<int>(f) + i) < edgeLength(shortest))
          shortest = static_cast<int>(f) + i;
      if (edgeLength(shortest) > 0.5 * length || !collapse(shortest, 2 * length))
        continue;
      int longest = -1;
      for (int c2 = 0; c2 < static_cast<int>(Corner.size()); ++c2)
        if (Corner[c2] >= 0 && (longest < 0 || edgeLength(c2) > edgeLength(longest)))
          longest = c2;
      if (longest >= 0)
        split(longest);
    }
  }

  void flipForValence()
  {
    for (int c = 0; c < static_cast<int>(Corner.size()); ++c)
    {
      const int o = Opp[c];
      if (Corner[c] < 0 || o < 0 || o < c)
        continue;
      const int vs[4] = {Corner[next(c)], Corner[prev(c)], Corner[c], Corner[o]};
      int deviation[2] = {0, 0};
      for (int i = 0; i < 4; ++i)
      {
        const int ideal = onBoundary(vs[i]) ? 4 : 6;
        const int val = valence(vs[i]);
        deviation[0] += std::abs(val - ideal);
        deviation[1] += std::abs(val + (i < 2 ? -1 : 1) - ideal);
      }
      if (deviation[1] < deviation[0] && canFlip(c))
        flip(c);
    }
  }

  // Each vertex to the area-weighted mean of its triangles' centroids, along the surface (the
  // tangent plane of its area-weighted normal), then onto the reference surface. Boundary
  // vertices only go onto the reference.
  void relax(const Reference& reference)
  {
    std::vector<Vec> moved(X);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, X.size(), 256),
                      [&](const tbb::blocked_range<std::size_t>& range)
                      {
                        std::vector<int> ring;
                        for (std::size_t v = range.begin(); v != range.end(); ++v)
                        {
                          if (Of[v] < 0)
                            continue;
                          const bool boundary = fan(Of[v], ring);
                          Vec normal{0, 0, 0}, centre{0, 0, 0};
                          double area = 0;
                          for (int r : ring)
                          {
                            const Vec n = faceNormal(r);
                            const double a = norm(n);
                            const int f = r - r % 3;
                            normal = normal + n;
                            centre = centre +
                                     (a / 3) * (X[Corner[f]] + X[Corner[f + 1]] + X[Corner[f + 2]]);
                            area += a;
                          }
                          const double length = norm(normal);
                          if (!(length > 0 && area > 0))
                            continue;
                          normal = (1 / length) * normal;
                          Vec target = X[v];
                          if (!boundary)
                          {
                            const Vec move = (1 / area) * centre - X[v];
                            target = X[v] + (move - dot(move, normal) * normal);
                          }
                          moved[v] = reference.project(target, normal);
                        }
                      });
    // Moves that would turn a triangle over or flatten it (two vertices onto the same point of
    // the reference, at a tip) are taken back.
    for (int pass = 0; pass < 4; ++pass)
    {
      bool any = false;
      for (std::size_t f = 0; f < Corner.size(); f += 3)
      {
        if (Corner[f] < 0)
          continue;
        const int a = Corner[f], b = Corner[f + 1], c = Corner[f + 2];
        const Vec before = cross(X[b] - X[a], X[c] - X[a]);
        const Vec after = cross(moved[b] - moved[a], moved[c] - moved[a]);
        if (dot(before, after) > 0 && norm(after) > 1e-3 * norm(before))
          continue;
        for (int v : {a, b, c})
          if (moved[v] != X[v])
          {
            moved[v] = X[v];
            any = true;
          }
      }
      if (!any)
        break;
    }
    X.swap(moved);
  }
};

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

ReconstructedMesh reconstructSurface(const double* points, const float* normals, std::size_t count,
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
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });

  const std::vector<double> all(points, points + 3 * count);
  const double diagonal = boundingBoxDiagonal(all);
  if (!(diagonal > 0))
    throw std::invalid_argument("surface reconstruction: all points coincide");

  const detail::KdTree tree(points, count);
  // The typical sample spacing: the median nearest-neighbour distance of a subsample.
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
  const double spacing = gaps[gaps.size() / 2];
  const Input in{points, normals, count, tree, spacing};

  const double h = options.voxelSize > 0 ? options.voxelSize : VoxelPerSpacing * spacing;
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

  // Edge length for the wanted count: a closed surface of V vertices has about 2 V triangles,
  // equilateral ones of edge L have area sqrt(3)/4 L^2 each.
  double area = 0;
  for (const auto& t : fine.triangles)
    area += 0.5 * norm(cross(fine.positions[t[1]] - fine.positions[t[0]],
                             fine.positions[t[2]] - fine.positions[t[0]]));
  const double wanted = static_cast<double>(options.targetVertices);
  double length = std::sqrt(2 * area / (std::sqrt(3.0) * wanted));
  const Reference reference(fine);
  Remesher remesher(fine);
  remesher.remesh(length, 6, reference);
  length *= std::clamp(std::sqrt(static_cast<double>(remesher.vertices()) / wanted), 0.5, 2.0);
  remesher.remesh(length, 4, reference);
  remesher.adjustCount(options.targetVertices, length, reference);

  ReconstructedMesh mesh;
  mesh.voxelSize = h;
  remesher.extract(mesh);

  // Orientation: the way the data's normals face (outward for estimateNormals' and a
  // scanner's), by a vote of every triangle for the normal of the point nearest to it. (The
  // tracker compares the template's normals with the data's.)
  mesh.closed = remesher.closed();
  double vote = 0;
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
  {
    Vec corner[3];
    for (int e = 0; e < 3; ++e)
    {
      const double* p = &mesh.positions[3 * static_cast<std::size_t>(mesh.triangles[t + e])];
      corner[e] = {p[0], p[1], p[2]};
    }
    const Vec n = cross(corner[1] - corner[0], corner[2] - corner[0]);
    const Vec centre = (1.0 / 3.0) * (corner[0] + corner[1] + corner[2]);
    const float* m = in.normals + 3 * in.tree.nearest(centre.data());
    vote += n[0] * m[0] + n[1] * m[1] + n[2] * m[2];
  }
  if (vote < 0)
    for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
      std::swap(mesh.triangles[t + 1], mesh.triangles[t + 2]);
  return mesh;
}

} // namespace dp
