// SPDX-License-Identifier: BSD-3-Clause
#include "dp/geometry/SurfaceLocator.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace dp
{
namespace
{
constexpr std::int32_t LeafSize = 4;

inline double dot3(const double* a, const double* b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// The answer of closestPointOnTriangle for weights (u, v, s) of a, b, c: the weights into w, the
// point into closest; returns its squared distance to p.
struct WeightedCorners
{
  const double *p, *a, *b, *c;
  double* w;
  double* closest;

  double operator()(double u, double v, double s) const
  {
    w[0] = u;
    w[1] = v;
    w[2] = s;
    double d2 = 0;
    for (int k = 0; k < 3; ++k)
    {
      closest[k] = u * a[k] + v * b[k] + s * c[k];
      d2 += (p[k] - closest[k]) * (p[k] - closest[k]);
    }
    return d2;
  }
};

// The centre (mean of the corners) of each triangle, 3 per triangle.
std::vector<double> triangleCentres(const std::vector<std::int64_t>& triangles,
                                    const double* positions)
{
  const std::size_t nt = triangles.size() / 3;
  std::vector<double> centres(3 * nt);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k)
      centres[3 * t + k] =
          (positions[3 * triangles[3 * t] + k] + positions[3 * triangles[3 * t + 1] + k] +
           positions[3 * triangles[3 * t + 2] + k]) /
          3.0;
  return centres;
}

// The triangles around each of nv vertices: those of vertex v are
// around[aroundStart[v], aroundStart[v + 1]), ascending (ties go to the lower index).
void trianglesAroundVertices(const std::vector<std::int64_t>& tri, std::size_t nv,
                             std::vector<std::int32_t>& aroundStart,
                             std::vector<std::int32_t>& around)
{
  const std::size_t nt = tri.size() / 3;
  aroundStart.assign(nv + 1, 0);
  for (const std::int64_t v : tri)
    ++aroundStart[static_cast<std::size_t>(v) + 1];
  for (std::size_t v = 0; v < nv; ++v)
    aroundStart[v + 1] += aroundStart[v];
  around.resize(tri.size());
  std::vector<std::int32_t> next(aroundStart.begin(), aroundStart.end() - 1);
  for (std::size_t t = 0; t < nt; ++t) // ascending within a vertex: ties go to the lower index
    for (int c = 0; c < 3; ++c)
      around[static_cast<std::size_t>(next[static_cast<std::size_t>(tri[3 * t + c])]++)] =
          static_cast<std::int32_t>(t);
}

// Across each edge: per triangle and corner c, the triangle sharing the edge opposite c (the
// first found, for an edge of more than two; -1: none).
std::vector<std::int64_t> trianglesAcross(const std::vector<std::int64_t>& tri,
                                          const std::vector<std::int32_t>& aroundStart,
                                          const std::vector<std::int32_t>& around)
{
  const std::size_t nt = tri.size() / 3;
  std::vector<std::int64_t> across(3 * nt, -1);
  for (std::size_t t = 0; t < nt; ++t)
    for (int c = 0; c < 3; ++c)
    {
      const std::int64_t a = tri[3 * t + (c + 1) % 3], b = tri[3 * t + (c + 2) % 3];
      const auto v = static_cast<std::size_t>(a);
      for (std::int32_t i = aroundStart[v]; i < aroundStart[v + 1] && across[3 * t + c] < 0; ++i)
      {
        const auto other = static_cast<std::size_t>(around[static_cast<std::size_t>(i)]);
        if (other != t &&
            (tri[3 * other] == b || tri[3 * other + 1] == b || tri[3 * other + 2] == b))
          across[3 * t + c] = static_cast<std::int64_t>(other);
      }
    }
  return across;
}
} // namespace

double closestPointOnTriangle(const double p[3], const double a[3], const double b[3],
                              const double c[3], double w[3], double closest[3])
{
  // Ericson, Real-Time Collision Detection, 5.1.5: which Voronoi region of the triangle p is in.
  double ab[3], ac[3], ap[3];
  for (int k = 0; k < 3; ++k)
  {
    ab[k] = b[k] - a[k];
    ac[k] = c[k] - a[k];
    ap[k] = p[k] - a[k];
  }
  const WeightedCorners finish{p, a, b, c, w, closest};
  const double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
  if (d1 <= 0 && d2 <= 0)
    return finish(1, 0, 0);
  double bp[3];
  for (int k = 0; k < 3; ++k)
    bp[k] = p[k] - b[k];
  const double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
  if (d3 >= 0 && d4 <= d3)
    return finish(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0)
  {
    const double v = d1 - d3 > 0 ? d1 / (d1 - d3) : 0.0;
    return finish(1 - v, v, 0);
  }
  double cp[3];
  for (int k = 0; k < 3; ++k)
    cp[k] = p[k] - c[k];
  const double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
  if (d6 >= 0 && d5 <= d6)
    return finish(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0)
  {
    const double s = d2 - d6 > 0 ? d2 / (d2 - d6) : 0.0;
    return finish(1 - s, 0, s);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
  {
    const double s = (d4 - d3) + (d5 - d6) > 0 ? (d4 - d3) / ((d4 - d3) + (d5 - d6)) : 0.0;
    return finish(0, 1 - s, s);
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) // degenerate triangle whose regions all failed: its first vertex
    return finish(1, 0, 0);
  const double v = vb / sum, s = vc / sum;
  return finish(1 - v - s, v, s);
}

SurfaceLocator::SurfaceLocator(const TriangleMesh& mesh, const double* positions)
    : SurfaceLocator(mesh.triangles(), mesh.numberOfVertices(), positions)
{
}

SurfaceLocator::SurfaceLocator(const std::vector<std::int64_t>& triangles, std::size_t vertices,
                               const double* positions)
    : Triangles(&triangles), VertexCount(vertices)
{
  build(positions);
}

void SurfaceLocator::build(const double* positions)
{
  const std::size_t nt = Triangles->size() / 3;
  const std::size_t nv = VertexCount;
  Copy.assign(positions, positions + 3 * nv);
  Positions = Copy.data();
  std::vector<double> centres = triangleCentres(*Triangles, Positions);
  Order.resize(nt);
  std::iota(Order.begin(), Order.end(), 0);
  Nodes.clear();
  Wide.clear();
  Nodes.reserve(2 * nt / LeafSize + 2);
  if (nt == 0)
    return;
  Nodes.emplace_back();
  split(0, 0, static_cast<std::int32_t>(nt), centres);
  LeafOf.assign(nt, -1);
  for (std::size_t n = 0; n < Nodes.size(); ++n)
  {
    const Node& node = Nodes[n];
    if (node.count > 0)
      for (std::int32_t i = node.first; i < node.first + node.count; ++i)
        LeafOf[static_cast<std::size_t>(Order[static_cast<std::size_t>(i)])] =
            static_cast<std::int32_t>(n);
  }
  const auto& tri = *Triangles;
  trianglesAroundVertices(tri, nv, AroundStart, Around);
  Across = trianglesAcross(tri, AroundStart, Around);
  Wide.reserve(Nodes.size() / 3 + 1);
  collapse(0);
  WideParent.assign(Wide.size(), Place{});
  LeafPlace.assign(Nodes.size(), Place{});
  for (std::size_t w = 0; w < Wide.size(); ++w)
    for (int e = 0; e < 4; ++e)
    {
      const Place here{static_cast<std::int32_t>(w), e};
      if (Wide[w].count[e] == 0)
        WideParent[static_cast<std::size_t>(Wide[w].first[e])] = here;
      else if (Wide[w].count[e] > 0)
        LeafPlace[static_cast<std::size_t>(Wide[w].source[e])] = here;
    }
  refit(Positions);
}

// The wide node standing for binary node `binary`: its children, or for an inner child, that
// child's two children. Returns its index in Wide (children are made after their parent).
std::int32_t SurfaceLocator::collapse(std::int32_t binary)
{
  WideNode wide;
  int slots = 0;
  auto add = [&](std::int32_t node)
  {
    wide.source[slots] = node;
    wide.count[slots] = Nodes[static_cast<std::size_t>(node)].count;
    wide.first[slots] = Nodes[static_cast<std::size_t>(node)].first;
    ++slots;
  };
  const Node& self = Nodes[static_cast<std::size_t>(binary)];
  if (self.count > 0)
    add(binary); // a tree of one leaf
  else
    for (std::int32_t child = self.first; child < self.first + 2; ++child)
    {
      const Node& node = Nodes[static_cast<std::size_t>(child)];
      if (node.count > 0)
        add(child);
      else
      {
        add(node.first);
        add(node.first + 1);
      }
    }
  for (int e = slots; e < 4; ++e)
  {
    wide.source[e] = -1;
    wide.count[e] = -1;
    wide.first[e] = 0;
  }
  const auto index = static_cast<std::int32_t>(Wide.size());
  Wide.push_back(wide);
  for (int e = 0; e < slots; ++e)
    if (Wide[static_cast<std::size_t>(index)].count[e] == 0)
    {
      const std::int32_t child = collapse(Wide[static_cast<std::size_t>(index)].source[e]);
      Wide[static_cast<std::size_t>(index)].first[e] = child;
    }
  return index;
}

// Makes node `self` cover Order[begin, end): a leaf, or two children (allocated together, so
// right = left + 1, and after their parent, so a reverse sweep meets children first).
void SurfaceLocator::split(std::int32_t self, std::int32_t begin, std::int32_t end,
                           const std::vector<double>& centres)
{
  if (end - begin <= LeafSize)
  {
    Nodes[self].first = begin;
    Nodes[self].count = end - begin;
    return;
  }
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (std::int32_t i = begin; i < end; ++i)
    for (int k = 0; k < 3; ++k)
    {
      lo[k] = std::min(lo[k], centres[3 * Order[i] + k]);
      hi[k] = std::max(hi[k], centres[3 * Order[i] + k]);
    }
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (hi[k] - lo[k] > hi[axis] - lo[axis])
      axis = k;
  const std::int32_t middle = begin + (end - begin) / 2;
  // Ties broken by index, so the tree is the same on every platform.
  std::nth_element(Order.begin() + begin, Order.begin() + middle, Order.begin() + end,
                   [&](std::int32_t a, std::int32_t b)
                   {
                     const double ca = centres[3 * a + axis], cb = centres[3 * b + axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  const auto left = static_cast<std::int32_t>(Nodes.size());
  Nodes.emplace_back();
  Nodes.emplace_back();
  Nodes[self].first = left;
  Nodes[self].count = 0;
  split(left, begin, middle, centres);
  split(left + 1, middle, end, centres);
}

void SurfaceLocator::refit(const double* positions)
{
  if (positions != Copy.data())
    Copy.assign(positions, positions + 3 * VertexCount);
  Positions = Copy.data();
  // Children are stored after their parents: a reverse sweep sees children first.
  for (auto n = static_cast<std::int32_t>(Nodes.size()) - 1; n >= 0; --n)
    boxOf(n);
  for (WideNode& wide : Wide)
    for (int e = 0; e < 4; ++e)
      for (int k = 0; k < 3; ++k)
      {
        const bool empty = wide.count[e] < 0; // a box no point is near
        const Node& node = Nodes[static_cast<std::size_t>(empty ? 0 : wide.source[e])];
        wide.lo[k][e] = empty ? HUGE_VAL : static_cast<double>(node.lo[k]);
        wide.hi[k][e] = empty ? HUGE_VAL : static_cast<double>(node.hi[k]);
      }
  // Each triangle's bounding sphere, in the leaves' order: centre rounded to float, radius
  // measured from that centre and rounded up, so the sphere still holds the triangle.
  const auto& tri = *Triangles;
  Spheres.resize(Order.size());
  for (std::size_t i = 0; i < Order.size(); ++i)
  {
    const std::int64_t* t = &tri[3 * static_cast<std::size_t>(Order[i])];
    Sphere& s = Spheres[i];
    for (int k = 0; k < 3; ++k)
      s.centre[k] = static_cast<float>(
          (Positions[3 * t[0] + k] + Positions[3 * t[1] + k] + Positions[3 * t[2] + k]) / 3.0);
    double r2 = 0;
    for (int c = 0; c < 3; ++c)
    {
      double d2 = 0;
      for (int k = 0; k < 3; ++k)
      {
        const double d = Positions[3 * t[c] + k] - s.centre[k];
        d2 += d * d;
      }
      r2 = std::max(r2, d2);
    }
    s.radius = std::nextafter(static_cast<float>(std::sqrt(r2) * (1 + 1e-12)), HUGE_VALF);
  }
}

void SurfaceLocator::boxOf(std::int32_t n)
{
  Node& node = Nodes[n];
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  if (node.count > 0)
  {
    const auto& tri = *Triangles;
    for (std::int32_t i = node.first; i < node.first + node.count; ++i)
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k)
        {
          const double v = Positions[3 * tri[3 * Order[i] + c] + k];
          lo[k] = std::min(lo[k], v);
          hi[k] = std::max(hi[k], v);
        }
  }
  else
    for (int child = 0; child < 2; ++child)
      for (int k = 0; k < 3; ++k)
      {
        lo[k] = std::min(lo[k], static_cast<double>(Nodes[node.first + child].lo[k]));
        hi[k] = std::max(hi[k], static_cast<double>(Nodes[node.first + child].hi[k]));
      }
  // Rounded outward to float, so the boxes still contain their triangles.
  for (int k = 0; k < 3; ++k)
  {
    node.lo[k] = std::nextafter(static_cast<float>(lo[k]), -HUGE_VALF);
    node.hi[k] = std::nextafter(static_cast<float>(hi[k]), HUGE_VALF);
  }
}

bool SurfaceLocator::outside(const Sphere& s, const double p[3], double reach)
{
  double d2 = 0;
  for (int k = 0; k < 3; ++k)
  {
    const double d = p[k] - s.centre[k];
    d2 += d * d;
  }
  const double far = s.radius + reach;
  return d2 > far * far;
}

void SurfaceLocator::visitLeaf(std::int32_t first, std::int32_t count, const double p[3],
                               Search& search) const
{
  const auto& tri = *Triangles;
  // The bound's distance with a relative margin for the rounding of outside(): never skip a
  // triangle that might win. (Kept as a distance, so a sphere's test needs no square root.)
  double reach = std::sqrt(search.bound * (1 + 1e-9));
  for (std::int32_t i = first; i < first + count; ++i)
  {
    if (outside(Spheres[static_cast<std::size_t>(i)], p, reach))
      continue; // its bounding sphere is farther than the best so far
    const std::int64_t t = Order[i];
    double w[3], c[3];
    const double d2 =
        closestPointOnTriangle(p, &Positions[3 * tri[3 * t]], &Positions[3 * tri[3 * t + 1]],
                               &Positions[3 * tri[3 * t + 2]], w, c);
    if (search.offer(t, d2, w, c))
      reach = std::sqrt(search.bound * (1 + 1e-9));
  }
}

void SurfaceLocator::descend(std::int32_t root, int skip, const double p[3], Search& search) const
{
  // Each entry keeps its box's squared distance, measured when it was pushed: the bound may have
  // shrunk since, and the test needs no second measurement.
  struct Entry
  {
    std::int32_t first, count; // as a WideNode's child
    double distance2;
  };
  Entry stack[256];
  int top = 0;
  auto pushChildren = [&](const WideNode& wide, int skipped)
  {
    double d2[4];
    for (int e = 0; e < 4; ++e)
    {
      d2[e] = 0;
      for (int k = 0; k < 3; ++k)
      {
        const double d = std::max({wide.lo[k][e] - p[k], 0.0, p[k] - wide.hi[k][e]});
        d2[e] += d * d;
      }
    }
    // The nearest child last on the stack, so it is searched first. (A child already beyond the
    // bound never will be nearer: the bound only shrinks.)
    int nearest = -1;
    for (int e = 0; e < 4; ++e)
      if (e != skipped && wide.count[e] >= 0 && search.mayHold(d2[e]) &&
          (nearest < 0 || d2[e] < d2[nearest]))
        nearest = e;
    // (A node's pop pushes at most four: the stack holds at most 3 x depth + 4 entries, under 256
    // for any tree of fewer than 2^80 triangles.)
    for (int e = 0; e < 4; ++e)
      if (e != nearest && e != skipped && wide.count[e] >= 0 && search.mayHold(d2[e]) && top < 256)
        stack[top++] = {wide.first[e], wide.count[e], d2[e]};
    if (nearest >= 0 && top < 256)
      stack[top++] = {wide.first[nearest], wide.count[nearest], d2[nearest]};
  };
  pushChildren(Wide[static_cast<std::size_t>(root)], skip);
  while (top > 0)
  {
    const Entry entry = stack[--top];
    if (!search.mayHold(entry.distance2))
      continue;
    if (entry.count > 0)
      visitLeaf(entry.first, entry.count, p, search);
    else
      pushChildren(Wide[static_cast<std::size_t>(entry.first)], -1);
  }
}

SurfaceLocator::Hit SurfaceLocator::closest(const double p[3], double maxDistance,
                                            std::int64_t hint) const
{
  Search search;
  search.bound = maxDistance * maxDistance;
  if (Wide.empty())
    return search.best;
  if (hint < 0 || static_cast<std::size_t>(hint) >= Triangles->size() / 3)
  {
    descend(0, -1, p, search);
    return search.best;
  }
  // From the hint's leaf up to the root, searching each sibling subtree the bound reaches:
  // near the hint (where the answer usually is) first, so the bound is small early and the
  // far subtrees are dismissed by one box each. The same answer as from the root (ties go to
  // the lower triangle index, whatever the order of the search).
  const auto leaf = static_cast<std::size_t>(LeafOf[static_cast<std::size_t>(hint)]);
  visitLeaf(Nodes[leaf].first, Nodes[leaf].count, p, search);
  for (Place place = LeafPlace[leaf]; place.node >= 0;
       place = WideParent[static_cast<std::size_t>(place.node)])
    descend(place.node, place.slot, p, search);
  return search.best;
}

SurfaceLocator::Hit SurfaceLocator::follow(const double p[3], std::int64_t from,
                                           double maxDistance) const
{
  Hit best;
  if (from < 0 || static_cast<std::size_t>(from) >= Triangles->size() / 3)
    return best;
  const auto& tri = *Triangles;
  auto measure = [&](std::int64_t t, Hit& hit)
  {
    hit.triangle = t;
    hit.squaredDistance =
        closestPointOnTriangle(p, &Positions[3 * tri[3 * t]], &Positions[3 * tri[3 * t + 1]],
                               &Positions[3 * tri[3 * t + 2]], hit.barycentric, hit.point);
  };
  measure(from, best);
  // Each move lowers the distance strictly, so the walk cannot cycle; the cap only bounds a
  // walk across a badly folded mesh.
  for (int moves = 0; moves < 64; ++moves)
  {
    Hit candidate, nearest;
    auto offer = [&](std::int64_t t)
    {
      if (t < 0 || t == best.triangle)
        return;
      measure(t, candidate);
      if (candidate.squaredDistance < nearest.squaredDistance ||
          (candidate.squaredDistance == nearest.squaredDistance && t < nearest.triangle))
        nearest = candidate;
    };
    // The triangles across the three edges (from inside a surface that bends away, the next
    // side may be nearer although the closest point lies inside this triangle) and, where the
    // closest point is a corner, the triangles around it.
    for (int c = 0; c < 3; ++c)
      offer(Across[3 * static_cast<std::size_t>(best.triangle) + c]);
    for (int c = 0; c < 3; ++c)
      if (best.barycentric[c] == 1)
      {
        const auto v = static_cast<std::size_t>(tri[3 * best.triangle + c]);
        for (std::int32_t a = AroundStart[v]; a < AroundStart[v + 1]; ++a)
          offer(Around[static_cast<std::size_t>(a)]);
      }
    if (!(nearest.squaredDistance < best.squaredDistance))
      break;
    best = nearest;
  }
  if (!(best.squaredDistance < maxDistance * maxDistance))
    return Hit{};
  return best;
}

} // namespace dp
