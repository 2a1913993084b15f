// SPDX-License-Identifier: BSD-3-Clause
// Handles of a closed surface cut where they are thinnest (HandleRemoval.h).
#include "dp/geometry/HandleRemoval.h"

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <queue>
#include <unordered_map>
#include <utility>
#include <vector>

namespace dp::support
{

namespace
{

constexpr std::size_t MostRoots = 64;

std::uint64_t key(int a, int b)
{
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
         static_cast<std::uint32_t>(b);
}

// The mesh's edges (each once, a < b), the faces on each, and each vertex's edges.
struct Edges
{
  std::vector<std::pair<int, int>> ends;
  std::vector<std::array<int, 2>> faces; // -1: none
  std::vector<std::vector<int>> ofVertex;
  std::vector<std::array<int, 3>> ofFace;
  std::unordered_map<std::uint64_t, int> index;
  bool manifoldAndClosed = true;

  explicit Edges(const IndexedMesh& m) : ofVertex(m.positions.size()), ofFace(m.triangles.size())
  {
    for (std::size_t f = 0; f < m.triangles.size(); ++f)
      for (int k = 0; k < 3; ++k)
      {
        const int a = m.triangles[f][k], b = m.triangles[f][(k + 1) % 3];
        const auto [it, added] =
            index.emplace(key(std::min(a, b), std::max(a, b)), static_cast<int>(ends.size()));
        ofFace[f][k] = it->second;
        if (added)
        {
          ends.push_back({std::min(a, b), std::max(a, b)});
          faces.push_back({static_cast<int>(f), -1});
          ofVertex[a].push_back(it->second);
          ofVertex[b].push_back(it->second);
        }
        else if (faces[it->second][1] < 0)
          faces[it->second][1] = static_cast<int>(f);
        else
          manifoldAndClosed = false;
      }
    for (const auto& f : faces)
      manifoldAndClosed = manifoldAndClosed && f[1] >= 0;
  }
};

double length(const IndexedMesh& m, int a, int b)
{
  const Vec3 d = m.positions[a] - m.positions[b];
  return norm(d);
}

// The shortest-path tree from `root` (edge lengths): each vertex's edge to its parent (-1: the
// root, or unreached).
std::vector<int> shortestPathTree(const IndexedMesh& m, const Edges& e, int root)
{
  const std::size_t nv = m.positions.size();
  std::vector<double> distance(nv, std::numeric_limits<double>::infinity());
  std::vector<int> parentEdge(nv, -1);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  distance[root] = 0;
  queue.push({0, root});
  while (!queue.empty())
  {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > distance[v])
      continue;
    for (int edge : e.ofVertex[v])
    {
      const int w = e.ends[edge].first == v ? e.ends[edge].second : e.ends[edge].first;
      const double through = d + length(m, v, w);
      if (through < distance[w])
      {
        distance[w] = through;
        parentEdge[w] = edge;
        queue.push({through, w});
      }
    }
  }
  return parentEdge;
}

// The edges a spanning tree of the faces crosses, never crossing an edge of `inTree`.
std::vector<char> cotree(const IndexedMesh& m, const Edges& e, const std::vector<char>& inTree)
{
  const std::size_t nf = m.triangles.size();
  std::vector<char> reached(nf, 0), inCotree(e.ends.size(), 0);
  std::vector<int> stack = {0};
  reached[0] = 1;
  while (!stack.empty())
  {
    const int f = stack.back();
    stack.pop_back();
    for (int edge : e.ofFace[f])
    {
      const int g = e.faces[edge][0] == f ? e.faces[edge][1] : e.faces[edge][0];
      if (inTree[edge] || g < 0 || reached[g])
        continue;
      reached[g] = 1;
      inCotree[edge] = 1;
      stack.push_back(g);
    }
  }
  return inCotree;
}

// The loop a leftover edge closes: up the tree from one end to where the two paths meet, then
// down to the other end.
std::vector<int> loopOf(const Edges& e, const std::vector<int>& parentEdge, int edge)
{
  const auto pathUp = [&](int v)
  {
    std::vector<int> path = {v};
    while (parentEdge[v] >= 0)
    {
      const auto [p, q] = e.ends[parentEdge[v]];
      v = p == v ? q : p;
      path.push_back(v);
    }
    return path;
  };
  std::vector<int> up = pathUp(e.ends[edge].first), down = pathUp(e.ends[edge].second);
  while (up.size() > 1 && down.size() > 1 && up[up.size() - 2] == down[down.size() - 2])
    up.pop_back(), down.pop_back();
  std::vector<int> loop(up.begin(), up.end());
  loop.insert(loop.end(), down.rbegin() + 1, down.rend());
  return loop;
}

// The shortest non-separating loop through the tree of `root` (vertices in order), and its
// length: tree-cotree, each edge in neither tree closing one.
std::pair<double, std::vector<int>> loopFrom(const IndexedMesh& m, const Edges& e, int root)
{
  const std::vector<int> parentEdge = shortestPathTree(m, e, root);
  std::vector<char> inTree(e.ends.size(), 0);
  for (int edge : parentEdge)
    if (edge >= 0)
      inTree[edge] = 1;
  const std::vector<char> inCotree = cotree(m, e, inTree);
  double best = std::numeric_limits<double>::infinity();
  std::vector<int> shortest;
  for (std::size_t edge = 0; edge < e.ends.size(); ++edge)
  {
    if (inTree[edge] || inCotree[edge])
      continue;
    std::vector<int> loop = loopOf(e, parentEdge, static_cast<int>(edge));
    double l = 0;
    for (std::size_t i = 0; i < loop.size(); ++i)
      l += length(m, loop[i], loop[(i + 1) % loop.size()]);
    if (l < best)
      best = l, shortest = std::move(loop);
  }
  return {best, shortest};
}

// Splits the mesh along the closed vertex loop and caps both sides with fans.
void cutAlong(IndexedMesh& m, const std::vector<int>& loop)
{
  std::unordered_map<std::uint64_t, int> faceOf; // directed edge -> face
  for (std::size_t f = 0; f < m.triangles.size(); ++f)
    for (int k = 0; k < 3; ++k)
      faceOf[key(m.triangles[f][k], m.triangles[f][(k + 1) % 3])] = static_cast<int>(f);
  const std::size_t n = loop.size();
  std::vector<int> copy(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    copy[i] = static_cast<int>(m.positions.size());
    m.positions.push_back(m.positions[loop[i]]);
  }
  // Around each loop vertex, the faces on the left of the loop (from the edge to the next loop
  // vertex, turning to the edge from the previous one) take its copy.
  for (std::size_t i = 0; i < n; ++i)
  {
    const int c = loop[i], next = loop[(i + 1) % n], previous = loop[(i + n - 1) % n];
    auto it = faceOf.find(key(c, next));
    for (std::size_t guard = 0; it != faceOf.end() && guard < 1000; ++guard)
    {
      auto& t = m.triangles[it->second];
      const int at = t[0] == c ? 0 : (t[1] == c ? 1 : 2);
      // The face's next corner, as it was before the cut (an earlier loop vertex may have
      // taken its copy here already).
      const int corner = t[(at + 2) % 3];
      const int last =
          corner >= copy[0] ? loop[static_cast<std::size_t>(corner - copy[0])] : corner;
      t[at] = copy[i];
      if (last == previous)
        break;
      it = faceOf.find(key(c, last));
    }
  }
  // The two rims: the copies' (left faces hold copy_i -> copy_i+1) and the originals'.
  Vec3 centre{0, 0, 0};
  for (int v : loop)
    centre = centre + m.positions[v];
  centre = (1.0 / static_cast<double>(n)) * centre;
  const int left = static_cast<int>(m.positions.size()), right = left + 1;
  m.positions.push_back(centre);
  m.positions.push_back(centre);
  for (std::size_t i = 0; i < n; ++i)
  {
    const std::size_t j = (i + 1) % n;
    m.triangles.push_back({left, copy[j], copy[i]});
    m.triangles.push_back({right, loop[i], loop[j]});
  }
}

} // namespace

