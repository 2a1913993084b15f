// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file CornerTable.h
 * @brief The mesh IsotropicRemesher works on: a triangle mesh in a corner table with the local
 *        operations of isotropic remeshing (edge split, flip and collapse), and the quadrics
 *        that place a collapsed edge's vertex.
 *
 * Corner c = 3 f + i is vertex i of triangle f; Opp[c] is the corner facing c across the edge
 * opposite c (-1 on a boundary). Internal to dp/geometry: the remeshing passes (which edges to
 * split, collapse or flip, and the relaxation) are IsotropicRemesher.cxx's.
 */
#pragma once

#include "dp/geometry/IsotropicRemesher.h"
#include "dp/support/Vec3.h"

#include <cstddef>
#include <vector>

namespace dp::support
{

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
 * A triangle mesh in a corner table, with Garland-Heckbert quadrics (Quadric) of the input's
 * planes around each vertex: split() at an edge's midpoint, flip() after canFlip(), collapse()
 * when the mesh stays manifold and unfolded; extract() gives the result. The remeshing passes
 * derive from it and read the arrays directly.
 *
 * Limits: the input is made manifold (see the constructor), not repaired otherwise; deleted
 * triangles and vertices stay in the arrays as -1 until extract(), so the arrays only grow.
 * Not thread-safe to change; the const queries may run in parallel.
 */
class CornerTable
{
public:
  /** Edges shared by more than two triangles, or by two of the same orientation, become
   *  boundaries; vertices where separate fans of triangles meet are split, one per fan. */
  explicit CornerTable(const IndexedMesh& mesh);

  std::size_t vertices() const { return Live; }

  /** No edge with one triangle only. */
  bool closed() const;

  /** Live vertices and triangles, renumbered. */
  void extract(RemeshedSurface& out) const;

protected:
  std::vector<Vec3> X;     // vertex positions
  std::vector<int> Corner; // the vertex of each corner; -1 for a deleted triangle
  std::vector<int> Opp;    // the opposite corner across the edge facing each corner
  std::vector<int> Of;     // a corner of each vertex; -1 for a deleted vertex
  std::size_t Live = 0;    // vertices in use

  static int next(int c) { return c % 3 == 2 ? c - 2 : c + 1; }
  static int prev(int c) { return c % 3 == 0 ? c + 2 : c - 1; }
  double edgeLength(int c) const { return norm(X[Corner[next(c)]] - X[Corner[prev(c)]]); }
  Vec3 faceNormal(int c) const // not normalised
  {
    const int f = c - c % 3;
    return cross(X[Corner[f + 1]] - X[Corner[f]], X[Corner[f + 2]] - X[Corner[f]]);
  }

  // The corners around the vertex of corner `start`, in order; true on a boundary.
  bool fan(int start, std::vector<int>& out) const;
  bool onBoundary(int v) const;
  // The vertices sharing an edge with v, sorted; true on a boundary.
  bool neighbours(int v, std::vector<int>& out) const;
  int valence(int v) const;

  // Splits the edge facing corner c at its midpoint.
  void split(int c);
  // Flips the edge facing corner c (which must have an opposite corner).
  void flip(int c);
  bool canFlip(int c) const;
  // Collapses the edge facing corner c into one vertex (at the midpoint, or at the endpoint on
  // the boundary), when that keeps the mesh manifold and unfolded and makes no edge longer than
  // maxLength. Returns whether it did.
  bool collapse(int c, double maxLength);

private:
  std::vector<Quadric> Planes; // of the fine surface around each vertex

  // What collapsing an edge does: the end that stays (moved to target, with the merged quadric)
  // and the end that goes.
  struct CollapsePlan
  {
    int keep = -1, gone = -1;
    Vec3 target{};
    Quadric merged;
  };

  void linkOpposites();
  void splitFans();
  void initPlanes();
  void link(int a, int b)
  {
    if (a >= 0)
      Opp[a] = b;
    if (b >= 0)
      Opp[b] = a;
  }
  int newFace(int a, int b, int c);
  bool planCollapse(int c, double maxLength, CollapsePlan& plan) const;
  bool staysUnfolded(int c, const Vec3& target, const std::vector<int>& fanGone,
                     const std::vector<int>& fanKeep) const;
  void applyCollapse(int c, const CollapsePlan& plan, const std::vector<int>& fanGone);
};

} // namespace dp::support
