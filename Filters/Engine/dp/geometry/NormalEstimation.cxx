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
                          std::vector<float>& normals, std::vector<std::uint32_t>* parts)
      : Points(points), Graph(graph), Normals(normals), Parts(parts), Done(graph.degree.size(), 0),
        Best(graph.degree.size()), Slot(graph.degree.size(), NotQueued)
  {
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
    offerNeighbours(seed);
    while (!Heap.empty())
    {
      const std::uint32_t to = popCheapest();
      const std::uint32_t from = Best[to].from;
      if (dot(from, to) < 0)
        flip(to);
      Done[to] = 1;
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
  std::vector<char> Done;
  std::vector<Edge> Best;          // per queued point: its cheapest edge from the tree
  std::vector<std::uint32_t> Slot; // per point: its place in Heap, or NotQueued
  std::vector<std::uint32_t> Heap; // queued points, a binary heap ordered by before()
  std::uint32_t Part = 0;
};
} // namespace

std::vector<float> estimateNormals(const double* points, std::size_t count, std::size_t neighbours,
                                   std::vector<std::uint32_t>* parts)
{
  std::vector<float> normals(3 * count, 0.0f);
  if (parts)
    parts->assign(count, 0);
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
  SpanningTreeOrientation orientation(points, graph, normals, parts);
  for (std::uint32_t seed : order)
    orientation.orientPartOf(seed);
  return normals;
}

} // namespace dp
