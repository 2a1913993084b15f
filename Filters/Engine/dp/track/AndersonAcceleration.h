// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file AndersonAcceleration.h
 * @brief Anderson acceleration (type II) of a fixed-point iteration u <- g(u): from the last m + 1
 *        steps (u_i, g_i = g(u_i)) with residuals f_i = g_i - u_i, the next iterate is
 *
 *   u_next = g_k - sum_i theta_i (g_{i+1} - g_i),
 *   theta  = argmin | f_k - sum_i theta_i (f_{i+1} - f_i) |
 *
 * (Walker & Ni 2011; for ICP, Pavlov et al. 2018 and Zhang et al. 2021). On a linear map it is
 * GMRES on u = g(u): an iteration that converges linearly (ICP-like, where correspondences slide
 * along the surface) converges much faster.
 *
 * The coarse level (GraphRegistration) uses it on its Levenberg-Marquardt steps, where the
 * points -> mesh term's points slide along the surface a little each step (GraphOptions::
 * acceleration, three steps by default: Documentation/TrackingHistory.md).
 *
 * Limits: no safeguard of its own (the caller limits how far the accelerated iterate may lie from
 * the plain one, checks it and resets the history when it is worse); the coordinates should have
 * comparable units (the caller scales them); theta by a column-pivoting QR, so a rank-deficient
 * history is handled.
 */
#pragma once

#include <Eigen/Core>

#include <deque>

namespace dp
{

class AndersonAcceleration
{
public:
  /** `depth` m: the most differences of steps combined (m >= 1). */
  explicit AndersonAcceleration(int depth);

  /** Records a step u -> g(u) and sets `next` to the accelerated iterate. Returns false (and
   *  leaves `next` alone) while there is no earlier step to combine with, or when the
   *  combination is not finite. */
  bool next(const Eigen::VectorXd& u, const Eigen::VectorXd& g, Eigen::VectorXd& next);

  /** Forgets the steps recorded (after the caller rejected an accelerated iterate). */
  void reset();

private:
  int Depth;
  std::deque<Eigen::VectorXd> Images;    // g_i, oldest first
  std::deque<Eigen::VectorXd> Residuals; // f_i = g_i - u_i
};

} // namespace dp
