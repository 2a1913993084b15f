// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file RobustKernel.h
 * @brief The robust penalties of the tracker's terms, one type: each term's iteratively
 *        reweighted least squares weight w(u^2) of a residual r at scale s, u = r / s.
 *
 *   GemanMcClure  w = 1 / (1 + u^2)^2: the data terms (DistanceTerm, CoverageTerm), so points
 *                 far from the surface (outliers, another limb's data) fade out;
 *   Huber         w = min(1, 1 / u): the coarse level's bending (GraphRegistration), an L1
 *                 penalty beyond the scale, so joints bend while the rest stays rigid;
 *   None          w = 1: plain least squares (a scale of 0 means this for every term).
 *
 * The weight is taken as a function of u^2, which each term computes from what it has at hand
 * (a distance, or a squared distance).
 */
#pragma once

#include <algorithm>
#include <cmath>

namespace dp
{

struct RobustKernel
{
  enum class Kind
  {
    None,
    GemanMcClure,
    Huber
  };
  Kind kind = Kind::None;
  double scale = 0; // world units; 0: plain least squares

  /** Whether it weighs anything (a kernel and a positive scale). */
  bool active() const { return kind != Kind::None && scale > 0; }

  /** The weight of a residual whose squared ratio to the scale is `u2`. */
  double weightOfSquaredRatio(double u2) const
  {
    switch (kind)
    {
    case Kind::GemanMcClure:
      return 1.0 / ((1 + u2) * (1 + u2));
    case Kind::Huber:
      return std::min(1.0, 1.0 / std::sqrt(u2));
    default:
      return 1.0;
    }
  }
};

} // namespace dp
