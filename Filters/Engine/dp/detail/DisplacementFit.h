// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DisplacementFit.h
 * @brief The detail layer of one frame: a scalar displacement per fine vertex, along the normal
 *        of the subdivided base mesh, that puts the fine mesh on the frame's data.
 *
 * The fine mesh of frame t is x_i = (S b_t)_i + d_i n_i, with S the subdivision map
 * (SubdivisionMap), b_t the tracked base positions and n_i the unit area-weighted normals of the
 * subdivided base S b_t. Each fine vertex first reads its observation o_i (FrameSurface::cross:
 * where its normal line meets the data, with the data's weight w_i; none in a hole, on the far
 * side of a thin part, beyond the reach). The displacements then minimise
 *
 *   sum_i w_i (d_i - o_i)^2 + lambda sum_{edges ij} (d_i - d_j)^2 + mu sum_i d_i^2
 *
 * (lambda the smoothness, mu = 1e-6: a part with no data at all stays on the base): where the
 * data speak they are followed, where they are silent the membrane term spans the gap with the
 * smoothest field that meets its rim (a hole's displacements stay between those around it:
 * bounded, no spike). Observations far from the fitted field (beyond three robust standard
 * deviations, and beyond a quarter of the reach: a stray part, a neighbour's surface) lose
 * weight, w_i / (1 + (r_i / width)^2), and the system is solved again (robustRounds). Each
 * system is solved by conjugate gradients with a Jacobi preconditioner, matrix-free over the
 * fine mesh's edges: O(fine vertices) per iteration, multi-threaded, the same result for any
 * thread count (sums in a fixed order).
 *
 * Limits: a displacement is along the normal only, so detail the subdivided base meets at a
 * grazing angle (a finger thinner than the base's edge) is beyond its reach; observations beyond
 * `reach` count as none.
 */
#pragma once

#include "dp/detail/FrameSurface.h"
#include "dp/geometry/SubdivisionMap.h"

#include <cstddef>
#include <vector>

namespace dp
{

struct DisplacementFitOptions
{
  double reach = 0;            // the farthest displacement that counts (world units; > 0)
  double normalAngle = 80;     // degrees between the fine normal and the data's beyond which
                               // the data are another surface's
  double smoothness = 0.02;    // lambda, relative to a data weight of 1
  double radius = 0;           // point data's Gaussian width (world units; 0: reach / 4)
  int robustRounds = 1;        // reweighted solves after the first
  int maximumIterations = 200; // of each conjugate-gradient solve
  double tolerance = 1e-6;     // relative residual that ends a solve
};

struct DisplacementFit
{
  std::vector<double> displacement; // per fine vertex (world units)
  std::vector<std::uint8_t> met;    // per fine vertex: 1 where its normal line met the data
  std::vector<double> residual;     // per fine vertex: |observation - displacement| where met
                                    // (how far the fitted surface lies from the data), else -1
  std::size_t observed = 0;         // fine vertices whose normal line met the data
  std::size_t downweighted = 0;     // of them, those the robust rounds gave under half weight
  int iterations = 0;               // conjugate-gradient iterations, all solves
};

/** Fits the detail layer of frames of one fine mesh (the map's connectivity). */
class DisplacementFitter
{
public:
  explicit DisplacementFitter(const SubdivisionMap& map);

  /** The frame's displacements against `data` (see the file comment), from the subdivided
   *  base's positions and normals (SubdivisionMap::subdivide). Throws
   *  std::invalid_argument for a reach that is not positive and finite. */
  DisplacementFit fit(const double* finePositions, const double* fineNormals,
                      const FrameSurface& data, const DisplacementFitOptions& options) const;

  const SubdivisionMap& map() const { return Map; }

private:
  // (W + lambda L + mu I) d = W o by Jacobi-preconditioned conjugate gradients from d.
  int solve(const std::vector<double>& w, const std::vector<double>& wo, double lambda,
            const DisplacementFitOptions& options, std::vector<double>& d) const;

  const SubdivisionMap& Map;
  std::vector<std::size_t> NeighbourStart; // fine vertex i's neighbours:
  std::vector<std::int64_t> Neighbours;    //   Neighbours[NeighbourStart[i] .. [i + 1])
};

} // namespace dp
