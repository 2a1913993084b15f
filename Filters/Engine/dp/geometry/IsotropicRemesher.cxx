// SPDX-License-Identifier: BSD-3-Clause
#include "dp/geometry/IsotropicRemesher.h"

#include "dp/geometry/CornerTable.h"
#include "dp/support/KdTree.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

namespace dp::support
{
namespace
{
// ---------------------------------------------------------------------------------------------
// The closest point on the fine mesh: the reference surface the remeshed vertices stay on.

// The closest point of triangle a b c to p (Ericson, Real-Time Collision Detection, 5.1.5).
// dp::closestPointOnTriangle (track/SurfaceLocator.h) finds the same point but forms it as
// u a + v b + w c rather than a + v (b - a) + w (c - a) (or b + t (c - b), or a vertex itself):
// a few ulps apart, which would change every reconstructed template's bits, so this one stays.
// It divides by zero for a triangle of zero area, which never reaches it: Reference::project
// skips the triangles that do not face the vertex's way, zero-area ones included.
Vec3 closestOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c)
{
  // Regions of the triangle's Voronoi diagram (vertices, edges, face), in turn.
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0)
    return a;
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3)
    return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0)
    return a + (d1 / (d1 - d3)) * ab;
  const Vec3 cp = p - c;
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

std::vector<double> flatten(const std::vector<Vec3>& positions)
{
  std::vector<double> flat;
  flat.reserve(3 * positions.size());
  for (const Vec3& p : positions)
    flat.insert(flat.end(), p.begin(), p.end());
  return flat;
}

/**
 * The reference surface the remeshed vertices stay on: the fine mesh, with a kd-tree over its
 * vertices and the triangles around each vertex. A projection searches the triangles around the
 * nearest vertices only (not an exact closest point of the whole surface, as dp::SurfaceLocator's
 * is) and only those facing the vertex's way, which keeps a vertex on its side of a thin part.
 *
 * Limits: the search covers the triangles around the nearest 8 (then 48) vertices, so a nearer
 * triangle none of whose corners is among them is missed; when none faces the vertex's way, the
 * point stays where it is. Const and thread-safe; the mesh must outlive it.
 */
