// SPDX-License-Identifier: BSD-3-Clause
#include "PerFrameMesh.h"

#include "dp/field/SurfaceReconstruction.h"
#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/NormalEstimation.h"
#include "dp/geometry/TriangleMesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <vector>

namespace dp::cli
{
namespace
{
// The samples in grid cells, for the nearest sample to a vertex (the vertices lie on the
// surface the samples came from, so a few cells around each suffice; farther, every sample).
class NearestSample
{
public:
  NearestSample(const std::vector<double>& points, double cell) : Points(points), Cell(cell)
  {
    for (std::size_t i = 0; i < points.size() / 3; ++i)
      Cells[key(&points[3 * i])].push_back(i);
  }
  std::size_t operator()(const double* x) const
  {
    const std::array<long long, 3> c = key(x);
    std::size_t best = 0;
    double bestD2 = std::numeric_limits<double>::infinity();
    const auto offer = [&](std::size_t i)
    {
      double d2 = 0;
      for (int k = 0; k < 3; ++k)
        d2 += (Points[3 * i + k] - x[k]) * (Points[3 * i + k] - x[k]);
      if (d2 < bestD2 || (d2 == bestD2 && i < best))
      {
        bestD2 = d2;
        best = i;
      }
    };
    for (long long dx = -1; dx <= 1; ++dx)
      for (long long dy = -1; dy <= 1; ++dy)
        for (long long dz = -1; dz <= 1; ++dz)
        {
          const auto it = Cells.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it != Cells.end())
            for (std::size_t i : it->second)
              offer(i);
        }
    if (!(bestD2 <= Cell * Cell))
      for (std::size_t i = 0; i < Points.size() / 3; ++i)
        offer(i);
    return best;
  }

private:
  std::array<long long, 3> key(const double* p) const
  {
    return {static_cast<long long>(std::floor(p[0] / Cell)),
            static_cast<long long>(std::floor(p[1] / Cell)),
            static_cast<long long>(std::floor(p[2] / Cell))};
  }
  const std::vector<double>& Points;
  double Cell;
  std::map<std::array<long long, 3>, std::vector<std::size_t>> Cells;
};

// Appends a copy of vertex v (its normal and colour too) and returns its index.
std::int64_t copyVertex(PointCloud& mesh, std::int64_t v)
{
  const int components = mesh.colorComponents;
  // Copies first: inserting a vector's own elements into it may move them.
  const std::vector<double> p(&mesh.points[3 * v], &mesh.points[3 * v] + 3);
  mesh.points.insert(mesh.points.end(), p.begin(), p.end());
  if (!mesh.normals.empty())
  {
    const std::vector<float> q(&mesh.normals[3 * v], &mesh.normals[3 * v] + 3);
    mesh.normals.insert(mesh.normals.end(), q.begin(), q.end());
  }
  if (components)
  {
    const std::vector<std::uint8_t> c(&mesh.colors[components * v],
                                      &mesh.colors[components * v] + components);
    mesh.colors.insert(mesh.colors.end(), c.begin(), c.end());
  }
  return static_cast<std::int64_t>(mesh.numberOfPoints() - 1);
}

// Triangles without area: repeated corners, and collinear ones (an edge's midpoint).
void addDegenerateTriangles(PointCloud& mesh)
{
  const std::int64_t a = mesh.faceConnectivity[0], b = mesh.faceConnectivity[1];
  std::int64_t ids[3] = {a, b, b};
  mesh.addFace(ids, 3);
  ids[0] = b;
  ids[1] = a;
  ids[2] = a;
  mesh.addFace(ids, 3);
  const std::int64_t middle = copyVertex(mesh, a);
  for (int k = 0; k < 3; ++k)
    mesh.points[3 * middle + k] = 0.5 * (mesh.points[3 * a + k] + mesh.points[3 * b + k]);
  ids[0] = a;
  ids[1] = b;
  ids[2] = middle;
  mesh.addFace(ids, 3);
}

// A small stray part: a tetrahedron beside the bounding box of the first `n` vertices.
void addStrayPart(PointCloud& mesh, std::int64_t n, double diagonal)
{
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL};
  for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i)
    for (int k = 0; k < 3; ++k)
      lo[k] = std::min(lo[k], mesh.points[3 * i + k]);
  const double size = 0.01 * diagonal;
  const double corner[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::int64_t first = copyVertex(mesh, 0);
  for (int c = 1; c < 4; ++c)
    copyVertex(mesh, 0);
  for (int c = 0; c < 4; ++c)
    for (int k = 0; k < 3; ++k)
      mesh.points[3 * (first + c) + k] = lo[k] - 0.05 * diagonal + size * corner[c][k];
  const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (const auto& f : faces)
  {
    const std::int64_t t[3] = {first + f[0], first + f[1], first + f[2]};
    mesh.addFace(t, 3);
  }
}

// The defects marching cubes leaves: duplicate vertices, triangles without area, a stray part.
void addDefects(PointCloud& mesh, double diagonal)
{
  const auto n = static_cast<std::int64_t>(mesh.numberOfPoints());
  // Duplicate vertices: the first corner of faces 0..4 moved to a copy of itself.
  for (std::size_t f = 0; f < 5 && f < mesh.numberOfFaces(); ++f)
  {
    std::int64_t& corner = mesh.faceConnectivity[static_cast<std::size_t>(mesh.faceOffsets[f])];
    corner = copyVertex(mesh, corner);
  }
  addDegenerateTriangles(mesh);
  addStrayPart(mesh, n, diagonal);
}
} // namespace

PointCloud perFrameMesh(const PointCloud& samples, std::size_t vertices, bool defects)
{
  const std::size_t n = samples.numberOfPoints();
  const std::vector<float> normals =
      samples.hasNormals() ? samples.normals : estimateNormals(samples.points.data(), n);
  ReconstructionOptions o;
  o.targetVertices = vertices;
  // As a capture's marching cubes: a part cut off by a hole (a tail) stays, noise floaters go.
  o.keptPieceShare = 0.01;
  const ReconstructedMesh surface = reconstructSurface(samples.points.data(), normals.data(), n, o);
  PointCloud mesh;
  mesh.points = surface.positions;
  for (std::size_t t = 0; t < surface.triangles.size(); t += 3)
    mesh.addFace(&surface.triangles[t], 3);
  const std::size_t nv = mesh.numberOfPoints();
  if (samples.hasNormals())
  {
    std::vector<double> vertexNormals(3 * nv);
    TriangleMesh(surface.triangles, nv).vertexNormals(mesh.points.data(), vertexNormals.data());
    mesh.normals.assign(vertexNormals.begin(), vertexNormals.end());
  }
  const double diagonal = boundingBoxDiagonal(samples.points.data(), n);
  if (samples.hasColors())
  {
    mesh.colorComponents = samples.colorComponents;
    const NearestSample nearest(
        samples.points, diagonal / std::sqrt(static_cast<double>(std::max<std::size_t>(n, 1))));
    const auto c = static_cast<std::size_t>(samples.colorComponents);
    for (std::size_t v = 0; v < nv; ++v)
    {
      const std::size_t i = nearest(&mesh.points[3 * v]);
      mesh.colors.insert(mesh.colors.end(), &samples.colors[c * i], &samples.colors[c * i] + c);
    }
  }
  if (defects)
    addDefects(mesh, diagonal);
  return mesh;
}

} // namespace dp::cli
