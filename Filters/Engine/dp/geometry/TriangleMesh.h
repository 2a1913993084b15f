// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file TriangleMesh.h
 * @brief Fixed connectivity of the deforming mesh: triangles plus the derived topology the
 *        energies need (edges, hinges = pairs of triangles sharing an edge, vertex one-rings).
 *
 * Limits: manifold or not, any triangle soup of valid indices is accepted; an edge shared by
 * more than two triangles yields one hinge per consistently oriented pair it can find (the
 * bending term is then partial there). Degenerate triangles (repeated vertex) are rejected.
 */
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace dp
{

class TriangleMesh
{
public:
  TriangleMesh() = default;
  /** Builds the topology; throws std::invalid_argument for bad indices or degenerate faces. */
  TriangleMesh(std::vector<std::int64_t> triangles, std::size_t vertexCount);

  std::size_t numberOfVertices() const { return VertexCount; }
  std::size_t numberOfTriangles() const { return Triangles.size() / 3; }
  const std::vector<std::int64_t>& triangles() const { return Triangles; }
  /** Unique edges (a < b). */
  const std::vector<std::array<std::int64_t, 2>>& edges() const { return Edges; }
  /**
   * Interior edges as (a, b, c, d): triangles (a, b, c) and (b, a, d) share the edge a-b with
   * the same orientation (c and d are the opposite vertices).
   */
  const std::vector<std::array<std::int64_t, 4>>& hinges() const { return Hinges; }
  /** Vertices sharing an edge with vertex v. */
  const std::vector<std::int64_t>& neighbours(std::size_t v) const { return Neighbours[v]; }

  /** Area of each vertex: a third of the area of each incident triangle, at `positions`. */
  std::vector<double> vertexAreas(const double* positions) const;
  /** Area-weighted (unnormalised face normals summed), normalised vertex normals. */
  void vertexNormals(const double* positions, double* normals) const;
  double totalArea(const double* positions) const;
  /** The share of triangles whose shape quality 4 sqrt(3) area / (sum of squared edges) is under
   *  `threshold` (1 for an equilateral triangle, 0 for a flat one): slivers. */
  double poorlyShapedShare(const double* positions, double threshold = 0.1) const;

private:
  std::vector<std::int64_t> Triangles;
  std::size_t VertexCount = 0;
  std::vector<std::array<std::int64_t, 2>> Edges;
  std::vector<std::array<std::int64_t, 4>> Hinges;
  std::vector<std::vector<std::int64_t>> Neighbours;
};

/** Area-weighted unit vertex normals of `triangles` (3 indices each) at `positions` (3 per
 *  vertex), into `normals` (3 per vertex; 0 0 0 for a vertex without area around it). Summed in
 *  triangle order: the same bits every time. */
void vertexNormalsOf(const std::vector<std::int64_t>& triangles, const double* positions,
                     std::size_t vertices, double* normals);

} // namespace dp
