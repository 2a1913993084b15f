// SPDX-License-Identifier: BSD-3-Clause
// Shapes the detail layer's tests share: an icosphere (the icosahedron subdivided and put back on
// the sphere), a bumpy sphere around it, and a flat grid with a boundary.
#pragma once

#include "dp/geometry/MeshSurfaceSamples.h"
#include "dp/geometry/SubdivisionMap.h"

#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

namespace dp::test
{

struct Mesh
{
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;

  std::size_t vertices() const { return positions.size() / 3; }
  MeshSurface surface() const
  {
    MeshSurface s;
    s.positions = positions.data();
    s.vertices = vertices();
    s.triangles = triangles.data();
    s.triangleCount = triangles.size() / 3;
    return s;
  }
};

inline Mesh icosahedron()
{
  const double p = (1 + std::sqrt(5.0)) / 2;
  Mesh m;
  m.positions = {-1, p,  0,  1, p, 0,  -1, -p, 0,  1, -p, 0, 0,  -1, p,  0,  1, p,
                 0,  -1, -p, 0, 1, -p, p,  0,  -1, p, 0,  1, -p, 0,  -1, -p, 0, 1};
  m.triangles = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                 4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
                 6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
  return m;
}

/** The icosahedron subdivided `levels` times, each vertex put at distance radius(direction) from
 *  the origin (a unit sphere by default): 12, 42, 162, 642, 2562, 10242 vertices. */
inline Mesh icosphere(
    int levels,
    const std::function<double(const double*)>& radius = [](const double*) { return 1.0; })
{
  const Mesh ico = icosahedron();
  const SubdivisionMap map(ico.triangles, ico.vertices(), levels);
  Mesh m;
  m.triangles = map.fineTriangles();
  m.positions.resize(3 * map.fineVertices());
  map.apply(ico.positions.data(), m.positions.data());
  for (std::size_t i = 0; i < m.vertices(); ++i)
  {
    double* x = &m.positions[3 * i];
    const double length = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    const double u[3] = {x[0] / length, x[1] / length, x[2] / length};
    for (int c = 0; c < 3; ++c)
      x[c] = u[c] * radius(u);
  }
  return m;
}

/** A sphere of radius 1 with bumps of `height` (a few per great circle) on unit direction u. */
inline double bumpyRadius(const double* u, double height)
{
  return 1 + height * std::sin(5 * u[0]) * std::sin(4 * u[1] + 1) * std::cos(3 * u[2]);
}

/** The square [0, 1]^2 at z = 0 as an n x n grid of triangle pairs (a boundary all round). */
inline Mesh grid(int n)
{
  Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      m.positions.insert(m.positions.end(),
                         {static_cast<double>(i) / n, static_cast<double>(j) / n, 0.0});
  const auto at = [n](int i, int j) { return static_cast<std::int64_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      m.triangles.insert(m.triangles.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j),
                                             at(i + 1, j + 1), at(i, j + 1)});
  return m;
}

} // namespace dp::test
