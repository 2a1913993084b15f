// SPDX-License-Identifier: BSD-3-Clause
#include "dp/geometry/NormalEstimation.h"

#include "dp/geometry/NeighbourLists.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <utility>

namespace dp
{
namespace
{
// 1 - |cos| of the angle beyond which orientation carried from one point to the next starts a
// new part (60 degrees).
constexpr float WeakOrientation = 0.5f;

// Local PCA: each normal is the eigenvector of the smallest eigenvalue of the covariance of the
// point's neighbours (unoriented). Returns the neighbour lists it used.
NeighbourLists pcaNormals(const double* points, std::size_t count, std::size_t k,
                          std::vector<float>& normals)
{
  NeighbourLists graph = nearestNeighbourLists(points, count, k);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 256),
                    [&](const tbb::blocked_range<std::size_t>& range)
                    {
                      for (std::size_t i = range.begin(); i != range.end(); ++i)
                      {
                        const std::uint32_t* ids = &graph.ids[i * graph.k];
                        const std::size_t degree = graph.degree[i];
                        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
                        for (std::size_t j = 0; j < degree; ++j)
                          mean += Eigen::Vector3d(points + 3 * ids[j]);
                        mean /= static_cast<double>(degree);
                        Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
                        for (std::size_t j = 0; j < degree; ++j)
                        {
                          const Eigen::Vector3d d = Eigen::Vector3d(points + 3 * ids[j]) - mean;
                          covariance += d * d.transpose();
                        }
                        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
                        solver.computeDirect(covariance);
                        const Eigen::Vector3d n = solver.eigenvectors().col(0);
                        for (int c = 0; c < 3; ++c)
                          normals[3 * i + c] = static_cast<float>(n[c]);
                      }
                    });
  return graph;
}

// Orientation: Prim's spanning tree on the neighbour graph with weight 1 - |n_i . n_j| plus
// |n_i . d_ij| / 2 (d_ij the unit step from point i to j; halved, as thin parts such as legs
// step off their tangent planes too: horse-gallop), so orientation crosses the flattest, most
// reliable edges first, and last a step along the normal: from one side of a thin gap to the
// other (a hand on the body, touching thighs), where the normals are opposite but |n_i . n_j|
// alone would call the edge the surest of all.
//
// The queue holds one entry per point not yet reached: its cheapest edge from the tree so far,
// lowered as the tree grows (an indexed heap). Points leave it in the order of their edges'
// (weight, from, to), the order a queue of every edge would give, in a heap of at most one entry
// per point instead of one per edge.
class SpanningTreeOrientation
{
public:
  SpanningTreeOrientation(const double* points, const NeighbourLists& graph,
                          std::vector<float>& normals, std::vector<std::uint32_t>* parts,
                          OrientationTree* tree)
      : Points(points), Graph(graph), Normals(normals), Parts(parts), Tree(tree),
        Done(graph.degree.size(), 0), Best(graph.degree.size()),
        Slot(graph.degree.size(), NotQueued)
  {
    if (Tree)
    {
      Tree->parent.assign(graph.degree.size(), 0);
      Tree->order.clear();
      Tree->order.reserve(graph.degree.size());
    }
  }

  /** Orients the part of `seed` (if not done yet) from it, its normal made to point to +x. */
  void orientPartOf(std::uint32_t seed)
  {
    if (Done[seed])
      return;
    if (Parts)
      (*Parts)[seed] = Part;
    if (Normals[3 * seed] < 0)
      flip(seed);
    Done[seed] = 1;
    record(seed, seed);
    offerNeighbours(seed);
    while (!Heap.empty())
    {
      const std::uint32_t to = popCheapest();
      const std::uint32_t from = Best[to].from;
      if (dot(from, to) < 0)
        flip(to);
      Done[to] = 1;
      record(to, from);
      // Orientation carried across a sharp turn of the normals is the least sure: a new part.
      if (Parts)
        (*Parts)[to] = Best[to].weight > WeakOrientation ? ++Part : (*Parts)[from];
      offerNeighbours(to);
    }
    ++Part;
  }

private:
  static constexpr std::uint32_t NotQueued = ~0u;
  struct Edge
  {
    float weight;
    std::uint32_t from;
  };

