// SPDX-License-Identifier: BSD-3-Clause
#include "dp/geometry/IsotropicRemesher.h"

#include "dp/detail/KdTree.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <unordered_map>
#include <utility>
#include <vector>

namespace dp::detail
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
// Isotropic remeshing (Botsch & Kobbelt 2004) on a corner table: corner c = 3 f + i is vertex
// i of triangle f; Opp[c] is the corner facing c across the edge opposite c (-1 on a boundary).

/**
 * The squared distance to a set of planes, area-weighted: x^T A x + 2 b.x + c (Garland &
 * Heckbert 1997, "Surface simplification using quadric error metrics"). A collapse puts the
 * merged vertex where the planes around both ends of the edge are best kept, so that tips and
 * thin parts (a toe, a horse's leg) do not shrink.
 *
 * Limits: only evaluated at the candidates (the edge's ends and midpoint), never minimised over
 * space; the planes are those of the fine surface at the start, summed along collapses and
 * splits, never refreshed.
 */
struct Quadric
{
  double a[6] = {0, 0, 0, 0, 0, 0}; // xx xy xz yy yz zz
  double b[3] = {0, 0, 0};
  double c = 0;

  void addPlane(const Vec3& normal, double offset, double weight)
  {
    const Vec3& n = normal;
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
  double operator()(const Vec3& x) const
  {
    return a[0] * x[0] * x[0] + 2 * a[1] * x[0] * x[1] + 2 * a[2] * x[0] * x[2] +
           a[3] * x[1] * x[1] + 2 * a[4] * x[1] * x[2] + a[5] * x[2] * x[2] +
           2 * (b[0] * x[0] + b[1] * x[1] + b[2] * x[2]) + c;
  }
};

/**
 * Isotropic remeshing (Botsch & Kobbelt 2004) of a triangle mesh held in a corner table, with
 * Garland-Heckbert quadrics (Quadric) placing collapsed vertices: remesh() runs the split,
 * collapse, flip and relax iterations at an edge length, adjustCount() meets a vertex count,
 * extract() gives the result. The relaxation projects every vertex onto a Reference.
 *
 * Limits: the input is made manifold (see the constructor), not repaired otherwise; deleted
 * triangles and vertices stay in the arrays as -1 until extract(), so the arrays only grow.
 * Splits and collapses are sequential; only the relaxation runs in parallel.
 */
class Remesher
{
public:
  /** Edges shared by more than two triangles, or by two of the same orientation, become
   *  boundaries; vertices where separate fans of triangles meet are split, one per fan. */
  explicit Remesher(const IndexedMesh& mesh)
  {
    X = mesh.positions;
    Corner.reserve(3 * mesh.triangles.size());
    for (const auto& t : mesh.triangles)
      Corner.insert(Corner.end(), t.begin(), t.end());
    linkOpposites();
    splitFans();
    for (int v : Of)
      Live += v >= 0;
    initPlanes();
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
  void extract(RemeshedSurface& out) const
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
  std::vector<Vec3> X;         // vertex positions
  std::vector<Quadric> Planes; // of the fine surface around each vertex
  std::vector<int> Corner;     // the vertex of each corner; -1 for a deleted triangle
  std::vector<int> Opp;        // the opposite corner across the edge facing each corner
  std::vector<int> Of;         // a corner of each vertex; -1 for a deleted vertex
  std::size_t Live = 0;        // vertices in use

  // Opp from the triangles: the corner across each edge used once in each direction; an edge
  // used twice in the same direction, or by more than two triangles, is a boundary.
  void linkOpposites()
  {
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
  }

  // One fan per vertex: corners not reached from the vertex's first fan get a new vertex. Sets Of.
  void splitFans()
  {
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
  }

  // Each vertex's quadric: the planes of the fine triangles around it.
  void initPlanes()
  {
    Planes.assign(X.size(), Quadric{});
    for (std::size_t f = 0; f < Corner.size(); f += 3)
    {
      const Vec3 n = faceNormal(static_cast<int>(f));
      const double area = norm(n);
      if (!(area > 0))
        continue;
      const Vec3 unit = (1 / area) * n;
      for (int i = 0; i < 3; ++i)
        Planes[Corner[f + i]].addPlane(unit, -dot(unit, X[Corner[f]]), area);
    }
  }

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
  Vec3 faceNormal(int c) const // not normalised
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
    const Vec3 before = faceNormal(c) + faceNormal(o);
    const Vec3 n1 = cross(X[a] - X[x], X[d] - X[x]);
    const Vec3 n2 = cross(X[b] - X[d], X[x] - X[d]);
    const double l1 = norm(n1), l2 = norm(n2), l0 = norm(before);
    if (!(l1 > 0 && l2 > 0 && l0 > 0))
      return false;
    return dot(n1, before) > 0.5 * l1 * l0 && dot(n2, before) > 0.5 * l2 * l0 &&
           dot(n1, n2) > 0.5 * l1 * l2;
  }

