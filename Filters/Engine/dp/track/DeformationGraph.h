// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DeformationGraph.h
 * @brief An embedded deformation graph on the template (Sumner, Schmid & Pauly, "Embedded
 *        Deformation for Shape Manipulation", SIGGRAPH 2007): a few hundred nodes, each with a
 *        rotation R_j and a translation t_j, deform the template's vertices v_i by blending
 *
 *   x_i = sum_j w_ij (R_j (v_i - g_j) + g_j + t_j)           (Sumner et al., eq. 1)
 *
 * with g_j the nodes' template positions. The tracker's coarse level (GraphRegistration) solves
 * for the nodes' motions: few unknowns, so its steps can be long, and each node moves a whole
 * patch rigidly, so a limb follows its data as one piece.
 *
 * Built on the template, so its rigidity is measured against the reference pose, never against
 * the last frame: nodes are the template vertices picked by farthest-point sampling in geodesic
 * distance along the mesh's edges; each vertex blends its `influences` geodesically nearest
 * nodes with weights (1 - d / d_max)^2 (d_max: the distance of the next nearest node), so a hand
 * resting on a thigh is never bound to the thigh's nodes. Two nodes are neighbours when they
 * blend a common vertex. A template in pieces (a depth mesh broken at its depth jumps) makes a
 * graph in parts; each part with fewer than a quarter of the largest part's nodes is linked to
 * the rest by an edge between its node and the nearest node outside it (Prim's growth from the
 * large parts), so a piece the data stop seeing moves with the body beside it instead of coasting
 * away on its last motion, while large parts (two people) stay apart. Everything is
 * deterministic (ties go to the lower index).
 *
 * Limits: geodesics follow the mesh's edges (a little longer than true geodesics); parts of the
 * mesh joined in the template (fused by a reconstruction) stay joined.
 */
#pragma once

#include "dp/geometry/TriangleMesh.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace dp
{

class DeformationGraph
{
public:
  struct Influence
  {
    std::int32_t node = 0;
    double weight = 0;
  };

  /** The motion of every node. */
  struct State
  {
    std::vector<Eigen::Matrix3d> rotation;
    std::vector<Eigen::Vector3d> translation;
  };

  /** Samples about `nodeCount` nodes on `mesh` at `rest` (3 per vertex; both must outlive the
   *  graph) and blends `influences` nodes per vertex. Throws std::invalid_argument for fewer than
   *  one node or influence. */
  DeformationGraph(const TriangleMesh& mesh, const double* rest, std::size_t nodeCount,
                   std::size_t influences);

  std::size_t numberOfNodes() const { return NodeVertex.size(); }
  /** The template vertex node j sits at. */
  std::int64_t nodeVertex(std::size_t j) const { return NodeVertex[j]; }
  /** g_j. */
  const double* nodePosition(std::size_t j) const { return &Rest[3 * NodeVertex[j]]; }
  /** The nodes vertex v blends, with their weights (summing to 1). */
  const Influence* influencesBegin(std::size_t v) const { return &Influences[Offsets[v]]; }
  const Influence* influencesEnd(std::size_t v) const { return &Influences[Offsets[v + 1]]; }
  /** Pairs (j, k), j < k, of neighbouring nodes. */
  const std::vector<std::array<std::int64_t, 2>>& edges() const { return Edges; }
  /** The largest geodesic distance from a vertex to its nearest node. */
  double spacing() const { return Spacing; }
  const TriangleMesh& mesh() const { return Mesh; }
  const double* rest() const { return Rest; }

  /** No motion: every R_j = I, t_j = 0. */
  State identity() const;
  /** x (3 per vertex) for a state. */
  void deform(const State& state, double* x) const;
  /** The state whose deformation comes closest to x: each node's rotation and translation fit
   *  (weighted Procrustes, Kabsch's method) to the vertices it blends. */
  State fit(const double* x) const;

private:
  void sampleNodes(std::size_t nodeCount);
  void blend(std::size_t influences);
  void linkSmallParts();

  const TriangleMesh& Mesh;
  const double* Rest;
  std::vector<std::int64_t> NodeVertex;
  std::vector<std::size_t> Offsets; // CSR over vertices
  std::vector<Influence> Influences;
  std::vector<std::array<std::int64_t, 2>> Edges;
  double Spacing = 0;
};

/** How a node's motion is continued: its rotation always turns on by the last step's; its point
 *  moves on by the last displacement (Straight) or by that displacement turned as well (Turning:
 *  a rigid motion continued, exact for a limb turning about a joint). */
enum class Extrapolation
{
  Straight,
  Turning
};

/** The state one step after `last` if the motion from `before` to `last` went on, scaled by
 *  `share` (1: constant velocity; 0: `last`). */
DeformationGraph::State extrapolate(const DeformationGraph::State& before,
                                    const DeformationGraph::State& last,
                                    const DeformationGraph& graph, double share,
                                    Extrapolation kind = Extrapolation::Turning);

} // namespace dp
