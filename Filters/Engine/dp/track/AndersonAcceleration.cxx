// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/AndersonAcceleration.h"

#include <Eigen/QR>

#include <stdexcept>

namespace dp
{

AndersonAcceleration::AndersonAcceleration(int depth) : Depth(depth)
{
  if (depth < 1)
    throw std::invalid_argument("AndersonAcceleration: the depth must be at least 1");
}

bool AndersonAcceleration::next(const Eigen::VectorXd& u, const Eigen::VectorXd& g,
                                Eigen::VectorXd& next)
{
  Images.push_back(g);
  Residuals.push_back(g - u);
  if (static_cast<int>(Images.size()) > Depth + 1)
  {
    Images.pop_front();
    Residuals.pop_front();
  }
  const auto m = static_cast<Eigen::Index>(Images.size()) - 1;
  if (m < 1)
    return false;
  Eigen::MatrixXd residualChanges(u.size(), m), imageChanges(u.size(), m);
  for (Eigen::Index i = 0; i < m; ++i)
  {
    const auto k = static_cast<std::size_t>(i);
    residualChanges.col(i) = Residuals[k + 1] - Residuals[k];
    imageChanges.col(i) = Images[k + 1] - Images[k];
  }
  const Eigen::VectorXd theta = residualChanges.colPivHouseholderQr().solve(Residuals.back());
  if (!theta.allFinite())
    return false;
  Eigen::VectorXd candidate = Images.back() - imageChanges * theta;
  if (!candidate.allFinite())
    return false;
  next = std::move(candidate);
  return true;
}

void AndersonAcceleration::reset()
{
  Images.clear();
  Residuals.clear();
}

} // namespace dp
