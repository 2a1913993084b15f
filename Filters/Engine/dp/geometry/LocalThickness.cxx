// SPDX-License-Identifier: BSD-3-Clause
#include "dp/geometry/LocalThickness.h"

#include "dp/support/KdTree.h"

#include <cmath>
#include <utility>

namespace dp
{
namespace
{
// Six times the volume the faces enclose with the vertices' centroid: positive when they turn
// outward, for a closed mesh (where the centroid does not matter) and for an open tube alike.
double signedVolume6(const TriangleMesh& mesh, const double* x)
{
  const std::size_t n = mesh.numberOfVertices();
  double o[3] = {0, 0, 0};
  for (std::size_t v = 0; v < n; ++v)
    for (int k = 0; k < 3; ++k)
      o[k] += x[3 * v + k] / static_cast<double>(n);
  double volume = 0;
  const auto& t = mesh.triangles();
  for (std::size_t f = 0; f < mesh.numberOfTriangles(); ++f)
  {
    double a[3], b[3], c[3];
    for (int k = 0; k < 3; ++k)
    {
      a[k] = x[3 * t[3 * f] + k] - o[k];
      b[k] = x[3 * t[3 * f + 1] + k] - o[k];
      c[k] = x[3 * t[3 * f + 2] + k] - o[k];
    }
    volume += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
              a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  return volume;
}

// A vertex seen from the ball's centre within this angle of the vertex the ball touches is its
// neighbour on the same side: it shrinks the ball only through the normal's error (a normal 3
// degrees off takes a sphere's radius to 0.7 on a 15-degree mesh), so it stops the shrinking.
const double MinSeparationCosine = std::cos(40.0 * 3.14159265358979323846 / 180.0);

// Shrinks the ball tangent at p (inward normal -n) from radius `largest` until its nearest
// vertex is on its sphere: a vertex q inside the ball gives the smaller ball through p and q,
// r = |p - q|^2 / (2 n.(p - q)).
double shrinkBall(const support::KdTree& tree, const double* x, std::size_t v, const double n[3],
                  double largest)
{
  const double* p = x + 3 * v;
  double r = largest;
  for (int iteration = 0; iteration < 50; ++iteration)
  {
    const double c[3] = {p[0] - r * n[0], p[1] - r * n[1], p[2] - r * n[2]};
    double d2 = 0;
    const std::uint32_t q = tree.nearest(c, &d2);
    if (q == v || d2 >= r * r * (1 - 1e-9))
      return r;
    const double pq[3] = {p[0] - x[3 * q], p[1] - x[3 * q + 1], p[2] - x[3 * q + 2]};
    const double along = pq[0] * n[0] + pq[1] * n[1] + pq[2] * n[2];
    const double pq2 = pq[0] * pq[0] + pq[1] * pq[1] + pq[2] * pq[2];
    const double next = pq2 / (2 * along);
    if (!(along > 0) || !(next < r))
      return r;
    // The angle at the new centre between p and q: cos = 1 - |p - q|^2 / (2 r^2).
    if (1 - pq2 / (2 * next * next) > MinSeparationCosine)
      return r;
    r = next;
  }
  return r;
}
} // namespace

std::vector<double> medialRadii(const TriangleMesh& mesh, const double* positions, double largest,
                                int smoothing, MedialSide side)
{
  const std::size_t n = mesh.numberOfVertices();
  std::vector<double> normals(3 * n);
  mesh.vertexNormals(positions, normals.data());
  // The ball's side: the normal points away from it (outward for an inner ball).
  const double outward = (signedVolume6(mesh, positions) < 0 ? -1.0 : 1.0) *
                         (side == MedialSide::Outside ? -1.0 : 1.0);
  const support::KdTree tree(positions, n);
  std::vector<double> radius(n, largest);
  for (std::size_t v = 0; v < n; ++v)
  {
    const double normal[3] = {outward * normals[3 * v], outward * normals[3 * v + 1],
                              outward * normals[3 * v + 2]};
    radius[v] = shrinkBall(tree, positions, v, normal, largest);
  }
  // Single vertices of a noisy surface give small balls: average them over a few rings.
  return smoothOverRings(mesh, std::move(radius), smoothing);
}

std::vector<double> smoothOverRings(const TriangleMesh& mesh, std::vector<double> values,
                                    int passes)
{
  const std::size_t n = mesh.numberOfVertices();
  for (int pass = 0; pass < passes; ++pass)
  {
    std::vector<double> next(n);
    for (std::size_t v = 0; v < n; ++v)
    {
      double sum = values[v];
      for (const std::int64_t w : mesh.neighbours(v))
        sum += values[static_cast<std::size_t>(w)];
      next[v] = sum / static_cast<double>(mesh.neighbours(v).size() + 1);
    }
    values.swap(next);
  }
  return values;
}

} // namespace dp