int genusOf(const IndexedMesh& mesh)
{
  const Edges e(mesh);
  if (!e.manifoldAndClosed)
    return -1;
  std::vector<char> used(mesh.positions.size(), 0);
  for (const auto& t : mesh.triangles)
    for (int v : t)
      used[v] = 1;
  const long vertices = std::count(used.begin(), used.end(), 1);
  const long chi =
      vertices - static_cast<long>(e.ends.size()) + static_cast<long>(mesh.triangles.size());
  return static_cast<int>((2 - chi) / 2);
}

std::size_t removeHandles(IndexedMesh& mesh, double longestLoop, std::size_t maximumCuts)
{
  std::size_t cuts = 0;
  for (int genus = genusOf(mesh); genus > 0 && cuts < maximumCuts; --genus, ++cuts)
  {
    const Edges e(mesh);
    if (!e.manifoldAndClosed)
      break;
    std::vector<int> best;
    double shortest = std::numeric_limits<double>::infinity();
    const std::size_t nv = mesh.positions.size();
    const std::size_t stride = std::max<std::size_t>(1, nv / MostRoots);
    for (std::size_t root = 0; root < nv; root += stride)
    {
      if (e.ofVertex[root].empty())
        continue;
      auto [l, loop] = loopFrom(mesh, e, static_cast<int>(root));
      if (l < shortest && loop.size() >= 3)
        shortest = l, best = std::move(loop);
    }
    if (best.empty() || shortest > longestLoop)
      break;
    // A cut that leaves anything but a closed surface of one genus less is undone (a loop
    // that met itself around a vertex); the mesh keeps its handles.
    IndexedMesh cut = mesh;
    cutAlong(cut, best);
    if (genusOf(cut) != genus - 1)
      break;
    mesh = std::move(cut);
  }
  return cuts;
}

} // namespace dp::support