  float dot(std::size_t a, std::size_t b) const
  {
    return Normals[3 * a] * Normals[3 * b] + Normals[3 * a + 1] * Normals[3 * b + 1] +
           Normals[3 * a + 2] * Normals[3 * b + 2];
  }
  float weight(std::size_t a, std::size_t b) const
  {
    double d[3], length2 = 0, along = 0;
    for (int c = 0; c < 3; ++c)
    {
      d[c] = Points[3 * b + c] - Points[3 * a + c];
      length2 += d[c] * d[c];
      along += d[c] * Normals[3 * a + c];
    }
    const double across = length2 > 0 ? std::abs(along) / std::sqrt(length2) : 0.0;
    return static_cast<float>(1.0 - std::abs(dot(a, b)) + 0.5 * across);
  }
  void record(std::uint32_t point, std::uint32_t from)
  {
    if (!Tree)
      return;
    Tree->parent[point] = from;
    Tree->order.push_back(point);
  }
  void flip(std::size_t i)
  {
    for (int c = 0; c < 3; ++c)
      Normals[3 * i + c] = -Normals[3 * i + c];
  }
  // Whether point a's edge leaves the queue before point b's: by (weight, from, to).
  bool before(std::uint32_t a, std::uint32_t b) const
  {
    const Edge &ea = Best[a], &eb = Best[b];
    return ea.weight < eb.weight ||
           (ea.weight == eb.weight && (ea.from < eb.from || (ea.from == eb.from && a < b)));
  }
  void offerNeighbours(std::uint32_t from)
  {
    for (std::size_t j = 0; j < Graph.degree[from]; ++j)
    {
      const std::uint32_t to = Graph.ids[from * Graph.k + j];
      if (Done[to])
        continue;
      const Edge offer{weight(from, to), from};
      if (Slot[to] == NotQueued)
      {
        Best[to] = offer;
        Slot[to] = static_cast<std::uint32_t>(Heap.size());
        Heap.push_back(to);
        siftUp(Slot[to]);
      }
      else if (offer.weight < Best[to].weight ||
               (offer.weight == Best[to].weight && offer.from < Best[to].from))
      {
        Best[to] = offer;
        siftUp(Slot[to]);
      }
    }
  }
  std::uint32_t popCheapest()
  {
    const std::uint32_t top = Heap.front();
    Slot[top] = NotQueued;
    const std::uint32_t last = Heap.back();
    Heap.pop_back();
    if (!Heap.empty())
    {
      Heap[0] = last;
      Slot[last] = 0;
      siftDown(0);
    }
    return top;
  }
  void place(std::size_t slot, std::uint32_t point)
  {
    Heap[slot] = point;
    Slot[point] = static_cast<std::uint32_t>(slot);
  }
  void siftUp(std::size_t slot)
  {
    const std::uint32_t point = Heap[slot];
    while (slot > 0)
    {
      const std::size_t parent = (slot - 1) / 2;
      if (!before(point, Heap[parent]))
        break;
      place(slot, Heap[parent]);
      slot = parent;
    }
    place(slot, point);
  }
  void siftDown(std::size_t slot)
  {
    const std::uint32_t point = Heap[slot];
    for (;;)
    {
      std::size_t child = 2 * slot + 1;
      if (child >= Heap.size())
        break;
      if (child + 1 < Heap.size() && before(Heap[child + 1], Heap[child]))
        ++child;
      if (!before(Heap[child], point))
        break;
      place(slot, Heap[child]);
      slot = child;
    }
    place(slot, point);
  }

  const double* Points;
  const NeighbourLists& Graph;
  std::vector<float>& Normals;
  std::vector<std::uint32_t>* Parts;
  OrientationTree* Tree;
  std::vector<char> Done;
  std::vector<Edge> Best;          // per queued point: its cheapest edge from the tree
  std::vector<std::uint32_t> Slot; // per point: its place in Heap, or NotQueued
  std::vector<std::uint32_t> Heap; // queued points, a binary heap ordered by before()
  std::uint32_t Part = 0;
};
} // namespace

std::vector<float> unorientedNormals(const double* points, std::size_t count,
                                     std::size_t neighbours)
{
  std::vector<float> normals(3 * count, 0.0f);
  if (count > 0)
    pcaNormals(points, count, std::max<std::size_t>(3, std::min(neighbours, count)), normals);
  return normals;
}

std::vector<float> estimateNormals(const double* points, std::size_t count, std::size_t neighbours,
                                   std::vector<std::uint32_t>* parts, OrientationTree* tree)
{
  std::vector<float> normals(3 * count, 0.0f);
  if (parts)
    parts->assign(count, 0);
  if (tree)
    *tree = {};
  if (count == 0)
    return normals;
  const std::size_t k = std::max<std::size_t>(3, std::min(neighbours, count));
  const NeighbourLists graph = pcaNormals(points, count, k, normals);
  // Seeds in order of decreasing x, so each connected part starts at its largest-x point.
  std::vector<std::uint32_t> order(count);
  for (std::size_t i = 0; i < count; ++i)
    order[i] = static_cast<std::uint32_t>(i);
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return points[3 * a] > points[3 * b]; });
  SpanningTreeOrientation orientation(points, graph, normals, parts, tree);
  for (std::uint32_t seed : order)
    orientation.orientPartOf(seed);
  return normals;
}

