// SPDX-License-Identifier: BSD-3-Clause
#include "dp/geometry/TriangleMesh.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace dp
{
namespace
{
void cross(const double* a, const double* b, double* out)
{
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

// Unnormalised normal (twice the area) of triangle t.
void faceNormal(const std::vector<std::int64_t>& tris, std::size_t t, const double* x, double* n)
{
  const double* a = x + 3 * tris[3 * t];
  const double* b = x + 3 * tris[3 * t + 1];
  const double* c = x + 3 * tris[3 * t + 2];
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  cross(u, v, n);
}

// A directed edge (a, b) with the opposite vertex of its triangle (a, b, opposite).
struct Directed
{
  std::int64_t a, b, opposite;
};

// The order of directed edges: by (a, b).
bool before(const Directed& x, const Directed& y)
{
  return x.a != y.a ? x.a < y.a : x.b < y.b;
}

// The triangles' directed edges, sorted by (a, b); where a directed edge repeats (a non-manifold
// fan) the last triangle's is kept. Throws std::invalid_argument for a vertex index out of range
// or a triangle that repeats a vertex.
std::vector<Directed> directedEdges(const std::vector<std::int64_t>& triangles,
                                    std::size_t vertexCount)
{
  const auto n = static_cast<std::int64_t>(vertexCount);
  std::vector<Directed> directed;
  directed.reserve(triangles.size());
  for (std::size_t t = 0; t < triangles.size() / 3; ++t)
  {
    const std::int64_t* v = &triangles[3 * t];
    for (int k = 0; k < 3; ++k)
      if (v[k] < 0 || v[k] >= n)
        throw std::invalid_argument("triangle " + std::to_string(t) + " uses vertex " +
                                    std::to_string(v[k]) + " of " + std::to_string(n));
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
      throw std::invalid_argument("triangle " + std::to_string(t) + " repeats a vertex");
    for (int k = 0; k < 3; ++k)
      directed.push_back({v[k], v[(k + 1) % 3], v[(k + 2) % 3]});
  }
  std::stable_sort(directed.begin(), directed.end(), before);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < directed.size(); ++i)
  {
    const bool last = i + 1 == directed.size() || before(directed[i], directed[i + 1]);
    if (last)
      directed[kept++] = directed[i];
  }
  directed.resize(kept);
  return directed;
}

} // namespace

TriangleMesh::TriangleMesh(std::vector<std::int64_t> triangles, std::size_t vertexCount)
    : Triangles(std::move(triangles)), VertexCount(vertexCount)
{
  if (Triangles.size() % 3 != 0)
    throw std::invalid_argument("triangle indices are not a multiple of 3");
  const std::vector<Directed> directed = directedEdges(Triangles, vertexCount);
  Neighbours.assign(vertexCount, {});
  for (const Directed& e : directed)
  {
    const Directed key{e.b, e.a, 0};
    const auto reverse = std::lower_bound(directed.begin(), directed.end(), key, before);
    const bool paired = reverse != directed.end() && reverse->a == e.b && reverse->b == e.a;
    if (!paired || e.a < e.b)
    {
      Edges.push_back({std::min(e.a, e.b), std::max(e.a, e.b)});
      Neighbours[e.a].push_back(e.b);
      Neighbours[e.b].push_back(e.a);
    }
    if (paired && e.a < e.b)
      Hinges.push_back({e.a, e.b, e.opposite, reverse->opposite});
  }
  for (auto& ring : Neighbours)
  {
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  }
  // A boundary edge seen once from each side is not possible; edges listed twice (from a
  // non-manifold fan) are made unique.
  std::sort(Edges.begin(), Edges.end());
  Edges.erase(std::unique(Edges.begin(), Edges.end()), Edges.end());
}

std::vector<double> TriangleMesh::vertexAreas(const double* positions) const
{
  std::vector<double> area(VertexCount, 0.0);
  for (std::size_t t = 0; t < numberOfTriangles(); ++t)
  {
    double n[3];
    faceNormal(Triangles, t, positions, n);
    const double third = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) / 6.0;
    for (int k = 0; k < 3; ++k)
      area[Triangles[3 * t + k]] += third;
  }
  return area;
}

double TriangleMesh::totalArea(const double* positions) const
{
  double total = 0;
  for (std::size_t t = 0; t < numberOfTriangles(); ++t)
  {
    double n[3];
    faceNormal(Triangles, t, positions, n);
    total += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  }
  return total;
}

void TriangleMesh::vertexNormals(const double* positions, double* normals) const
{
  vertexNormalsOf(Triangles, positions, VertexCount, normals);
}

void vertexNormalsOf(const std::vector<std::int64_t>& triangles, const double* positions,
                     std::size_t vertices, double* normals)
{
  std::fill(normals, normals + 3 * vertices, 0.0);
  for (std::size_t t = 0; t < triangles.size() / 3; ++t)
  {
    double n[3];
    faceNormal(triangles, t, positions, n);
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c)
        normals[3 * triangles[3 * t + k] + c] += n[c];
  }
  for (std::size_t v = 0; v < vertices; ++v)
  {
    double* n = normals + 3 * v;
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (length > 0)
      for (int c = 0; c < 3; ++c)
        n[c] /= length;
  }
}

double TriangleMesh::poorlyShapedShare(const double* x, double threshold) const
{
  if (Triangles.empty())
    return 0;
  std::size_t poor = 0;
  for (std::size_t t = 0; t < Triangles.size(); t += 3)
  {
    const double* p[3] = {x + 3 * Triangles[t], x + 3 * Triangles[t + 1], x + 3 * Triangles[t + 2]};
    double squares = 0;
    for (int e = 0; e < 3; ++e)
      for (int k = 0; k < 3; ++k)
        squares += (p[(e + 1) % 3][k] - p[e][k]) * (p[(e + 1) % 3][k] - p[e][k]);
    const double u[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
    const double v[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    const double c[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                         u[0] * v[1] - u[1] * v[0]};
    const double area = 0.5 * std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    poor += !(squares > 0 && 4 * std::sqrt(3.0) * area / squares >= threshold);
  }
  return static_cast<double>(poor) / static_cast<double>(Triangles.size() / 3);
}

} // namespace dp
