// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/DeformationGraph.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <stdexcept>
#include <utility>

namespace dp
{
namespace
{
// A part of the graph (nodes linked by edges) with fewer nodes than this share of the largest
// part's is linked to the rest (DeformationGraph::linkSmallParts).
constexpr double SmallPartShare = 0.25;

using Queue = std::priority_queue<std::pair<double, std::int64_t>,
                                  std::vector<std::pair<double, std::int64_t>>,
                                  std::greater<std::pair<double, std::int64_t>>>;

double edgeLength(const double* x, std::int64_t a, std::int64_t b)
{
  double d2 = 0;
  for (int k = 0; k < 3; ++k)
    d2 += (x[3 * a + k] - x[3 * b + k]) * (x[3 * a + k] - x[3 * b + k]);
  return std::sqrt(d2);
}

// The nodes a vertex reaches, as (geodesic distance, node index).
using NodeDistances = std::vector<std::pair<double, std::int32_t>>;

// For every vertex, the nodes within geodesic distance `radius` of it: one Dijkstra from each
// node, stopped at the radius (the distances it touched reset after each).
std::vector<NodeDistances> nodesWithinRadius(const TriangleMesh& mesh, const double* rest,
                                             const std::vector<std::int64_t>& nodeVertex,
                                             double radius)
{
  const std::size_t nv = mesh.numberOfVertices();
  std::vector<NodeDistances> found(nv);
  std::vector<double> distance(nv, std::numeric_limits<double>::infinity());
  std::vector<std::int64_t> touched;
  for (std::size_t j = 0; j < nodeVertex.size(); ++j)
  {
    Queue queue;
    distance[nodeVertex[j]] = 0;
    touched.push_back(nodeVertex[j]);
    queue.push({0.0, nodeVertex[j]});
    while (!queue.empty())
    {
      const auto [d, v] = queue.top();
      queue.pop();
      if (d > distance[v])
        continue;
      found[v].push_back({d, static_cast<std::int32_t>(j)});
      for (std::int64_t u : mesh.neighbours(static_cast<std::size_t>(v)))
      {
        const double du = d + edgeLength(rest, v, u);
        if (du < distance[u] && du <= radius)
        {
          if (distance[u] == std::numeric_limits<double>::infinity())
            touched.push_back(u);
          distance[u] = du;
          queue.push({du, u});
        }
      }
    }
    for (std::int64_t v : touched)
      distance[v] = std::numeric_limits<double>::infinity();
    touched.clear();
  }
  return found;
}

// A vertex's influences, appended to `out`: its `influences` nearest nodes (`nodes`, sorted
// here) weighted (1 - d / d_max)^2 and normalised; the pairs of nodes it blends appended to
// `pairs` (they become the graph's edges).
void appendVertexInfluences(NodeDistances& nodes, std::size_t influences, double radius,
                            std::vector<DeformationGraph::Influence>& out,
                            std::vector<std::array<std::int64_t, 2>>& pairs)
{
  std::sort(nodes.begin(), nodes.end());
  const std::size_t kept = std::min(influences, nodes.size());
  // d_max: the next nearest node's distance, or the search radius when there is none.
  const double dMax = nodes.size() > kept ? nodes[kept].first : radius;
  double total = 0;
  const std::size_t first = out.size();
  for (std::size_t i = 0; i < kept; ++i)
  {
    const double u = 1 - nodes[i].first / std::max(dMax, 1e-300);
    const double w = std::max(u, 0.0) * std::max(u, 0.0);
    if (w <= 0)
      continue;
    out.push_back({nodes[i].second, w});
    total += w;
  }
  if (total <= 0 && !nodes.empty()) // all at d_max: the nearest alone
  {
    out.push_back({nodes[0].second, 1.0});
    total = 1;
  }
  for (std::size_t i = first; i < out.size(); ++i)
  {
    out[i].weight /= total;
    for (std::size_t k = first; k < i; ++k)
      pairs.push_back({std::min(out[i].node, out[k].node), std::max(out[i].node, out[k].node)});
  }
}
// Each node's part (the lowest node index of the nodes it is linked to by `edges`).
std::vector<std::size_t> connectedParts(std::size_t nodes,
                                        const std::vector<std::array<std::int64_t, 2>>& edges)
{
  std::vector<std::size_t> parent(nodes);
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  const auto root = [&parent](std::size_t j)
  {
    while (parent[j] != j)
      j = parent[j] = parent[parent[j]];
    return j;
  };
  for (const auto& e : edges)
  {
    const std::size_t a = root(static_cast<std::size_t>(e[0]));
    const std::size_t b = root(static_cast<std::size_t>(e[1]));
    parent[std::max(a, b)] = std::min(a, b);
  }
  for (std::size_t j = 0; j < nodes; ++j)
    parent[j] = root(j);
  return parent;
}

// The nearest pair (a joined node, a node not joined) at rest; ties to the lower indices.
std::array<std::size_t, 2> nearestJoinedPair(const DeformationGraph& graph,
                                             const std::vector<char>& joined)
{
  double best = std::numeric_limits<double>::infinity();
  std::array<std::size_t, 2> pair{0, 0};
  for (std::size_t a = 0; a < joined.size(); ++a)
    for (std::size_t b = 0; b < joined.size() && joined[a]; ++b)
    {
      if (joined[b])
        continue;
      const double* p = graph.nodePosition(a);
      const double* q = graph.nodePosition(b);
      const double d2 = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                        (p[2] - q[2]) * (p[2] - q[2]);
      if (d2 < best)
      {
        best = d2;
        pair = {a, b};
      }
    }
  return pair;
}

} // namespace

DeformationGraph::DeformationGraph(const TriangleMesh& mesh, const double* rest,
                                   std::size_t nodeCount, std::size_t influences)
    : Mesh(mesh), Rest(rest)
{
  if (nodeCount < 1 || influences < 1)
    throw std::invalid_argument("deformation graph: at least one node and one influence needed");
  sampleNodes(std::min(nodeCount, mesh.numberOfVertices()));
  blend(influences);
  linkSmallParts();
}

void DeformationGraph::sampleNodes(std::size_t nodeCount)
{
  // Farthest-point sampling in geodesic distance: each new node is the vertex farthest from the
  // nodes so far; one Dijkstra from it lowers the distances it can (and stops where it cannot).
  const std::size_t nv = Mesh.numberOfVertices();
  std::vector<double> distance(nv, std::numeric_limits<double>::infinity());
  std::int64_t next = 0;
  while (NodeVertex.size() < nodeCount)
  {
    NodeVertex.push_back(next);
    Queue queue;
    distance[next] = 0;
    queue.push({0.0, next});
    while (!queue.empty())
    {
      const auto [d, v] = queue.top();
      queue.pop();
      if (d > distance[v])
        continue;
      for (std::int64_t u : Mesh.neighbours(static_cast<std::size_t>(v)))
      {
        const double du = d + edgeLength(Rest, v, u);
        if (du < distance[u])
        {
          distance[u] = du;
          queue.push({du, u});
        }
      }
    }
    // The farthest vertex (unreached parts first); ties to the lower index.
    next = static_cast<std::int64_t>(std::max_element(distance.begin(), distance.end()) -
                                     distance.begin());
    if (distance[next] == 0)
      break; // every vertex is a node
  }
  Spacing = *std::max_element(distance.begin(), distance.end());
}

void DeformationGraph::blend(std::size_t influences)
{
  // Every node's geodesic neighbourhood up to a radius that reaches past `influences` nodes for
  // every vertex (each vertex has a node within Spacing, so 2.5 Spacing holds several).
  const std::size_t nv = Mesh.numberOfVertices();
  const double radius = 2.5 * std::max(Spacing, 1e-300);
  std::vector<NodeDistances> found = nodesWithinRadius(Mesh, Rest, NodeVertex, radius);
  Offsets.assign(nv + 1, 0);
  std::vector<std::array<std::int64_t, 2>> pairs;
  for (std::size_t v = 0; v < nv; ++v)
  {
    appendVertexInfluences(found[v], influences, radius, Influences, pairs);
    Offsets[v + 1] = Influences.size();
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  Edges = std::move(pairs);
}

void DeformationGraph::linkSmallParts()
{
  const std::size_t n = NodeVertex.size();
  const std::vector<std::size_t> part = connectedParts(n, Edges);
  std::vector<std::size_t> size(n, 0);
  for (std::size_t j = 0; j < n; ++j)
    ++size[part[j]];
  const std::size_t largest = *std::max_element(size.begin(), size.end());
  // Prim's growth from the large parts: each time the nearest pair of a joined node and a node
  // of a part not joined yet becomes an edge, and that whole part joins.
  std::vector<char> joined(n);
  for (std::size_t j = 0; j < n; ++j)
    joined[j] = SmallPartShare * static_cast<double>(largest) <= static_cast<double>(size[part[j]]);
  while (std::count(joined.begin(), joined.end(), 0) > 0)
  {
    const std::array<std::size_t, 2> link = nearestJoinedPair(*this, joined);
    Edges.push_back({static_cast<std::int64_t>(std::min(link[0], link[1])),
                     static_cast<std::int64_t>(std::max(link[0], link[1]))});
    for (std::size_t j = 0; j < n; ++j)
      joined[j] = joined[j] || part[j] == part[link[1]];
  }
  std::sort(Edges.begin(), Edges.end());
}

DeformationGraph::State DeformationGraph::identity() const
{
  State s;
  s.rotation.assign(numberOfNodes(), Eigen::Matrix3d::Identity());
  s.translation.assign(numberOfNodes(), Eigen::Vector3d::Zero());
  return s;
}

void DeformationGraph::deform(const State& state, double* x) const
{
  const std::size_t nv = Mesh.numberOfVertices();
  for (std::size_t v = 0; v < nv; ++v)
  {
    const Eigen::Vector3d rest(&Rest[3 * v]);
    Eigen::Vector3d y = Eigen::Vector3d::Zero();
    for (const Influence* i = influencesBegin(v); i != influencesEnd(v); ++i)
    {
      const Eigen::Vector3d g(nodePosition(static_cast<std::size_t>(i->node)));
      y += i->weight * (state.rotation[i->node] * (rest - g) + g + state.translation[i->node]);
    }
    std::copy(y.data(), y.data() + 3, &x[3 * v]);
  }
}

DeformationGraph::State DeformationGraph::fit(const double* x) const
{
  // Gather, per node, the vertices it blends with their weights.
  const std::size_t nn = numberOfNodes(), nv = Mesh.numberOfVertices();
  std::vector<double> total(nn, 0.0);
  std::vector<Eigen::Vector3d> restMean(nn, Eigen::Vector3d::Zero()),
      mean(nn, Eigen::Vector3d::Zero());
  for (std::size_t v = 0; v < nv; ++v)
    for (const Influence* i = influencesBegin(v); i != influencesEnd(v); ++i)
    {
      total[i->node] += i->weight;
      restMean[i->node] += i->weight * Eigen::Vector3d(&Rest[3 * v]);
      mean[i->node] += i->weight * Eigen::Vector3d(&x[3 * v]);
    }
  std::vector<Eigen::Matrix3d> covariance(nn, Eigen::Matrix3d::Zero());
  for (std::size_t j = 0; j < nn; ++j)
    if (total[j] > 0)
    {
      restMean[j] /= total[j];
      mean[j] /= total[j];
    }
  for (std::size_t v = 0; v < nv; ++v)
    for (const Influence* i = influencesBegin(v); i != influencesEnd(v); ++i)
      covariance[i->node] += i->weight * (Eigen::Vector3d(&x[3 * v]) - mean[i->node]) *
                             (Eigen::Vector3d(&Rest[3 * v]) - restMean[i->node]).transpose();
  State s = identity();
  for (std::size_t j = 0; j < nn; ++j)
  {
    if (total[j] <= 0)
      continue;
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance[j],
                                                Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
    // A patch too flat or too small to fix a rotation keeps the identity's remainder: the SVD of
    // a rank-deficient covariance still gives a rotation, which the translation then matches.
    s.rotation[j] = svd.matrixU() * D * svd.matrixV().transpose();
    const Eigen::Vector3d g(nodePosition(j));
    s.translation[j] = mean[j] - g - s.rotation[j] * (restMean[j] - g);
  }
  return s;
}

DeformationGraph::State extrapolate(const DeformationGraph::State& before,
                                    const DeformationGraph::State& last,
                                    const DeformationGraph& graph, double share, Extrapolation kind)
{
  // Each node's frame continues its motion: the relative rotation S = R_last R_before^T applied
  // once more (as an angle-axis scaled by `share`), and the position its point g_j moves to moving
  // on by the last displacement, turned by S when Turning. A limb turning about a joint then keeps
  // turning about it (exact for a constant rotation); Straight cuts the arc's chord, off by about
  // r dtheta^2 (2.5 cm for a leg 1 m long at 0.16 rad a frame), but is the safer guess where the
  // nodes' rotations are noise (a shape melting).
  DeformationGraph::State next = last;
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
  {
    const Eigen::AngleAxisd step(last.rotation[j] * before.rotation[j].transpose());
    const Eigen::Matrix3d turn =
        Eigen::AngleAxisd(share * step.angle(), step.axis()).toRotationMatrix();
    next.rotation[j] = turn * last.rotation[j];
    next.translation[j] =
        last.translation[j] +
        share * (kind == Extrapolation::Turning
                     ? Eigen::Vector3d(turn * (last.translation[j] - before.translation[j]))
                     : Eigen::Vector3d(last.translation[j] - before.translation[j]));
  }
  return next;
}

} // namespace dp
