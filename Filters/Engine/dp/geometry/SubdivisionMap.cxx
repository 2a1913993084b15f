// SPDX-License-Identifier: BSD-3-Clause
#include "dp/geometry/SubdivisionMap.h"

#include "dp/geometry/TriangleMesh.h"
#include "dp/support/Parallel.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace dp
{
namespace
{

// One side of an edge: the triangle corner it faces and the vertex opposite it.
struct EdgeSide
{
  std::int64_t a, b;     // a < b
  std::int64_t opposite; // the third vertex of the triangle
  std::size_t corner;    // 3 t + k: triangle t's edge from its corner k to k + 1
};

// The level's edges: for each unique edge its ends and the opposite vertices of its triangles.
struct Edges
{
  std::vector<std::array<std::int64_t, 2>> ends;
  std::vector<std::array<std::int64_t, 2>> opposite; // both set only for an interior edge
  std::vector<std::uint8_t> sharp;                   // one triangle, or more than two
  std::vector<std::size_t> ofCorner;                 // edge index of each triangle corner's edge
};

Edges edgesOf(const std::vector<std::int64_t>& triangles)
{
  std::vector<EdgeSide> sides;
  sides.reserve(triangles.size());
  for (std::size_t c = 0; c < triangles.size(); ++c)
  {
    const std::size_t t = c / 3, k = c % 3;
    const std::int64_t u = triangles[c], v = triangles[3 * t + (k + 1) % 3];
    sides.push_back({std::min(u, v), std::max(u, v), triangles[3 * t + (k + 2) % 3], c});
  }
  std::sort(sides.begin(), sides.end(),
            [](const EdgeSide& x, const EdgeSide& y) {
              return x.a != y.a ? x.a < y.a : x.b != y.b ? x.b < y.b : x.corner < y.corner;
            });
  Edges e;
  e.ofCorner.resize(triangles.size());
  for (std::size_t i = 0; i < sides.size();)
  {
    std::size_t j = i;
    while (j < sides.size() && sides[j].a == sides[i].a && sides[j].b == sides[i].b)
      ++j;
    const std::size_t index = e.ends.size();
    e.ends.push_back({sides[i].a, sides[i].b});
    const bool interior = j - i == 2;
    e.opposite.push_back({sides[i].opposite, interior ? sides[i + 1].opposite : -1});
    e.sharp.push_back(interior ? 0 : 1);
    for (std::size_t s = i; s < j; ++s)
      e.ofCorner[sides[s].corner] = index;
    i = j;
  }
  return e;
}

// Loop's weight of each neighbour of a smooth vertex of valence n (Warren's simplification).
double loopBeta(std::size_t n)
{
  return n > 3 ? 3.0 / (8.0 * static_cast<double>(n)) : 3.0 / 16.0;
}

// Each vertex's edges (CSR): vertex v's are edge[first[v] .. first[v + 1]).
struct VertexEdges
{
  std::vector<std::size_t> first, edge;
};

VertexEdges vertexEdgesOf(const Edges& e, std::size_t vertices)
{
  VertexEdges ve;
  std::vector<std::size_t>& first = ve.first;
  first.assign(vertices + 1, 0);
  for (const auto& ab : e.ends)
  {
    ++first[static_cast<std::size_t>(ab[0]) + 1];
    ++first[static_cast<std::size_t>(ab[1]) + 1];
  }
  for (std::size_t v = 0; v < vertices; ++v)
    first[v + 1] += first[v];
  std::vector<std::size_t> fill(first.begin(), first.end() - 1);
  ve.edge.resize(first.back());
  for (std::size_t i = 0; i < e.ends.size(); ++i)
    for (const std::int64_t end : e.ends[i])
      ve.edge[fill[static_cast<std::size_t>(end)]++] = i;
  return ve;
}

// A level's masks as they are made: row r of its output is sum of weight[k] * input[column[k]],
// k in [start[r], start[r + 1]).
struct MaskRows
{
  std::vector<std::size_t> start{0};
  std::vector<std::int64_t> column;
  std::vector<double> weight;

  void add(std::int64_t c, double w)
  {
    column.push_back(c);
    weight.push_back(w);
  }
  void endRow() { start.push_back(column.size()); }
};

// Loop's masks of the level's old vertices: a vertex unused or at a corner stays, one on a
// sharp crease moves along it, a smooth one towards its neighbours.
void addVertexMasks(const Edges& e, std::size_t vertices, MaskRows& rows)
{
  const VertexEdges ve = vertexEdgesOf(e, vertices);
  const std::vector<std::size_t>& first = ve.first;
  for (std::size_t v = 0; v < vertices; ++v)
  {
    const std::size_t n = first[v + 1] - first[v];
    const auto self = static_cast<std::int64_t>(v);
    std::vector<std::int64_t> sharpNeighbours;
    for (std::size_t k = first[v]; k < first[v + 1]; ++k)
    {
      const auto& ab = e.ends[ve.edge[k]];
      if (e.sharp[ve.edge[k]])
        sharpNeighbours.push_back(ab[0] == self ? ab[1] : ab[0]);
    }
    if (n == 0 || (!sharpNeighbours.empty() && sharpNeighbours.size() != 2))
      rows.add(self, 1.0); // unused, or a corner
    else if (sharpNeighbours.size() == 2)
    {
      rows.add(self, 0.75);
      rows.add(sharpNeighbours[0], 0.125);
      rows.add(sharpNeighbours[1], 0.125);
    }
    else
    {
      const double beta = loopBeta(n);
      rows.add(self, 1.0 - static_cast<double>(n) * beta);
      for (std::size_t k = first[v]; k < first[v + 1]; ++k)
      {
        const auto& ab = e.ends[ve.edge[k]];
        rows.add(ab[0] == self ? ab[1] : ab[0], beta);
      }
    }
    rows.endRow();
  }
}

// Loop's masks of the vertices the level makes on its edges, one per edge in order.
void addEdgeMasks(const Edges& e, MaskRows& rows)
{
  for (std::size_t i = 0; i < e.ends.size(); ++i)
  {
    const auto& ab = e.ends[i];
    if (e.sharp[i])
    {
      rows.add(ab[0], 0.5);
      rows.add(ab[1], 0.5);
    }
    else
    {
      rows.add(ab[0], 0.375);
      rows.add(ab[1], 0.375);
      rows.add(e.opposite[i][0], 0.125);
      rows.add(e.opposite[i][1], 0.125);
    }
    rows.endRow();
  }
}

// Each of the level's triangles split in four at its edges' new vertices (numbered from
// `vertices` on in edge order).
std::vector<std::int64_t> childTriangles(const std::vector<std::int64_t>& triangles, const Edges& e,
                                         std::size_t vertices)
{
  std::vector<std::int64_t> children;
  children.reserve(4 * triangles.size());
  const auto offset = static_cast<std::int64_t>(vertices);
  for (std::size_t t = 0; t < triangles.size(); t += 3)
  {
    const std::int64_t a = triangles[t], b = triangles[t + 1], c = triangles[t + 2];
    const std::int64_t ab = offset + static_cast<std::int64_t>(e.ofCorner[t]);
    const std::int64_t bc = offset + static_cast<std::int64_t>(e.ofCorner[t + 1]);
    const std::int64_t ca = offset + static_cast<std::int64_t>(e.ofCorner[t + 2]);
    children.insert(children.end(), {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca});
  }
  return children;
}

} // namespace

SubdivisionMap::SubdivisionMap(const std::vector<std::int64_t>& baseTriangles,
                               std::size_t baseVertices, int levels)
    : BaseVertices(baseVertices)
{
  if (levels < 0 || levels > MaximumDetailLevels)
    throw std::invalid_argument("detail levels must be 0 to " +
                                std::to_string(MaximumDetailLevels) + ", not " +
                                std::to_string(levels));
  if (baseTriangles.size() % 3 != 0)
    throw std::invalid_argument("triangle indices are not a multiple of 3");
  for (std::size_t t = 0; t < baseTriangles.size(); t += 3)
  {
    const std::int64_t* v = &baseTriangles[t];
    for (int k = 0; k < 3; ++k)
      if (v[k] < 0 || static_cast<std::size_t>(v[k]) >= baseVertices)
        throw std::invalid_argument("triangle " + std::to_string(t / 3) + " uses vertex " +
                                    std::to_string(v[k]) + " of " + std::to_string(baseVertices));
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
      throw std::invalid_argument("triangle " + std::to_string(t / 3) + " repeats a vertex");
  }
  Triangles = baseTriangles;
  Counts.push_back(baseVertices);
  for (int l = 0; l < levels; ++l)
    subdivide(Triangles, Counts.back());
}

void SubdivisionMap::subdivide(std::vector<std::int64_t>& triangles, std::size_t vertices)
{
  const Edges e = edgesOf(triangles);
  MaskRows rows;
  addVertexMasks(e, vertices, rows);
  addEdgeMasks(e, rows);
  Levels.push_back({std::move(rows.start), std::move(rows.column), std::move(rows.weight)});
  Parents.insert(Parents.end(), e.ends.begin(), e.ends.end());
  Counts.push_back(vertices + e.ends.size());
  triangles = childTriangles(triangles, e, vertices);
}

void SubdivisionMap::apply(const double* base, double* fine) const
{
  std::vector<double> from(base, base + 3 * BaseVertices), to;
  for (std::size_t l = 0; l < Levels.size(); ++l)
  {
    const Level& level = Levels[l];
    const std::size_t rows = Counts[l + 1];
    double* out = l + 1 == Levels.size() ? fine : (to.assign(3 * rows, 0.0), to.data());
    forEachIndex(rows,
                 [&](std::size_t r)
                 {
                   double x = 0, y = 0, z = 0;
                   for (std::size_t k = level.start[r]; k < level.start[r + 1]; ++k)
                   {
                     const double* p = &from[3 * static_cast<std::size_t>(level.column[k])];
                     x += level.weight[k] * p[0];
                     y += level.weight[k] * p[1];
                     z += level.weight[k] * p[2];
                   }
                   out[3 * r] = x;
                   out[3 * r + 1] = y;
                   out[3 * r + 2] = z;
                 });
    if (l + 1 < Levels.size())
      from.swap(to);
  }
  if (Levels.empty())
    std::copy(base, base + 3 * BaseVertices, fine);
}

void SubdivisionMap::subdivide(const double* base, double* fine, double* normals) const
{
  apply(base, fine);
  vertexNormalsOf(Triangles, fine, fineVertices(), normals);
}

std::vector<std::uint8_t> subdividedColours(const SubdivisionMap& map, const std::uint8_t* rgb)
{
  const std::vector<double> base(rgb, rgb + 3 * map.baseVertices());
  std::vector<double> fine(3 * map.fineVertices());
  map.apply(base.data(), fine.data());
  std::vector<std::uint8_t> out(fine.size());
  for (std::size_t i = 0; i < fine.size(); ++i)
    out[i] = static_cast<std::uint8_t>(std::clamp(std::lround(fine[i]), 0L, 255L));
  return out;
}

void displaceAlongNormals(const double* fine, const double* normals, const double* displacements,
                          std::size_t vertices, double* out)
{
  forEachIndex(vertices,
               [&](std::size_t i)
               {
                 for (int c = 0; c < 3; ++c)
                   out[3 * i + c] = fine[3 * i + c] + displacements[i] * normals[3 * i + c];
               });
}

} // namespace dp