  // What collapsing an edge does: the end that stays (moved to target, with the merged quadric)
  // and the end that goes.
  struct CollapsePlan
  {
    int keep = -1, gone = -1;
    Vec3 target{};
    Quadric merged;
  };

  // Collapses the edge facing corner c into one vertex (at the midpoint, or at the endpoint on
  // the boundary), when that keeps the mesh manifold and unfolded and makes no edge longer than
  // maxLength. Returns whether it did.
  bool collapse(int c, double maxLength)
  {
    if (Live <= 4)
      return false;
    CollapsePlan plan;
    if (!planCollapse(c, maxLength, plan))
      return false;
    thread_local std::vector<int> fanGone, fanKeep;
    fan(Of[plan.gone], fanGone);
    fan(Of[plan.keep], fanKeep);
    if (!staysUnfolded(c, plan.target, fanGone, fanKeep))
      return false;
    applyCollapse(c, plan, fanGone);
    return true;
  }

  // The ends and the merged vertex of a collapse of the edge facing corner c; false when the
  // collapse would pinch the surface, break the link condition or make an edge longer than
  // maxLength.
  bool planCollapse(int c, double maxLength, CollapsePlan& plan) const
  {
    const int o = Opp[c];
    int keep = Corner[next(c)], gone = Corner[prev(c)];
    thread_local std::vector<int> ringKeep, ringGone;
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
    Vec3 target = 0.5 * (X[keep] + X[gone]);
    if (goneOnBoundary && !keepOnBoundary)
    {
      std::swap(keep, gone);
      target = X[keep];
    }
    else if (keepOnBoundary && !goneOnBoundary)
      target = X[keep];
    else
      // The end or the midpoint that keeps the planes around the edge best.
      for (const Vec3& candidate : {X[keep], X[gone]})
        if (merged(candidate) < merged(target))
          target = candidate;
    for (const auto* ring : {&ringKeep, &ringGone})
      for (int v : *ring)
        if (v != keep && v != gone && norm(X[v] - target) > maxLength)
          return false;
    plan.keep = keep;
    plan.gone = gone;
    plan.target = target;
    plan.merged = merged;
    return true;
  }

  // No triangle that stays (around either end, but the two on the edge facing corner c) may
  // turn over or degenerate when the end moves to target.
  bool staysUnfolded(int c, const Vec3& target, const std::vector<int>& fanGone,
                     const std::vector<int>& fanKeep) const
  {
    const int o = Opp[c];
    const int f1 = c - c % 3, f2 = o < 0 ? -1 : o - o % 3;
    for (const auto* ring : {&fanGone, &fanKeep})
      for (int r : *ring)
      {
        const int f = r - r % 3;
        if (f == f1 || f == f2)
          continue;
        const Vec3 before = faceNormal(r);
        const Vec3 p = X[Corner[next(r)]], q = X[Corner[prev(r)]];
        const Vec3 after = cross(p - target, q - target);
        const double lb = norm(before), la = norm(after);
        if (!(la > 1e-12 * lb) || dot(before, after) < 0.3 * la * lb)
          return false;
      }
    return true;
  }

  // Carries out a planned collapse of the edge facing corner c; `fanGone`: the corners of the
  // end that goes, before the collapse.
  void applyCollapse(int c, const CollapsePlan& plan, const std::vector<int>& fanGone)
  {
    const int o = Opp[c];
    const int f1 = c - c % 3, f2 = o < 0 ? -1 : o - o % 3;
    const int keep = plan.keep;
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
    X[keep] = plan.target;
    Planes[keep] = plan.merged;
    Of[plan.gone] = -1;
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

} // namespace dp::detail
