// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file MeshPrediction.h
 * @brief Prediction of per-vertex integers from the vertices a decoder already has (beyond the
 *        paper, which stores floats): the order the vertices are met in, and three predictors
 *        of a vertex's value from its earlier neighbours.
 *
 * VertexTraversal orders the vertices so that most are predicted from neighbours all around
 * them. A vertex's row of values (its weight in every component, or its mean and basis
 * coordinates) is then predicted column by column from those neighbours:
 *
 *   Mean        the rounded mean of the earlier neighbours' values in the column (a Laplacian
 *               predictor: exact where the field is locally linear);
 *   Regression  sum_n alpha_n x_n, where alpha minimises, over the columns already coded for this
 *               vertex, |x_v - sum_n alpha_n x_n|^2 + lambda |alpha - 1/|N||^2 (ridge towards the
 *               mean): the vertex's place among its neighbours, learnt from its strong
 *               components, carried to the weaker ones (after Vasa & Skala's neighbourhood
 *               predictors for PCA-coded animation). Two ridges, Light and Heavy.
 *
 * Encoder and decoder compute the same prediction bit for bit: the arithmetic is scalar IEEE
 * double in a fixed order (this unit is compiled without floating-point contraction), and a
 * prediction that is not finite or beyond +-2^60 falls back to the mean.
 *
 * Internal to the compression; not installed API. Limits: at most MaximumNeighbours earlier
 * neighbours take part in a regression (the first met); values are within +-2^60.
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dp::compress
{

/**
 * The order a decoder meets the vertices in, and for each the vertices it is predicted from,
 * all met before it. The mesh is decimated in levels, as progressive mesh coders do: each level
 * takes out a maximal independent set of vertices (no two neighbours), joining each one's ring
 * so the coarser graph keeps its links; what is left (the base) is met first, breadth first,
 * each vertex predicted from its neighbours met before it; then the levels, coarsest first, each
 * vertex predicted from its whole ring, which is all known by then. About a third of the
 * vertices go at each level, so most are predicted from neighbours all around them (a
 * Laplacian predictor) rather than from one side.
 */
struct VertexTraversal
{
  static constexpr std::size_t MaximumLevels = 8, MinimumBase = 32;

  VertexTraversal(const std::vector<std::int64_t>& triangles, std::size_t vertices);
  std::size_t vertices() const { return order.size(); }
  std::vector<std::size_t> order; // vertex indices, in the order they are met
  // The i-th vertex met is predicted from earlier[start[i] .. start[i + 1]) (vertex indices).
  std::vector<std::size_t> start, earlier;
  std::size_t base = 0; // the first `base` vertices met are the base
};

/** What a column of per-vertex values is predicted from (stored as 2 bits per column). */
enum class VertexPredictor : std::uint8_t
{
  None = 0,
  Mean = 1,
  LightRegression = 2,
  HeavyRegression = 3
};
constexpr int VertexPredictors = 4;

/** The largest magnitude of a coded value (and of a prediction). */
constexpr std::int64_t ValueLimit = std::int64_t{1} << 60;

/**
 * The predictions of one vertex's row, column by column, from its earlier neighbours' rows
 * (`values` row-major, `columns` per vertex; the neighbours' rows complete, this vertex's row
 * complete up to the column asked). Columns must be asked in order 0, 1, 2, ...
 */
class RowPredictor
{
public:
  static constexpr std::size_t MaximumNeighbours = 16;

  RowPredictor(const std::int64_t* values, std::size_t columns, const std::size_t* neighbours,
               std::size_t count, std::size_t vertex);
  /** The prediction of column c by `p`; then learn(c) once the column's value is known. */
  std::int64_t predict(std::size_t c, VertexPredictor p);
  void learn(std::size_t c);

private:
  std::int64_t mean(std::size_t c) const;
  std::int64_t regression(std::size_t c, double ridge);

  const std::int64_t* Values;
  std::size_t Columns, Vertex;
  const std::size_t* Neighbours; // all of them take part in the mean,
  std::size_t All, Count;        // the first Count (at most MaximumNeighbours) in the regression
  // The normal equations so far: G = sum_c x_c x_c^T, b = sum_c x_c v_c (x_c: the neighbours'
  // values of column c, v_c this vertex's).
  double G[MaximumNeighbours * MaximumNeighbours] = {};
  double B[MaximumNeighbours] = {};
};

} // namespace dp::compress
