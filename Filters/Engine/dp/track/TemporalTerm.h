// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file TemporalTerm.h
 * @brief Temporal coherence (beyond the paper): each vertex is pulled toward where its motion
 *        would take it, the constant-velocity extrapolation x^_i = 2 x_i[t-1] - x_i[t-2], so
 *        that E penalises the vertices' acceleration:
 *
 *   E_acc = k_acc / (L voxel) * sum_i m_i |x_i - x^_i|^2 / 2
 *
 * (same units as the data terms). Along the surface, where the data say nothing, it keeps each
 * vertex on its course from frame to frame (no shake); across the surface the data term, far
 * stiffer, wins, so real motion is not held back.
 *
 * Limits: it resists real tangential acceleration in proportion to k_acc / k_dis.
 */
#pragma once

#include "dp/track/EnergyTerm.h"

#include <vector>

namespace dp
{

class TemporalTerm : public EnergyTerm
{
public:
  /** `target` x^ (3 per vertex) and `mass` must outlive the term. */
  TemporalTerm(const std::vector<double>& target, const std::vector<double>& mass, double weight,
               double lengthScale, double voxel)
      : Target(target), Mass(mass), Scale(weight / (lengthScale * voxel))
  {
  }

  const char* name() const override { return "temporal"; }
  double evaluate(const double* x, double* gradient) const override
  {
    double e = 0;
    for (std::size_t v = 0; v < Mass.size(); ++v)
    {
      const double c = Scale * Mass[v];
      for (int k = 0; k < 3; ++k)
      {
        const double d = x[3 * v + k] - Target[3 * v + k];
        e += 0.5 * c * d * d;
        if (gradient)
          gradient[3 * v + k] += c * d;
      }
    }
    return e;
  }
  double addModel(const double* x, support::BlockSparseMatrix& hessian,
                  double* gradient) const override
  {
    for (std::size_t v = 0; v < Mass.size(); ++v)
    {
      const double c = Scale * Mass[v];
      const double block[9] = {c, 0, 0, 0, c, 0, 0, 0, c};
      hessian.addToDiagonalBlock(static_cast<std::int64_t>(v), block);
    }
    return evaluate(x, gradient);
  }

private:
  const std::vector<double>& Target;
  const std::vector<double>& Mass;
  double Scale;
};

} // namespace dp
