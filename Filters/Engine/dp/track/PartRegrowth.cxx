// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/PartRegrowth.h"

#include "dp/geometry/SurfaceLocator.h"

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include <algorithm>
#include <cstddef>
#include <limits>

namespace dp
{
namespace
{
// Fewer lost vertices or unexplained points than these place nothing.
constexpr std::size_t MinimumVertices = 4, MinimumPoints = 12;
// At most this many of each enter the closest-point steps (evenly picked; the motion found moves
// the whole part).
constexpr std::size_t MostUsed = 300;
constexpr int IcpSteps = 30;

using Points = std::vector<Eigen::Vector3d>;

struct Motion
{
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  double residual = std::numeric_limits<double>::infinity(); // mean squared pair distance
};

// The largest connected set of vertices farther than `reach` from every data point.
std::vector<std::size_t> lostPart(const FrameData& frame, const TriangleMesh& mesh,
                                  const std::vector<double>& x, double reach)
{
  const std::size_t nv = mesh.numberOfVertices();
  std::vector<char> far(nv, 0);
  for (std::size_t v = 0; v < nv; ++v)
  {
    double d2 = 0;
    frame.nearest(&x[3 * v], &d2);
    far[v] = d2 > reach * reach;
  }
  std::vector<std::size_t> largest, part;
  for (std::size_t seed = 0; seed < nv; ++seed)
  {
    if (far[seed] != 1)
      continue;
    part.assign(1, seed);
    far[seed] = 2;
    for (std::size_t i = 0; i < part.size(); ++i)
      for (std::int64_t w : mesh.neighbours(part[i]))
        if (far[static_cast<std::size_t>(w)] == 1)
        {
          far[static_cast<std::size_t>(w)] = 2;
          part.push_back(static_cast<std::size_t>(w));
        }
    if (part.size() > largest.size())
      largest = part;
  }
  return largest;
}

// The subsample's points (strays left out) farther than `reach` from the mesh.
Points unexplainedPoints(const FrameData& frame, const TriangleMesh& mesh,
                         const std::vector<double>& x, double reach)
{
  const SurfaceLocator locator(mesh, x.data());
  const auto& spread = frame.spread();
  const auto& stray = frame.strayInSpread();
  Points q;
  for (std::size_t i = 0; i < spread.size(); ++i)
  {
    const double* p = frame.point(spread[i]);
    if ((stray.empty() || !stray[i]) && locator.closest(p, reach).triangle < 0)
      q.emplace_back(p[0], p[1], p[2]);
  }
  return q;
}

// At most MostUsed of `all`, evenly picked.
Points thinned(const Points& all)
{
  const std::size_t step = (all.size() + MostUsed - 1) / MostUsed;
  Points kept;
  for (std::size_t i = 0; i < all.size(); i += std::max<std::size_t>(step, 1))
    kept.push_back(all[i]);
  return kept;
}

Eigen::Vector3d centroid(const Points& p)
{
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& q : p)
    c += q;
  return c / static_cast<double>(p.size());
}

// The direction of the largest spread of p about c.
Eigen::Vector3d principalAxis(const Points& p, const Eigen::Vector3d& c)
{
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (const auto& q : p)
    C += (q - c) * (q - c).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(C);
  return solver.eigenvectors().col(2);
}

std::size_t nearest(const Points& set, const Eigen::Vector3d& p)
{
  std::size_t best = 0;
  double bestD2 = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < set.size(); ++i)
  {
    const double d2 = (set[i] - p).squaredNorm();
    if (d2 < bestD2)
    {
      bestD2 = d2;
      best = i;
    }
  }
  return best;
}

// The rigid motion taking each from[i] closest to to[i], weighted by w[i] (Kabsch), and its
// weighted mean squared distance.
Motion kabsch(const Points& from, const Points& to, const std::vector<double>& w)
{
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
  double total = 0;
  for (std::size_t i = 0; i < from.size(); ++i)
  {
    a += w[i] * from[i];
    b += w[i] * to[i];
    total += w[i];
  }
  a /= total;
  b /= total;
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < from.size(); ++i)
    C += w[i] * (to[i] - b) * (from[i] - a).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(C, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  Motion m;
  m.R = svd.matrixU() * D * svd.matrixV().transpose();
  m.t = b - m.R * a;
  m.residual = 0;
  for (std::size_t i = 0; i < from.size(); ++i)
    m.residual += w[i] * (m.R * from[i] + m.t - to[i]).squaredNorm();
  m.residual /= total;
  return m;
}

