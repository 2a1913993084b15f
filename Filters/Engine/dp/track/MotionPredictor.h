// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file MotionPredictor.h
 * @brief Where each frame's solve starts: the motion of the last frames continued.
 *
 * It keeps the last three tracked shapes and the deformation graph's last two states. For the
 * fine level it offers the vertices' constant-velocity extrapolation (the temporal term's
 * target, and the start without data) and the paper's motion prediction (MP): the minimum of E
 * along the constant, linear and quadratic extrapolations of the trajectories (a 1-D search on
 * each, at 0.25 .. 1.5 of the step). For the coarse level it continues each graph node's
 * rotation and the displacement of its point, that displacement turned with the node (a limb
 * swinging keeps turning about its joint) or not (Extrapolation; the tracker lets the data
 * choose).
 *
 * Limits: one global step length per frame in MP (not per vertex); a sudden change of motion
 * (a landing) is not foreseen: the coarse level's capture range has to absorb it.
 */
#pragma once

#include "dp/track/DeformationGraph.h"

#include <functional>
#include <vector>

namespace dp
{

class MotionPredictor
{
public:
  /** Forgets everything. */
  void clear()
  {
    Shapes.clear();
    States.clear();
  }
  /** Records a tracked frame (and the graph state that fits it, if any). */
  void push(const std::vector<double>& shape, const DeformationGraph::State* state = nullptr);
  /** Continues from `shape` with no motion history. */
  void restartFrom(const std::vector<double>& shape,
                   const DeformationGraph::State* state = nullptr);

  bool empty() const { return Shapes.empty(); }
  std::size_t depth() const { return Shapes.size(); }
  const std::vector<double>& last() const { return Shapes.back(); }

  /** 2 x[t-1] - x[t-2] (x[t-1] with a single frame of history). */
  std::vector<double> constantVelocity() const;
  /** The paper's MP: the point of lowest `energy` among the last shape and its linear and
   *  quadratic extrapolations at 0.25, 0.5, ..., 1.5 of the step. */
  std::vector<double>
  searchExtrapolations(const std::function<double(const double*)>& energy) const;
  /** The graph state continued by `share` of the last step (the last state when there is only
   *  one); false when no state is known. */
  bool predictState(const DeformationGraph& graph, double share, DeformationGraph::State& out,
                    Extrapolation kind = Extrapolation::Turning) const;
  /** Whether there are two states to continue (else predictState gives the last). */
  bool hasMotion() const { return States.size() >= 2; }
  /** The last recorded graph state (null when none). */
  const DeformationGraph::State* lastState() const
  {
    return States.empty() ? nullptr : &States.back();
  }

private:
  std::vector<std::vector<double>> Shapes;     // the last three, most recent last
  std::vector<DeformationGraph::State> States; // the last two
};

} // namespace dp
