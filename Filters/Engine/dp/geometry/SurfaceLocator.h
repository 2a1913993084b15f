// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file SurfaceLocator.h
 * @brief Exact closest points on a triangle mesh whose vertices move (fixed connectivity): the
 *        "closest point of the mesh surface" of the points -> mesh data term (CoverageTerm) and
 *        of the frame quality measures.
 *
 * An axis-aligned bounding-box tree over the triangles, built for one set of positions (median
 * splits along the longest axis, four triangles per leaf) and refitted to new positions in
 * linear time (the boxes grow, the tree stays valid). It is searched with its levels taken two
 * at a time (four children a node, their boxes tested in one loop: half the levels to descend;
 * 1.05x on a tracked frame). Queries descend the nearest child first and prune boxes
 * farther than the best hit, and in a leaf the triangles whose bounding sphere is farther (about
 * half the triangle tests of a tracked take: jumping, 10 frames), so they are exact; they are
 * const and thread-safe. A query with a hint (the triangle found last time) starts at the hint's
 * leaf and climbs to the root, searching each sibling subtree: the bound is small from the
 * start, so most subtrees cost one box test. Ties go to the lower triangle index, so a hint
 * never changes the answer.
 *
 * follow() is the cheap, local alternative for a point whose closest triangle was found a step
 * ago: it walks over the surface from that triangle to the nearest of its neighbours (across its
 * edges, and around the corner the closest point may be), until none is nearer: a local minimum
 * of the distance, four triangle tests for most points. It is not exact: another part of the
 * surface may be nearer.
 *
 * Limits: after large deformations a refitted tree prunes less well (rebuild it then: build()
 * costs O(n log n)); degenerate (zero-area) triangles are handled (their closest point is on an
 * edge or a vertex).
 */
#pragma once

#include "dp/geometry/TriangleMesh.h"

#include <cstdint>
#include <limits>
#include <vector>

namespace dp
{

/** Closest point of one triangle to p: barycentric weights (summing to 1) and the point. */
double closestPointOnTriangle(const double p[3], const double a[3], const double b[3],
                              const double c[3], double barycentric[3], double closest[3]);

class SurfaceLocator
{
public:
  struct Hit
  {
    std::int64_t triangle = -1; // -1: nothing within the distance asked
    double barycentric[3] = {0, 0, 0};
    double point[3] = {0, 0, 0};
    double squaredDistance = std::numeric_limits<double>::infinity();
  };

  SurfaceLocator() = default;
  /** The tree over `mesh`'s triangles at `positions` (3 per vertex). The mesh must outlive it. */
  SurfaceLocator(const TriangleMesh& mesh, const double* positions);
  /** The same over `triangles` (3 indices each, none repeating a vertex) of `vertices` vertices,
   *  without a TriangleMesh's topology; `triangles` must outlive it. */
  SurfaceLocator(const std::vector<std::int64_t>& triangles, std::size_t vertices,
                 const double* positions);

  /** Rebuilds the tree for new positions (O(n log n)). */
  void build(const double* positions);
  /** Keeps the tree, recomputes its boxes for new positions (O(n)). */
  void refit(const double* positions);

  /** The closest point of the surface to p within `maxDistance` (else triangle = -1). `hint`, a
   *  triangle likely near p (the last answer for a point that moved little), is measured first:
   *  its distance bounds the search, which then visits few boxes. */
  Hit closest(const double p[3], double maxDistance = std::numeric_limits<double>::infinity(),
              std::int64_t hint = -1) const;

  /** The surface's locally closest point to p, walking from triangle `from` (see the file
   *  comment); triangle = -1 when it is not within `maxDistance`. */
  Hit follow(const double p[3], std::int64_t from,
             double maxDistance = std::numeric_limits<double>::infinity()) const;

private:
  struct Node
  {
    float lo[3], hi[3];
    std::int32_t first = 0; // leaf: first entry in Order; inner: left child (right = first + 1)
    std::int32_t count = 0; // leaf: number of triangles; inner: 0
  };
  void split(std::int32_t node, std::int32_t begin, std::int32_t end,
             const std::vector<double>& centres);
  void boxOf(std::int32_t node);
  struct Sphere
  {
    float centre[3];
    float radius;
  };
  // Whether every point of the sphere is farther from p than `reach`.
  static bool outside(const Sphere& s, const double p[3], double reach);

  // The best hit so far and the squared distance a triangle must not exceed to replace it.
  // Before a hit, only what is strictly nearer than the bound (the caller's maxDistance) counts;
  // after one, an equally near triangle of lower index replaces it, so the answer does not
  // depend on the order the tree is searched in.
  struct Search
  {
    Hit best;
    double bound = 0;
    bool mayHold(double distance2) const
    {
      return best.triangle < 0 ? distance2 < bound : distance2 <= bound;
    }
    // True when the triangle became the best (the bound may have shrunk).
    bool offer(std::int64_t t, double d2, const double w[3], const double c[3])
    {
      if (!(best.triangle < 0 ? d2 < bound : d2 < bound || (d2 == bound && t < best.triangle)))
        return false;
      bound = d2;
      best.triangle = t;
      best.squaredDistance = d2;
      for (int k = 0; k < 3; ++k)
      {
        best.barycentric[k] = w[k];
        best.point[k] = c[k];
      }
      return true;
    }
  };
  // The binary tree with its levels taken two at a time: each node holds the (up to) four
  // grandchildren of a binary node, their boxes side by side, so a search descends half as many
  // levels and tests four boxes in one loop. Boxes as the binary nodes' (floats widened).
  struct WideNode
  {
    double lo[3][4], hi[3][4];
    std::int32_t first[4];  // a leaf's first entry in Order, or the child's index in Wide
    std::int32_t count[4];  // a leaf's number of triangles; 0: a child wide node; -1: no child
    std::int32_t source[4]; // the binary node each child stands for (its box)
  };
  std::int32_t collapse(std::int32_t binary);
  void visitLeaf(std::int32_t first, std::int32_t count, const double p[3], Search& search) const;
  // Searches the children of `wide` but `skip` (-1: all) and their subtrees (with the bound
  // search holds), nearer children first.
  void descend(std::int32_t wide, int skip, const double p[3], Search& search) const;
  struct Place
  {
    std::int32_t node = -1; // in Wide
    int slot = 0;
  };

  const std::vector<std::int64_t>* Triangles = nullptr;
  std::size_t VertexCount = 0;
  const double* Positions = nullptr; // the positions of the last build/refit (caller's memory)
  std::vector<double> Copy;          // ... copied, so the caller's array may change
  std::vector<Node> Nodes;
  std::vector<std::int32_t> Order;  // triangle indices, leaves' ranges
  std::vector<Sphere> Spheres;      // per entry of Order: its triangle's bounding sphere
  std::vector<WideNode> Wide;       // the tree searched (root first)
  std::vector<Place> WideParent;    // per wide node: where its parent holds it (root: none)
  std::vector<Place> LeafPlace;     // per binary node that is a leaf: where Wide holds it
  std::vector<std::int32_t> LeafOf; // per triangle, the leaf that holds it
  // The triangles around each vertex (follow()): those of vertex v are
  // Around[AroundStart[v], AroundStart[v + 1]).
  std::vector<std::int32_t> AroundStart, Around;
  std::vector<std::int64_t> Across; // per triangle and corner c: the triangle across the edge
                                    // opposite c (-1: none)
};

} // namespace dp
