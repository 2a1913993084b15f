// SPDX-License-Identifier: BSD-3-Clause
// Compiled with -ffp-contract=off (Filters/Engine/CMakeLists.txt): the encoder's and the
// decoder's predictions must agree to the last bit on every IEEE machine.
#include "dp/compress/MeshPrediction.h"

#include <algorithm>
#include <cmath>
#include <deque>

namespace dp::compress
{
namespace
{

// The ridges of the regression, in squared steps: light where the neighbourhood's structure is
// clean (a rigid part, a smooth field), heavy where its finer columns are noise.
constexpr double LightRidge = 30, HeavyRidge = 3000;

// Solves (G + ridge I) a = b + ridge p in place (Cholesky, n <= 16): false when not positive.
bool solveRidge(const double* g, const double* b, double ridge, double prior, std::size_t n,
                double* a)
{
  double l[RowPredictor::MaximumNeighbours * RowPredictor::MaximumNeighbours];
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j <= i; ++j)
    {
      double s = g[i * n + j] + (i == j ? ridge : 0.0);
      for (std::size_t k = 0; k < j; ++k)
        s -= l[i * n + k] * l[j * n + k];
      if (i == j)
      {
        if (!(s > 0))
          return false;
        l[i * n + i] = std::sqrt(s);
      }
      else
        l[i * n + j] = s / l[j * n + j];
    }
  for (std::size_t i = 0; i < n; ++i)
  {
    double s = b[i] + ridge * prior;
    for (std::size_t k = 0; k < i; ++k)
      s -= l[i * n + k] * a[k];
    a[i] = s / l[i * n + i];
  }
  for (std::size_t i = n; i-- > 0;)
  {
    double s = a[i];
    for (std::size_t k = i + 1; k < n; ++k)
      s -= l[k * n + i] * a[k];
    a[i] = s / l[i * n + i];
  }
  return true;
}

} // namespace

namespace
{

using Graph = std::vector<std::vector<std::size_t>>;
// A level of the decimation: its vertices, each with its ring at removal.
using RemovedLevel = std::vector<std::pair<std::size_t, std::vector<std::size_t>>>;

// The edge graph, each vertex's neighbours in index order.
Graph edgeGraph(const std::vector<std::int64_t>& triangles, std::size_t vertices)
{
  Graph g(vertices);
  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3)
    for (int e = 0; e < 3; ++e)
    {
      const auto a = static_cast<std::size_t>(triangles[t + e]);
      const auto b = static_cast<std::size_t>(triangles[t + (e + 1) % 3]);
      if (a != b && a < vertices && b < vertices)
      {
        g[a].push_back(b);
        g[b].push_back(a);
      }
    }
  for (auto& n : g)
  {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  return g;
}

// One level of the decimation: a maximal independent set of the alive vertices (fewest
// neighbours first, then by index; none with more than RowPredictor::MaximumNeighbours), each
// taken out of the graph with its ring joined up, so the next level's graph still links what it
// linked. Returns the set, each vertex with its ring at removal.
RemovedLevel removeIndependentSet(Graph& g, std::vector<char>& alive)
{
  std::vector<std::size_t> candidates;
  for (std::size_t v = 0; v < g.size(); ++v)
    if (alive[v] && !g[v].empty() && g[v].size() <= RowPredictor::MaximumNeighbours)
      candidates.push_back(v);
  std::stable_sort(candidates.begin(), candidates.end(),
                   [&](std::size_t a, std::size_t b) { return g[a].size() < g[b].size(); });
  std::vector<char> blocked(g.size(), 0);
  RemovedLevel removed;
  for (std::size_t v : candidates)
    if (!blocked[v])
    {
      blocked[v] = 1;
      for (std::size_t n : g[v])
        blocked[n] = 1;
      removed.emplace_back(v, g[v]);
    }
  for (const auto& [v, ring] : removed)
  {
    for (std::size_t a : ring)
    {
      std::vector<std::size_t>& n = g[a];
      n.erase(std::remove(n.begin(), n.end(), v), n.end());
      for (std::size_t b : ring)
        if (b != a)
          n.push_back(b);
      std::sort(n.begin(), n.end());
      n.erase(std::unique(n.begin(), n.end()), n.end());
    }
    g[v].clear();
    alive[v] = 0;
  }
  return removed;
}

// The decimation's levels, finest first: independent sets taken out of `g` until there are
// MaximumLevels, no more than MinimumBase vertices are left, or none can be taken.
std::vector<RemovedLevel> decimate(Graph& g, std::vector<char>& alive, std::size_t vertices)
{
  std::vector<RemovedLevel> levels;
  std::size_t left = vertices;
  while (levels.size() < VertexTraversal::MaximumLevels && left > VertexTraversal::MinimumBase)
  {
    levels.push_back(removeIndependentSet(g, alive));
    if (levels.back().empty())
    {
      levels.pop_back();
      break;
    }
    left -= levels.back().size();
  }
  return levels;
}

// The base into `t`: what is left alive, breadth first over the last level's graph, each vertex
// predicted from its neighbours met before it.
void traverseBase(const Graph& g, const std::vector<char>& alive, VertexTraversal& t)
{
  const std::size_t vertices = g.size();
  std::vector<std::size_t> rank(vertices, vertices); // vertices: not met yet
  std::vector<char> queued(vertices, 0);
  std::deque<std::size_t> queue;
  t.start.assign(1, 0);
  for (std::size_t seed = 0; seed < vertices; ++seed)
  {
    if (!alive[seed] || queued[seed])
      continue;
    queued[seed] = 1;
    queue.push_back(seed);
    while (!queue.empty())
    {
      const std::size_t v = queue.front();
      queue.pop_front();
      rank[v] = t.order.size();
      t.order.push_back(v);
      for (std::size_t n : g[v])
        if (rank[n] < rank[v])
          t.earlier.push_back(n);
      t.start.push_back(t.earlier.size());
      for (std::size_t n : g[v])
        if (!queued[n])
        {
          queued[n] = 1;
          queue.push_back(n);
        }
    }
  }
}

} // namespace

