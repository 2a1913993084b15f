// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/RigidAlignment.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <cmath>

namespace dp
{
namespace
{
// Gauss-Newton steps of the rotation and translation (each one is kept only if it lowers the
// distance term, so a few are enough to converge or stop).
constexpr int RigidIterations = 10;
// Move only along rigid motions the data holds at least this share as firmly as the firmest
// (0.05 still let a waving sheet slide along its waves; 0.2 holds it and keeps a turning body).
constexpr double RigidConstrained = 0.2;

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

// The centre of x weighted by the data's stiffness at each vertex, and the weighted RMS radius
// about it; false when there is no stiffness or no extent (nothing to align).
bool weightedCentreAndRadius(const std::vector<double>& x, const DistanceTerm& distance,
                             Eigen::Vector3d& centre, double& radius)
{
  const std::size_t nv = x.size() / 3;
  centre = Eigen::Vector3d::Zero();
  double total = 0;
  for (std::size_t v = 0; v < nv; ++v)
  {
    centre += distance.stiffness(v) * Eigen::Vector3d(&x[3 * v]);
    total += distance.stiffness(v);
  }
  if (!(total > 0))
    return false;
  centre /= total;
  double sum = 0;
  for (std::size_t v = 0; v < nv; ++v)
    sum += distance.stiffness(v) * (Eigen::Vector3d(&x[3 * v]) - centre).squaredNorm();
  radius = std::sqrt(sum / total);
  return radius > 0;
}

// The Gauss-Newton system A [w; t] = -b of the rigid motion d = w x r + t, r = (x - centre) /
// radius, from the distance term's quadric at each vertex.
void addRigidSystem(const std::vector<double>& x, const DistanceTerm& distance,
                    const Eigen::Vector3d& centre, double radius, Matrix6& A, Vector6& b)
{
  const std::size_t nv = x.size() / 3;
  for (std::size_t v = 0; v < nv; ++v)
  {
    const double c = distance.stiffness(v);
    if (c == 0)
      continue;
    const PlaneQuadric& q = distance.quadric(v);
    Eigen::Matrix3d M;
    M << q.matrix[0], q.matrix[1], q.matrix[2], q.matrix[1], q.matrix[3], q.matrix[4], q.matrix[2],
        q.matrix[4], q.matrix[5];
    const Eigen::Vector3d g(q.vector[0], q.vector[1], q.vector[2]);
    // d = w x r + t (r = x - centre): d = J [w; t] with J = [-[r]x, I].
    const Eigen::Vector3d r = (Eigen::Vector3d(&x[3 * v]) - centre) / radius;
    Eigen::Matrix<double, 3, 6> J;
    J << 0, r.z(), -r.y(), 1, 0, 0, -r.z(), 0, r.x(), 0, 1, 0, r.y(), -r.x(), 0, 0, 0, 1;
    A += c * J.transpose() * M * J;
    b += c * J.transpose() * g;
  }
}

// The system's solution along the rigid motions it holds at least RigidConstrained times as
// firmly as the firmest (added to `step`); false when it holds none.
bool constrainedStep(const Matrix6& A, const Vector6& b, Vector6& step)
{
  const Eigen::SelfAdjointEigenSolver<Matrix6> eigen(A);
  const double largest = eigen.eigenvalues()[5];
  if (!(largest > 0))
    return false;
  for (int i = 0; i < 6; ++i)
    if (eigen.eigenvalues()[i] >= RigidConstrained * largest)
      step -= eigen.eigenvectors().col(i) *
              (eigen.eigenvectors().col(i).dot(b) / eigen.eigenvalues()[i]);
  return true;
}
} // namespace

int alignRigidly(std::vector<double>& x, const DistanceTerm& distance)
{
  const std::size_t nv = x.size() / 3;
  support::BlockSparseMatrix diagonal(nv, {});
  std::vector<double> gradient(x.size());
  int kept = 0;
  for (int iteration = 0; iteration < RigidIterations; ++iteration)
  {
    diagonal.setZero();
    std::fill(gradient.begin(), gradient.end(), 0.0);
    const double before = distance.addModel(x.data(), diagonal, gradient.data());
    Eigen::Vector3d centre;
    double radius = 0;
    if (!weightedCentreAndRadius(x, distance, centre, radius))
      return kept;
    Matrix6 A = Matrix6::Zero();
    Vector6 b = Vector6::Zero();
    addRigidSystem(x, distance, centre, radius, A, b);
    Vector6 step = Vector6::Zero();
    if (!constrainedStep(A, b, step))
      return kept;
    const Eigen::Vector3d w = step.head<3>() / radius, t = step.tail<3>();
    const double angle = w.norm();
    const Eigen::Matrix3d R = angle > 0 ? Eigen::AngleAxisd(angle, w / angle).toRotationMatrix()
                                        : Eigen::Matrix3d::Identity();
    std::vector<double> trial(x.size());
    for (std::size_t v = 0; v < nv; ++v)
    {
      const Eigen::Vector3d y = R * (Eigen::Vector3d(&x[3 * v]) - centre) + centre + t;
      std::copy(y.data(), y.data() + 3, &trial[3 * v]);
    }
    if (!(distance.evaluate(trial.data(), nullptr) < before))
      return kept;
    x.swap(trial);
    ++kept;
  }
  return kept;
}

} // namespace dp
