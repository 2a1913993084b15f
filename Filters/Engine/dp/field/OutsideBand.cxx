// SPDX-License-Identifier: BSD-3-Clause
#include "dp/field/OutsideBand.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>

namespace dp::support
{
// ---------------------------------------------------------------------------------------------
// The pieces of space outside the band.

template <typename Visit>
void OutsideBand::forFaces(std::size_t i, Visit visit) const
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

template <typename Visit>
void OutsideBand::border(Visit visit) const
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

OutsideBand::OutsideBand(openvdb::FloatGrid& grid)
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

std::size_t OutsideBand::labelPieces()
{
  for (int& l : Label)
    if (l != Band)
      l = Free;
  int pieces = 0;
  std::vector<std::size_t> stack;
  for (std::size_t seed = 0; seed < Label.size(); ++seed)
  {
    if (Label[seed] != Free)
      continue;
    const int piece = pieces++;
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
  return static_cast<std::size_t>(pieces);
}

void OutsideBand::findPieces(const openvdb::FloatGrid& grid)
{
  const std::size_t pieces = labelPieces();
  Inside.clear();
  std::vector<std::int64_t> votes(pieces, 0), count(pieces, 0);
  auto acc = grid.getConstAccessor();
  border(
      [&](int piece, const openvdb::Coord& v)
      {
        const float value = acc.getValue(v);
        if (value != UnknownHoleValue)
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

bool OutsideBand::open() const
{
  return std::find(Mixed.begin(), Mixed.end(), true) != Mixed.end();
}

int OutsideBand::side(const openvdb::Coord& voxel) const
{
  const openvdb::Coord c = cellOf(voxel);
  for (int axis = 0; axis < 3; ++axis)
    if (c[axis] < 0 || c[axis] >= Size[axis])
      return Inside[Label[0]] ? -1 : 1;
  const int l = Label[index(c)];
  return l < 0 ? 0 : (Inside[l] ? -1 : 1);
}

void OutsideBand::borderOfSettledPieces(std::vector<std::pair<openvdb::Coord, bool>>& out) const
{
  border(
      [&](int piece, const openvdb::Coord& v)
      {
        if (!Mixed[piece])
          out.push_back({v, Inside[piece]});
      });
}

void OutsideBand::settle(openvdb::FloatGrid& grid, float background) const
{
  auto acc = grid.getAccessor();
  border(
      [&](int piece, const openvdb::Coord& v)
      {
        const float value = acc.getValue(v);
        if (value != UnknownHoleValue && !Mixed[piece] && (value < 0) != Inside[piece])
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

// ---------------------------------------------------------------------------------------------
// The holes, interpolated across.

namespace
{

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

} // namespace

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

} // namespace dp::support