VertexTraversal::VertexTraversal(const std::vector<std::int64_t>& triangles, std::size_t vertices)
{
  Graph g = edgeGraph(triangles, vertices);
  std::vector<char> alive(vertices, 1);
  const std::vector<RemovedLevel> levels = decimate(g, alive, vertices);
  traverseBase(g, alive, *this);
  base = order.size();
  // Then the levels, coarsest first: each vertex predicted from its whole ring.
  for (auto level = levels.rbegin(); level != levels.rend(); ++level)
    for (const auto& [v, ring] : *level)
    {
      order.push_back(v);
      earlier.insert(earlier.end(), ring.begin(), ring.end());
      start.push_back(earlier.size());
    }
}

RowPredictor::RowPredictor(const std::int64_t* values, std::size_t columns,
                           const std::size_t* neighbours, std::size_t count, std::size_t vertex)
    : Values(values), Columns(columns), Vertex(vertex), Neighbours(neighbours), All(count),
      Count(std::min(count, MaximumNeighbours))
{
}

std::int64_t RowPredictor::mean(std::size_t c) const
{
  if (All == 0)
    return 0;
  // Summed as doubles: exact for what a valid file holds (|v| <= 2^60, at most a few hundred
  // neighbours lose only the last bits, identically on both sides).
  double sum = 0;
  for (std::size_t n = 0; n < All; ++n)
    sum += static_cast<double>(Values[Neighbours[n] * Columns + c]);
  const double m = std::nearbyint(sum / static_cast<double>(All));
  return std::abs(m) <= static_cast<double>(ValueLimit) ? static_cast<std::int64_t>(m) : 0;
}

std::int64_t RowPredictor::regression(std::size_t c, double ridge)
{
  if (Count == 0)
    return 0;
  double alpha[MaximumNeighbours];
  if (!solveRidge(G, B, ridge, 1.0 / static_cast<double>(Count), Count, alpha))
    return mean(c);
  double p = 0;
  for (std::size_t n = 0; n < Count; ++n)
    p += alpha[n] * static_cast<double>(Values[Neighbours[n] * Columns + c]);
  p = std::nearbyint(p);
  if (!std::isfinite(p) || std::abs(p) > static_cast<double>(ValueLimit))
    return mean(c);
  return static_cast<std::int64_t>(p);
}

std::int64_t RowPredictor::predict(std::size_t c, VertexPredictor p)
{
  switch (p)
  {
  case VertexPredictor::None:
    return 0;
  case VertexPredictor::Mean:
    return mean(c);
  case VertexPredictor::LightRegression:
    return regression(c, LightRidge);
  case VertexPredictor::HeavyRegression:
    return regression(c, HeavyRidge);
  }
  return 0;
}

void RowPredictor::learn(std::size_t c)
{
  double x[MaximumNeighbours];
  for (std::size_t n = 0; n < Count; ++n)
    x[n] = static_cast<double>(Values[Neighbours[n] * Columns + c]);
  const double v = static_cast<double>(Values[Vertex * Columns + c]);
  for (std::size_t i = 0; i < Count; ++i)
  {
    for (std::size_t j = 0; j < Count; ++j)
      G[i * Count + j] += x[i] * x[j];
    B[i] += x[i] * v;
  }
}

} // namespace dp::compress