class Reference
{
public:
  explicit Reference(const IndexedMesh& mesh)
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
  Vec3 project(const Vec3& p, const Vec3& normal) const
  {
    for (std::size_t k : {8, 48})
    {
      std::uint32_t ids[48];
      double d2[48];
      const std::size_t found = Tree.nearest(p.data(), std::min(k, Mesh.positions.size()), ids, d2);
      double best = std::numeric_limits<double>::infinity();
      Vec3 result = p;
      for (std::size_t j = 0; j < found; ++j)
        for (int f = Offsets[ids[j]]; f < Offsets[ids[j] + 1]; ++f)
        {
          const auto& t = Mesh.triangles[Faces[f]];
          const Vec3& a = Mesh.positions[t[0]];
          const Vec3& b = Mesh.positions[t[1]];
          const Vec3& c = Mesh.positions[t[2]];
          if (dot(cross(b - a, c - a), normal) <= 0)
            continue;
          const Vec3 q = closestOnTriangle(p, a, b, c);
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
  const IndexedMesh& Mesh;
  std::vector<double> Flat;
  KdTree Tree;
  std::vector<int> Offsets, Faces; // the triangles around each vertex
};

// ---------------------------------------------------------------------------------------------
// The remeshing passes, over the corner table and its local operations (CornerTable.h).

/**
 * Isotropic remeshing (Botsch & Kobbelt 2004) of a triangle mesh held in a corner table, with
 * Garland-Heckbert quadrics placing collapsed vertices (CornerTable): remesh() runs the split,
 * collapse, flip and relax iterations at an edge length, adjustCount() meets a vertex count,
 * extract() gives the result. The relaxation projects every vertex onto a Reference.
 *
 * Limits: those of CornerTable. Splits and collapses are sequential; only the relaxation runs in
 * parallel.
 */
class Remesher : public CornerTable
{
public:
  using CornerTable::CornerTable;

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
      std::vector<std::pair<double, int>> edges = edgesWithLengths();
      if (Live > wanted)
        collapseShortest(edges, wanted, length);
      else
        splitLongest(edges, wanted);
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

private:
  // Each edge once, as (its length, a corner facing it).
  std::vector<std::pair<double, int>> edgesWithLengths() const
  {
    std::vector<std::pair<double, int>> edges;
    for (int c = 0; c < static_cast<int>(Corner.size()); ++c)
      if (Corner[c] >= 0 && (Opp[c] < 0 || c < Opp[c]))
        edges.push_back({edgeLength(c), c});
    return edges;
  }

  // Collapses `edges`, shortest first, until there are `wanted` vertices.
  void collapseShortest(std::vector<std::pair<double, int>>& edges, std::size_t wanted,
                        double length)
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

  // Splits the longest of `edges` for the vertices wanted. Each split adds one vertex; an edge
  // split earlier in this round is not split again.
  void splitLongest(std::vector<std::pair<double, int>>& edges, std::size_t wanted)
  {
    std::sort(edges.rbegin(), edges.rend());
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
  static double quality(const Vec3& a, const Vec3& b, const Vec3& c)
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
      const Vec3 &x = X[Corner[c]], &a = X[Corner[next(c)]], &b = X[Corner[prev(c)]],
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
      const Vec3 &a = X[Corner[f]], &b = X[Corner[f + 1]], &c = X[Corner[f + 2]];
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
    std::vector<Vec3> moved = relaxed(reference);
    takeBackFolds(moved);
    X.swap(moved);
  }

  // The relaxed and projected position of every vertex (relax's first step).
  std::vector<Vec3> relaxed(const Reference& reference) const
  {
    std::vector<Vec3> moved(X);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, X.size(), 256),
                      [&](const tbb::blocked_range<std::size_t>& range)
                      {
                        std::vector<int> ring;
                        for (std::size_t v = range.begin(); v != range.end(); ++v)
                        {
                          if (Of[v] < 0)
                            continue;
                          const bool boundary = fan(Of[v], ring);
                          Vec3 normal{0, 0, 0}, centre{0, 0, 0};
                          double area = 0;
                          for (int r : ring)
                          {
                            const Vec3 n = faceNormal(r);
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
                          Vec3 target = X[v];
                          if (!boundary)
                          {
                            const Vec3 move = (1 / area) * centre - X[v];
                            target = X[v] + (move - dot(move, normal) * normal);
                          }
                          moved[v] = reference.project(target, normal);
                        }
                      });
    return moved;
  }

  // Moves that would turn a triangle over or flatten it (two vertices onto the same point of
  // the reference, at a tip) are taken back.
  void takeBackFolds(std::vector<Vec3>& moved) const
  {
    for (int pass = 0; pass < 4; ++pass)
    {
      bool any = false;
      for (std::size_t f = 0; f < Corner.size(); f += 3)
      {
        if (Corner[f] < 0)
          continue;
        const int a = Corner[f], b = Corner[f + 1], c = Corner[f + 2];
        const Vec3 before = cross(X[b] - X[a], X[c] - X[a]);
        const Vec3 after = cross(moved[b] - moved[a], moved[c] - moved[a]);
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
  }
};

} // namespace

RemeshedSurface remeshIsotropic(const IndexedMesh& fine, std::size_t targetVertices)
{
  // Edge length for the wanted count: a closed surface of V vertices has about 2 V triangles,
  // equilateral ones of edge L have area sqrt(3)/4 L^2 each.
  double area = 0;
  for (const auto& t : fine.triangles)
    area += 0.5 * norm(cross(fine.positions[t[1]] - fine.positions[t[0]],
                             fine.positions[t[2]] - fine.positions[t[0]]));
  const double wanted = static_cast<double>(targetVertices);
  double length = std::sqrt(2 * area / (std::sqrt(3.0) * wanted));
  const Reference reference(fine);
  Remesher remesher(fine);
  remesher.remesh(length, 6, reference);
  length *= std::clamp(std::sqrt(static_cast<double>(remesher.vertices()) / wanted), 0.5, 2.0);
  remesher.remesh(length, 4, reference);
  remesher.adjustCount(targetVertices, length, reference);

  RemeshedSurface out;
  remesher.extract(out);
  out.closed = remesher.closed();
  return out;
}

} // namespace dp::support
