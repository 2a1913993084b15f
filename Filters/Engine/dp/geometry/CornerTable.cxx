// SPDX-License-Identifier: BSD-3-Clause
#include "dp/geometry/CornerTable.h"

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <utility>

namespace dp::support
{

CornerTable::CornerTable(const IndexedMesh& mesh)
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

bool CornerTable::closed() const
{
  for (std::size_t c = 0; c < Corner.size(); ++c)
    if (Corner[c] >= 0 && Opp[c] < 0)
      return false;
  return true;
}

void CornerTable::extract(RemeshedSurface& out) const
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

// Opp from the triangles: the corner across each edge used once in each direction; an edge
// used twice in the same direction, or by more than two triangles, is a boundary.
void CornerTable::linkOpposites()
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
void CornerTable::splitFans()
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
void CornerTable::initPlanes()
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

bool CornerTable::fan(int start, std::vector<int>& out) const
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

bool CornerTable::onBoundary(int v) const
{
  thread_local std::vector<int> ring;
  return fan(Of[v], ring);
}

bool CornerTable::neighbours(int v, std::vector<int>& out) const
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

int CornerTable::valence(int v) const
{
  thread_local std::vector<int> ring;
  const bool boundary = fan(Of[v], ring);
  return static_cast<int>(ring.size()) + (boundary ? 1 : 0);
}

int CornerTable::newFace(int a, int b, int c)
{
  const int f = static_cast<int>(Corner.size());
  Corner.insert(Corner.end(), {a, b, c});
  Opp.insert(Opp.end(), {-1, -1, -1});
  return f;
}

void CornerTable::split(int c)
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

void CornerTable::flip(int c)
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

bool CornerTable::canFlip(int c) const
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

bool CornerTable::collapse(int c, double maxLength)
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
bool CornerTable::planCollapse(int c, double maxLength, CollapsePlan& plan) const
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
bool CornerTable::staysUnfolded(int c, const Vec3& target, const std::vector<int>& fanGone,
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
void CornerTable::applyCollapse(int c, const CollapsePlan& plan, const std::vector<int>& fanGone)
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
} // namespace dp::support
