// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/MotionPredictor.h"

namespace dp
{

void MotionPredictor::push(const std::vector<double>& shape, const DeformationGraph::State* state)
{
  Shapes.push_back(shape);
  if (Shapes.size() > 3)
    Shapes.erase(Shapes.begin());
  if (state)
  {
    States.push_back(*state);
    if (States.size() > 2)
      States.erase(States.begin());
  }
  else
    States.clear();
}

void MotionPredictor::restartFrom(const std::vector<double>& shape,
                                  const DeformationGraph::State* state)
{
  clear();
  push(shape, state);
}

std::vector<double> MotionPredictor::constantVelocity() const
{
  std::vector<double> x = Shapes.back();
  if (Shapes.size() >= 2)
  {
    const auto& before = Shapes[Shapes.size() - 2];
    for (std::size_t i = 0; i < x.size(); ++i)
      x[i] = 2 * x[i] - before[i];
  }
  return x;
}

std::vector<double>
MotionPredictor::searchExtrapolations(const std::function<double(const double*)>& energy) const
{
  const std::vector<double>& last = Shapes.back();
  std::vector<std::vector<double>> targets;
  if (Shapes.size() >= 2)
  {
    targets.push_back(constantVelocity());
    if (Shapes.size() >= 3)
    {
      const auto& before = Shapes[Shapes.size() - 2];
      const auto& earlier = Shapes[Shapes.size() - 3];
      std::vector<double> quadratic(last.size());
      for (std::size_t i = 0; i < last.size(); ++i)
        quadratic[i] = 3 * last[i] - 3 * before[i] + earlier[i];
      targets.push_back(std::move(quadratic));
    }
  }
  std::vector<double> best = last, candidate(last.size());
  double lowest = energy(last.data());
  for (const auto& target : targets)
    for (double alpha : {0.25, 0.5, 0.75, 1.0, 1.25, 1.5})
    {
      for (std::size_t i = 0; i < last.size(); ++i)
        candidate[i] = last[i] + alpha * (target[i] - last[i]);
      const double e = energy(candidate.data());
      if (e < lowest)
      {
        lowest = e;
        best = candidate;
      }
    }
  return best;
}

bool MotionPredictor::predictState(const DeformationGraph& graph, double share,
                                   DeformationGraph::State& out, Extrapolation kind) const
{
  if (States.empty())
    return false;
  out = States.size() >= 2 ? extrapolate(States[0], States[1], graph, share, kind) : States.back();
  return true;
}

} // namespace dp