namespace
{
// Whether the edge from point p's parent to p lies inside a part (the parts' own boundaries are
// the orientation's weak edges, each part voted on as a whole by the caller).
bool innerEdge(const OrientationTree& tree, const std::vector<std::uint32_t>& parts,
               std::uint32_t p)
{
  const std::uint32_t q = tree.parent[p];
  return q != p && parts[q] == parts[p];
}

// The votes for and against in each point's branch (the point and what descends from it inside
// its part), and each part's totals.
struct BranchVotes
{
  std::vector<std::uint32_t> agree, disagree, asked;
  std::vector<std::uint32_t> partAgree, partDisagree, partAsked;

  BranchVotes(const OrientationTree& tree, const std::vector<std::uint32_t>& parts,
              const std::vector<std::int8_t>& votes)
      : agree(votes.size()), disagree(votes.size()), asked(votes.size())
  {
    for (std::size_t p = 0; p < votes.size(); ++p)
    {
      agree[p] = votes[p] == 1;
      disagree[p] = votes[p] == -1;
      asked[p] = votes[p] != NotAsked;
    }
    for (auto it = tree.order.rbegin(); it != tree.order.rend(); ++it)
      if (innerEdge(tree, parts, *it))
      {
        agree[tree.parent[*it]] += agree[*it];
        disagree[tree.parent[*it]] += disagree[*it];
        asked[tree.parent[*it]] += asked[*it];
      }
    const std::uint32_t partCount = *std::max_element(parts.begin(), parts.end()) + 1;
    partAgree.assign(partCount, 0);
    partDisagree.assign(partCount, 0);
    partAsked.assign(partCount, 0);
    for (std::uint32_t p : tree.order)
      if (!innerEdge(tree, parts, p)) // the top of its part
      {
        partAgree[parts[p]] += agree[p];
        partDisagree[parts[p]] += disagree[p];
        partAsked[parts[p]] += asked[p];
      }
  }
};

// The cut that turns the most disagreement around: below `branch` (inside) or the rest of its
// part (outside).
struct Cut
{
  std::uint32_t branch = 0;
  bool inside = true;
  std::uint32_t gain = 0;
};

Cut bestCut(const OrientationTree& tree, const std::vector<std::uint32_t>& parts,
            const BranchVotes& v, const MendOptions& options)
{
  Cut best;
  auto oneWay = [&](double with, double total) { return with >= options.share * total; };
  for (std::uint32_t p : tree.order)
  {
    if (!innerEdge(tree, parts, p))
      continue;
    const double inA = v.agree[p], inD = v.disagree[p];
    const double outA = v.partAgree[parts[p]] - inA, outD = v.partDisagree[parts[p]] - inD;
    const double inAsked = v.asked[p], outAsked = v.partAsked[parts[p]] - inAsked;
    // Each side must gather enough votes, from most of the points asked: where the reference
    // meets only a few of a side's points it is elsewhere (a hand that moved through its own
    // thickness meets the data's other side).
    if (inA + inD < options.minimumVotes || outA + outD < options.minimumVotes ||
        inA + inD < options.coverage * inAsked || outA + outD < options.coverage * outAsked)
      continue;
    if (oneWay(inD, inA + inD) && oneWay(outA, outA + outD) && inD - inA > best.gain)
      best = {p, true, static_cast<std::uint32_t>(inD - inA)};
    else if (oneWay(inA, inA + inD) && oneWay(outD, outA + outD) && outD - outA > best.gain)
      best = {p, false, static_cast<std::uint32_t>(outD - outA)};
  }
  return best;
}
} // namespace

std::size_t mendOrientation(const OrientationTree& tree, const std::vector<std::uint32_t>& parts,
                            std::vector<std::int8_t>& votes, float* normals,
                            const MendOptions& options)
{
  if (tree.order.empty() || parts.size() != votes.size() || tree.parent.size() != votes.size())
    return 0;
  std::size_t turned = 0;
  std::vector<char> below(votes.size());
  for (int cut = 0; cut < options.maximumCuts; ++cut)
  {
    const Cut c = bestCut(tree, parts, BranchVotes(tree, parts, votes), options);
    if (c.gain == 0)
      break;
    const std::uint32_t part = parts[c.branch];
    for (std::uint32_t p : tree.order) // parents first: a point is below once its parent is
      below[p] = p == c.branch || (innerEdge(tree, parts, p) && below[tree.parent[p]]);
    for (std::size_t p = 0; p < votes.size(); ++p)
      if (parts[p] == part && (below[p] != 0) == c.inside)
      {
        for (int k = 0; k < 3; ++k)
          normals[3 * p + k] = -normals[3 * p + k];
        if (votes[p] != NotAsked)
          votes[p] = static_cast<std::int8_t>(-votes[p]);
        ++turned;
      }
  }
  return turned;
}

} // namespace dp