// The lost part, the points to place it on, and its border: its vertices next to the rest of the
// mesh (where it joins the body, about which a limb turns).
struct Placement
{
  Points part, target, border;
};

// Closest points both ways from `m`, each step solved exactly.
Motion closestPoints(const Placement& p, Motion m)
{
  const std::vector<double> w(p.part.size() + p.target.size(), 1.0);
  for (int step = 0; step < IcpSteps; ++step)
  {
    Points moved(p.part.size()), from, to;
    for (std::size_t i = 0; i < p.part.size(); ++i)
      moved[i] = m.R * p.part[i] + m.t;
    for (std::size_t i = 0; i < p.part.size(); ++i)
    {
      from.push_back(p.part[i]);
      to.push_back(p.target[nearest(p.target, moved[i])]);
    }
    for (const auto& q : p.target)
    {
      from.push_back(p.part[nearest(moved, q)]);
      to.push_back(q);
    }
    const Motion next = kabsch(from, to, w);
    const bool settled = (next.t - m.t).norm() < 1e-12 && (next.R - m.R).norm() < 1e-12;
    m = next;
    if (settled)
      break;
  }
  return m;
}

// The mean squared distance `m` moves the border.
double borderShift(const Placement& p, const Motion& m)
{
  double sum = 0;
  for (const auto& b : p.border)
    sum += (m.R * b + m.t - b).squaredNorm();
  return p.border.empty() ? 0.0 : sum / static_cast<double>(p.border.size());
}

// The motion from each start (no rotation; the principal axes matched either way; the centroids
// matched) that ends closest, its border's shift counted as much.
Motion bestMotion(const Placement& p)
{
  const Eigen::Vector3d cp = centroid(p.part), ct = centroid(p.target);
  const Eigen::Vector3d ap = principalAxis(p.part, cp), at = principalAxis(p.target, ct);
  Motion best;
  double bestScore = std::numeric_limits<double>::infinity();
  for (int start = 0; start < 3; ++start)
  {
    Motion m;
    if (start > 0)
      m.R = Eigen::Quaterniond::FromTwoVectors(ap, start == 1 ? at : Eigen::Vector3d(-at))
                .toRotationMatrix();
    m.t = ct - m.R * cp;
    const Motion ended = closestPoints(p, m);
    const double score = ended.residual + borderShift(p, ended);
    if (score < bestScore)
    {
      best = ended;
      bestScore = score;
    }
  }
  return best;
}

} // namespace

std::vector<double> regrowLostPart(const FrameData& frame, const TriangleMesh& mesh,
                                   const std::vector<double>& x, double reach)
{
  if (frame.empty())
    return {};
  const std::vector<std::size_t> lost = lostPart(frame, mesh, x, reach);
  if (lost.size() < MinimumVertices)
    return {};
  const Points target = unexplainedPoints(frame, mesh, x, reach);
  if (target.size() < MinimumPoints)
    return {};
  std::vector<char> inPart(mesh.numberOfVertices(), 0);
  for (std::size_t v : lost)
    inPart[v] = 1;
  Points part, border;
  for (std::size_t v : lost)
  {
    part.emplace_back(x[3 * v], x[3 * v + 1], x[3 * v + 2]);
    const auto& around = mesh.neighbours(v);
    if (std::any_of(around.begin(), around.end(),
                    [&](std::int64_t w) { return !inPart[static_cast<std::size_t>(w)]; }))
      border.push_back(part.back());
  }
  const Motion m = bestMotion({thinned(part), thinned(target), thinned(border)});
  std::vector<double> y = x;
  for (std::size_t v : lost)
  {
    const Eigen::Vector3d moved = m.R * Eigen::Vector3d(&x[3 * v]) + m.t;
    for (int k = 0; k < 3; ++k)
      y[3 * v + k] = moved[k];
  }
  return y;
}

} // namespace dp
