// SPDX-License-Identifier: BSD-3-Clause
#include "dp/Tracker.h"

#include "dp/SurfaceSampler.h"
#include "dp/detail/BlockSparseMatrix.h"

#include <lbfgs.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

namespace dp
{

namespace
{
// body(v) for every vertex, on all threads in blocks; body must touch only vertex v's data.
template <typename Body>
void forEachVertex(std::size_t count, const Body& body)
{
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 128),
                    [&](const tbb::blocked_range<std::size_t>& range)
                    {
                      for (std::size_t v = range.begin(); v != range.end(); ++v)
                        body(v);
                    });
}
} // namespace
namespace
{
constexpr double Pi = 3.14159265358979323846;
// Gauss-Newton: relative residual at which conjugate gradients stop (an inexact Newton step:
// tighter solves cost more than the extra iterations they save), and the largest vertex move,
// in voxels, below which a frame counts as settled (the field resolves nothing finer).
constexpr double StepTolerance = 0.3;
constexpr double SettledStep = 0.1;
// Planes: how far from a data point (in voxels) its tangent plane stands for the surface.
constexpr double PlaneReach = 2.0;
// Rigid pre-alignment: Gauss-Newton steps of the rotation and translation (each one is kept only
// if it lowers the distance energy, so a few are enough to converge or stop).
constexpr int RigidIterations = 10;
// ... moving only along rigid motions the data holds at least this share as firmly as the firmest
// (0.05 still let a waving sheet slide along its waves; 0.2 holds it and keeps a turning body).
constexpr double RigidConstrained = 0.2;

// The Gauss-Newton model of D^2 around a sample: (D + g.(y - x))^2.
PlaneQuadric quadricOf(const DistanceSample& s)
{
  PlaneQuadric q;
  int m = 0;
  for (int i = 0; i < 3; ++i)
  {
    q.vector[i] = s.distance * s.gradient[i];
    for (int j = i; j < 3; ++j)
      q.matrix[m++] = s.gradient[i] * s.gradient[j];
  }
  q.constant = s.distance * s.distance;
  return q;
}

// What the solvers minimise: the tracker's energy with fixed data weights.
struct Objective
{
  const Tracker* tracker;
  const DistanceField* field;
  const std::vector<double>* weights;
  int evaluations = 0;
  double operator()(const double* x, double* gradient)
  {
    ++evaluations;
    if (gradient)
      std::fill(gradient, gradient + tracker->templatePositions().size(), 0.0);
    return tracker->energy(x, field, *weights, gradient);
  }
};

lbfgsfloatval_t evaluateForLbfgs(void* instance, const lbfgsfloatval_t* x, lbfgsfloatval_t* g,
                                 const int, const lbfgsfloatval_t)
{
  return (*static_cast<Objective*>(instance))(x, g);
}

// Largest eigenvalue of the Hessian of the objective at x, by power iteration on finite
// differences of the gradient.
double largestCurvature(Objective& objective, const std::vector<double>& x, double lengthScale)
{
  const std::size_t n = x.size();
  std::vector<double> v(n), gp(n), gm(n), xp(n), xm(n);
  for (std::size_t i = 0; i < n; ++i)
    v[i] = std::sin(12.9898 * static_cast<double>(i) + 1.0); // fixed, generic start
  double lambda = 0;
  const double h = 1e-6 * lengthScale;
  for (int iteration = 0; iteration < 30; ++iteration)
  {
    double length = 0;
    for (double value : v)
      length += value * value;
    length = std::sqrt(length);
    if (length == 0)
      break;
    for (std::size_t i = 0; i < n; ++i)
    {
      v[i] /= length;
      xp[i] = x[i] + h * v[i];
      xm[i] = x[i] - h * v[i];
    }
    objective(xp.data(), gp.data());
    objective(xm.data(), gm.data());
    double rayleigh = 0;
    for (std::size_t i = 0; i < n; ++i)
    {
      const double hv = (gp[i] - gm[i]) / (2 * h);
      rayleigh += v[i] * hv;
      v[i] = hv;
    }
    if (iteration > 3 && std::abs(rayleigh - lambda) < 1e-3 * std::abs(rayleigh))
    {
      lambda = rayleigh;
      break;
    }
    lambda = rayleigh;
  }
  return std::abs(lambda);
}
} // namespace

Tracker::Tracker(TriangleMesh mesh, std::vector<double> templatePositions,
                 const TrackerOptions& options)
    : Mesh(std::move(mesh)), Template(std::move(templatePositions)), Options(options),
      Cloth(Mesh, Template.data(), options.cloth)
{
  if (Template.size() != 3 * Mesh.numberOfVertices())
    throw std::invalid_argument("the template has " + std::to_string(Template.size() / 3) +
                                " positions for " + std::to_string(Mesh.numberOfVertices()) +
                                " vertices");
  if (!(options.distanceWeight >= 0) || !(options.tolerance > 0) || options.maxIterations < 1 ||
      options.voxelSize < 0 || options.bandWidth < 0 || options.outlierDistance < 0 ||
      !(options.restUpdate >= 0 && options.restUpdate <= 1))
    throw std::invalid_argument("tracker options out of range (weights, sizes and tolerance "
                                "must be non-negative, iterations at least 1, the rest update "
                                "between 0 and 1)");
  TemplateRest = Cloth.restState();
  Voxel = options.voxelSize > 0 ? options.voxelSize : boundingBoxDiagonal(Template) / 200.0;
}

double Tracker::energy(const double* x, const DistanceField* field,
                       const std::vector<double>& weights, double* gradient, double* internal,
                       double* distance) const
{
  const double eInt = Cloth.addGradient(x, gradient);
  const double eDis = distanceEnergy(x, field, weights, gradient);
  if (internal)
    *internal = eInt;
  if (distance)
    *distance = eDis;
  return eInt + eDis;
}

double Tracker::distanceEnergy(const double* x, const DistanceField* field,
                               const std::vector<double>& weights, double* gradient,
                               double* perVertex) const
{
  if (!field)
    return 0;
  const auto& mass = Cloth.vertexMass();
  const double scale = Options.distanceWeight / Cloth.lengthScale();
  // Vertices in parallel (sampling the field is most of the tracker's time), each writing only
  // its own entries; the sum is taken afterwards in vertex order, so any thread count gives the
  // same bits.
  std::vector<double> values(mass.size(), 0.0);
  forEachVertex(mass.size(),
                [&](std::size_t v)
                {
                  if (weights[v] == 0)
                    return;
                  const DistanceSample s = sampleData(*field, x + 3 * v, v);
                  const double w = scale * mass[v] * weights[v];
                  // Squared: D^2 / (2 voxel), smooth at the data; else the paper's D.
                  const double value =
                      Options.squaredDistance ? 0.5 * s.distance * s.distance / Voxel : s.distance;
                  const double slope = Options.squaredDistance ? s.distance / Voxel : 1.0;
                  values[v] = w * value;
                  if (gradient)
                    for (int k = 0; k < 3; ++k)
                      gradient[3 * v + k] += w * slope * s.gradient[k];
                });
  double e = 0;
  for (std::size_t v = 0; v < values.size(); ++v)
  {
    e += values[v];
    if (perVertex && weights[v] != 0)
      perVertex[v] = values[v];
  }
  return e;
}

DistanceSample Tracker::sampleData(const DistanceField& field, const double* x,
                                   std::size_t vertex) const
{
  VoxelCell* cell = vertex < Cells.size() ? &Cells[vertex] : nullptr;
  if (Options.distanceMeasure == DistanceMeasure::Planes && !FrameNormals.empty())
    return field.sampleToPlanes(x, FrameNormals.data(), PlaneReach * Voxel, cell);
  return field.sample(x, cell);
}

std::vector<double> Tracker::predict() const
{
  return History.empty() ? Template : History.back();
}

namespace
{
// Preconditioned conjugate gradients on the lower-stored symmetric positive definite A, from
// x = 0, until the residual falls below tolerance * |b| or after `limit` iterations. Every
// iterate is a descent direction of the quadratic model, so an early stop still gives a usable
// (inexact Newton) step.
template <typename Preconditioner>
Eigen::VectorXd conjugateGradients(const detail::BlockSparseMatrix::Matrix& A,
                                   const Eigen::VectorXd& b, const Preconditioner& precondition,
                                   double tolerance, int limit, int& iterations)
{
  const auto S = A.selfadjointView<Eigen::Lower>();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(b.size());
  Eigen::VectorXd r = b;
  Eigen::VectorXd z = precondition(r);
  Eigen::VectorXd p = z;
  double rz = r.dot(z);
  const double target = tolerance * b.norm();
  for (iterations = 0; iterations < limit && r.norm() > target; ++iterations)
  {
    const Eigen::VectorXd q = S * p;
    const double curvature = p.dot(q);
    if (!(curvature > 0))
      break;
    const double alpha = rz / curvature;
    x += alpha * p;
    r -= alpha * q;
    z = precondition(r);
    const double next = r.dot(z);
    p = z + (next / rz) * p;
    rz = next;
  }
  return x;
}
} // namespace

// The Gauss-Newton state kept across frames: the matrix pattern is the mesh's, so it and the
// symbolic analysis of the preconditioner are made once.
struct Tracker::NewtonState
{
  detail::BlockSparseMatrix Hessian;
  // The preconditioner: P (x) I_3, P the matrix of the 3x3 blocks' traces / 3 (a rotation-
  // invariant, Laplacian-like approximation of the Gauss-Newton matrix with a third of its
  // unknowns, so 27x cheaper to factorise), factorised by sparse LDL^T.
  Eigen::SimplicialLDLT<detail::BlockSparseMatrix::Matrix, Eigen::Lower> Preconditioner;
  bool Analysed = false;
  // The blocks each cloth term's pairs add to, in the order ClothEnergy visits them.
  std::vector<detail::BlockSparseMatrix::Slot> TermSlots;

  Eigen::VectorXd precondition(const Eigen::VectorXd& r) const
  {
    const Eigen::Index n = r.size() / 3;
    using Columns = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
    const Columns z = Preconditioner.solve(Eigen::Map<const Columns>(r.data(), n, 3));
    return Eigen::Map<const Eigen::VectorXd>(z.data(), 3 * n);
  }
};

Tracker::~Tracker() = default;

int Tracker::solveGaussNewton(
    std::vector<double>& x, const DistanceField* field, std::vector<double>& weights,
    const std::function<std::size_t(const std::vector<double>&)>& decideWeights)
{
  const std::size_t nv = Mesh.numberOfVertices();
  const auto n = static_cast<Eigen::Index>(3 * nv);
  const double scale = Options.distanceWeight / Cloth.lengthScale();
  const auto& mass = Cloth.vertexMass();
  if (!Newton)
  {
    // Pattern: every pair of vertices sharing a term (edges; the opposite vertices of hinges).
    std::vector<std::array<std::int64_t, 2>> pairs(Mesh.edges().begin(), Mesh.edges().end());
    for (const auto& h : Mesh.hinges())
      pairs.push_back({h[2], h[3]});
    Newton = std::make_unique<NewtonState>();
    Newton->Hessian = detail::BlockSparseMatrix(nv, pairs);
  }
  detail::BlockSparseMatrix& H = Newton->Hessian;

  // The data term's Gauss-Newton model at the current x: vertex v's squared distance near x is
  // the quadric Q_v(d) = D^2 + 2 b.d + d^T M d of DistanceField::sampleToPlanes (its tangent
  // planes held, as in ICP; for the distance to the points: (D + g.d)^2, g the field's
  // gradient), and its penalty c/2 Q_v with c = w / voxel (squared distance) or w / max(D, voxel)
  // (the paper's D, reweighted: the fixed point minimises the sum of D). Steps are judged by how
  // much of the decrease the model promises E delivers (Levenberg-Marquardt).
  const bool planes = Options.distanceMeasure == DistanceMeasure::Planes && !FrameNormals.empty();
  std::vector<PlaneQuadric> quadric(nv);
  std::vector<double> c(nv);
  auto linearise = [&]()
  {
    forEachVertex(nv, [&](std::size_t v) { // each vertex writes only its own entries
      c[v] = 0;
      quadric[v] = PlaneQuadric();
      if (!field || weights[v] == 0)
        return;
      DistanceSample s;
      if (planes)
      {
        s = field->sampleToPlanes(&x[3 * v], FrameNormals.data(), PlaneReach * Voxel, &Cells[v],
                                  &quadric[v]);
      }
      else
      {
        s = sampleData(*field, &x[3 * v], v);
        quadric[v] = quadricOf(s);
      }
      c[v] = scale * mass[v] * weights[v] /
             (Options.squaredDistance ? Voxel : std::max(s.distance, Voxel));
    });
  };

  std::vector<double> trial(x.size()), dataAtTrial(nv, 0.0), vertexDamping(nv, 0.0);
  int decisions = 0;
  Eigen::VectorXd gradient(n);
  double damping = 1e-4; // Levenberg damping, relative to the mean diagonal
  int iteration = 0;
  for (; iteration < Options.maxIterations; ++iteration)
  {
    linearise();
    // Gauss-Newton matrix and gradient: each cloth term 1/2 k r^2 gives k grad(r) grad(r)^T,
    // each data term c M.
    H.setZero();
    gradient.setZero();
    double clothAtX = 0;
    auto& slots = Newton->TermSlots;
    const bool haveSlots = !slots.empty();
    std::size_t next = 0;
    Cloth.forEachTerm(x.data(),
                      [&](const ClothTerm& t)
                      {
                        clothAtX += t.energy;
                        for (int a = 0; a < t.count; ++a)
                        {
                          for (int k = 0; k < 3; ++k)
                            gradient[3 * t.vertex[a] + k] +=
                                t.weight * t.residual * t.gradient[a][k];
                          for (int b = a; b < t.count; ++b)
                          {
                            if (!haveSlots)
                              slots.push_back(H.slotOf(t.vertex[a], t.vertex[b]));
                            H.addOuter(slots[next++], t.gradient[a], t.gradient[b], t.weight);
                          }
                        }
                      });
    for (std::size_t v = 0; v < nv; ++v)
      if (c[v] != 0)
      {
        const PlaneQuadric& q = quadric[v];
        const double block[9] = {c[v] * q.matrix[0], c[v] * q.matrix[1], c[v] * q.matrix[2],
                                 c[v] * q.matrix[1], c[v] * q.matrix[3], c[v] * q.matrix[4],
                                 c[v] * q.matrix[2], c[v] * q.matrix[4], c[v] * q.matrix[5]};
        H.addToDiagonalBlock(static_cast<std::int64_t>(v), block);
        for (int k = 0; k < 3; ++k)
          gradient[static_cast<Eigen::Index>(3 * v + k)] += c[v] * q.vector[k];
      }
    const double energyAtX = clothAtX + distanceEnergy(x.data(), field, weights, nullptr);
    const double meanDiagonal = std::max(H.diagonal().mean(), 1e-300);

    // One preconditioner per iteration, at the damping of its first attempt; later attempts
    // (more damping) reuse it. Damping is global (Levenberg) plus per vertex: where a vertex's
    // data term keeps breaking the model's promise (it sits on a ridge of the field, between
    // two parts of the data), that vertex alone is damped, so it does not stall the others.
    bool accepted = false, converged = false;
    for (int attempt = 0; attempt < 12 && !accepted; ++attempt)
    {
      Eigen::VectorXd shift(n);
      for (std::size_t v = 0; v < nv; ++v)
        shift.segment<3>(static_cast<Eigen::Index>(3 * v))
            .setConstant(damping * meanDiagonal + vertexDamping[v]);
      H.addToDiagonal(shift);
      if (attempt == 0)
      {
        const auto P = H.traceMatrix();
        if (!Newton->Analysed)
        {
          Newton->Preconditioner.analyzePattern(P);
          Newton->Analysed = true;
        }
        Newton->Preconditioner.factorize(P);
      }
      int cgIterations = 0;
      const Eigen::VectorXd step =
          Newton->Preconditioner.info() == Eigen::Success
              ? conjugateGradients(
                    H.matrix(), -gradient,
                    [&](const Eigen::VectorXd& r) { return Newton->precondition(r); },
                    StepTolerance, 200, cgIterations)
              : Eigen::VectorXd(-gradient.cwiseQuotient(shift));
      H.addToDiagonal(-shift);
      for (std::size_t i = 0; i < x.size(); ++i)
        trial[i] = x[i] + step[static_cast<Eigen::Index>(i)];
      // The decrease the quadratic model promises: -(gradient.step + step.H.step / 2).
      const double predicted =
          -(gradient.dot(step) + 0.5 * step.dot(H.matrix().selfadjointView<Eigen::Lower>() * step));
      const double actual =
          energyAtX - Cloth.value(trial.data()) -
          distanceEnergy(trial.data(), field, weights, nullptr, dataAtTrial.data());
      if (predicted > 0 && actual > 0.1 * predicted)
      {
        accepted = true;
        x.swap(trial);
        if (actual > 0.75 * predicted)
          damping = std::max(damping * 0.3, 1e-9);
        for (double& d : vertexDamping)
          d *= 0.3;
        converged = actual <= Options.tolerance * std::abs(energyAtX) ||
                    step.cwiseAbs().maxCoeff() <= SettledStep * Voxel;
        continue;
      }
      // Which vertices broke the promise: their data energy at the trial against the model's.
      const double shortfall = predicted - actual;
      bool blamed = false;
      for (std::size_t v = 0; v < nv && shortfall > 0; ++v)
      {
        if (c[v] == 0)
          continue;
        const double promised = 0.5 * c[v] * quadric[v](&step[static_cast<Eigen::Index>(3 * v)]);
        if (dataAtTrial[v] - promised > 0.2 * shortfall)
        {
          vertexDamping[v] = 10 * std::max(vertexDamping[v], c[v]);
          blamed = true;
        }
      }
      if (!blamed)
        damping *= 10;
    }
    // Settled: decide the normal test again at the new shape (at most twice a frame); go on only
    // if that changed which vertices see the data.
    if (accepted && converged && decisions < 2 && decideWeights(x) > 0)
    {
      ++decisions;
      continue;
    }
    if (!accepted || converged)
      break; // no step decreases E any more, or the last one barely moved: a (local) minimum
  }
  return iteration + 1;
}

void Tracker::alignRigidly(std::vector<double>& x, const DistanceField& field,
                           const std::vector<double>& weights)
{
  // Point-to-plane ICP of the whole mesh: minimise sum_v m_v D_v(R x_v + t)^2 over a rotation R
  // and a translation t, with each vertex's quadric (its tangent planes held) as its model.
  const std::size_t nv = Mesh.numberOfVertices();
  const auto& mass = Cloth.vertexMass();
  const bool planes = Options.distanceMeasure == DistanceMeasure::Planes && !FrameNormals.empty();
  for (int iteration = 0; iteration < RigidIterations; ++iteration)
  {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    double total = 0;
    for (std::size_t v = 0; v < nv; ++v)
      if (weights[v] != 0)
      {
        centre += mass[v] * Eigen::Vector3d(&x[3 * v]);
        total += mass[v];
      }
    if (total <= 0)
      return;
    centre /= total;
    // Rotations act on r / radius so that both halves of the 6x6 system have the same units and
    // the solve rounds alike at any scale of the data.
    double radius = 0;
    for (std::size_t v = 0; v < nv; ++v)
      if (weights[v] != 0)
        radius += mass[v] * (Eigen::Vector3d(&x[3 * v]) - centre).squaredNorm();
    radius = std::sqrt(radius / total);
    if (!(radius > 0))
      return;
    Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    double before = 0;
    for (std::size_t v = 0; v < nv; ++v)
    {
      if (weights[v] == 0)
        continue;
      PlaneQuadric q;
      if (planes)
        field.sampleToPlanes(&x[3 * v], FrameNormals.data(), PlaneReach * Voxel, &Cells[v], &q);
      else
      {
        q = quadricOf(sampleData(field, &x[3 * v], v));
      }
      before += mass[v] * q.constant;
      Eigen::Matrix3d M;
      M << q.matrix[0], q.matrix[1], q.matrix[2], q.matrix[1], q.matrix[3], q.matrix[4],
          q.matrix[2], q.matrix[4], q.matrix[5];
      const Eigen::Vector3d g(q.vector[0], q.vector[1], q.vector[2]);
      // d = w x r + t (r = x - centre): d = J [w; t] with J = [-[r]x, I].
      const Eigen::Vector3d r = (Eigen::Vector3d(&x[3 * v]) - centre) / radius;
      Eigen::Matrix<double, 3, 6> J;
      J << 0, r.z(), -r.y(), 1, 0, 0, -r.z(), 0, r.x(), 0, 1, 0, r.y(), -r.x(), 0, 0, 0, 1;
      A += mass[v] * J.transpose() * M * J;
      b += mass[v] * J.transpose() * g;
    }
    // Move only along the motions the data pins down: on a flat or round part, sliding along
    // the surface changes no plane distance, and a step there would follow the noise.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(A);
    const double largest = eigen.eigenvalues()[5];
    if (!(largest > 0))
      return;
    Eigen::Matrix<double, 6, 1> step = Eigen::Matrix<double, 6, 1>::Zero();
    for (int i = 0; i < 6; ++i)
      if (eigen.eigenvalues()[i] >= RigidConstrained * largest)
        step -= eigen.eigenvectors().col(i) *
                (eigen.eigenvectors().col(i).dot(b) / eigen.eigenvalues()[i]);
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
    double after = 0;
    for (std::size_t v = 0; v < nv; ++v)
      if (weights[v] != 0)
      {
        const DistanceSample s = sampleData(field, &trial[3 * v], v);
        after += mass[v] * s.distance * s.distance;
      }
    if (!(after < before))
      return;
    x.swap(trial);
  }
}

FrameResult Tracker::track(const double* points, std::size_t count, const float* normals)
{
  const auto start = std::chrono::steady_clock::now();
  const std::size_t nv = Mesh.numberOfVertices();
  const double L = Cloth.lengthScale();
  FrameResult result;
  result.frozen.assign(nv, 0);
  result.rejected.assign(nv, 0);
  result.residual.assign(nv, -1.0);

  // The frame's distance field and target normals.
  DistanceField field;
  FrameNormals.clear();
  const bool haveData = count > 0;
  if (haveData)
  {
    DistanceFieldOptions fieldOptions;
    fieldOptions.voxelSize = Voxel;
    fieldOptions.bandWidth = Options.bandWidth > 0 ? Options.bandWidth : 4 * Voxel;
    fieldOptions.lazy = true; // only the voxels around the vertices are ever needed
    field.build(points, count, fieldOptions);
    if (Options.normalTestDegrees < 180 || Options.distanceMeasure == DistanceMeasure::Planes)
      FrameNormals = normals ? std::vector<float>(normals, normals + 3 * count)
                             : estimateNormals(points, count);
  }

  if (Options.restUpdate > 0)
    Cloth.setRestState(History.empty() ? TemplateRest
                                       : ClothRestState::blend(
                                             TemplateRest, Cloth.restStateOf(History.back().data()),
                                             Options.restUpdate));

  // Data weights: the normal test and the outlier cut-off, decided at a given shape.
  std::vector<double> weights(nv, haveData ? 1.0 : 0.0);
  Cells.assign(nv, VoxelCell{}); // a new field
  // Returns how many vertices changed side.
  auto decideWeights = [&](const std::vector<double>& x) -> std::size_t
  {
    if (!haveData)
      return 0;
    std::size_t changed = 0;
    std::vector<double> vertexNormals(3 * nv);
    Mesh.vertexNormals(x.data(), vertexNormals.data());
    const double cosLimit = std::cos(Options.normalTestDegrees * Pi / 180.0);
    for (std::size_t v = 0; v < nv; ++v)
    {
      const DistanceSample s = field.sample(&x[3 * v], &Cells[v]);
      bool keep = Options.outlierDistance <= 0 || s.distance <= Options.outlierDistance;
      if (keep && Options.normalTestDegrees < 180)
      {
        const float* n = &FrameNormals[3 * static_cast<std::size_t>(s.nearest)];
        const double agreement = vertexNormals[3 * v] * n[0] + vertexNormals[3 * v + 1] * n[1] +
                                 vertexNormals[3 * v + 2] * n[2];
        keep = agreement >= cosLimit;
      }
      changed += (weights[v] != 0) != keep;
      weights[v] = keep ? 1.0 : 0.0;
      result.rejected[v] = keep ? 0 : 1;
    }
    return changed;
  };

  Objective objective{this, haveData ? &field : nullptr, &weights};

  // Start: the template for the first frame; afterwards motion prediction. Without data
  // there is nothing to search the predictions against: keep moving as before (linear).
  std::vector<double> x = predict();
  if (!haveData && History.size() >= 2)
  {
    const auto& last = History.back();
    const auto& before = History[History.size() - 2];
    for (std::size_t i = 0; i < x.size(); ++i)
      x[i] = 2 * last[i] - before[i];
  }
  else if (!History.empty() && Options.motionPrediction)
  {
    decideWeights(x);
    const std::vector<double>& last = History.back();
    std::vector<std::vector<double>> targets;
    if (History.size() >= 2)
    {
      const auto& before = History[History.size() - 2];
      std::vector<double> linear(last.size());
      for (std::size_t i = 0; i < last.size(); ++i)
        linear[i] = 2 * last[i] - before[i];
      targets.push_back(std::move(linear));
      if (History.size() >= 3)
      {
        const auto& earlier = History[History.size() - 3];
        std::vector<double> quadratic(last.size());
        for (std::size_t i = 0; i < last.size(); ++i)
          quadratic[i] = 3 * last[i] - 3 * before[i] + earlier[i];
        targets.push_back(std::move(quadratic));
      }
    }
    double best = objective(last.data(), nullptr);
    std::vector<double> candidate(last.size());
    for (const auto& target : targets)
      for (double alpha : {0.25, 0.5, 0.75, 1.0, 1.25, 1.5})
      {
        for (std::size_t i = 0; i < last.size(); ++i)
          candidate[i] = last[i] + alpha * (target[i] - last[i]);
        const double e = objective(candidate.data(), nullptr);
        if (e < best)
        {
          best = e;
          x = candidate;
        }
      }
  }
  decideWeights(x);
  if (haveData && Options.rigidAlignment)
  {
    alignRigidly(x, field, weights);
    decideWeights(x);
  }

  if (!haveData)
  {
    result.emptyFrame = true;
  }

  if (Options.solver == TrackerSolver::GaussNewton)
  {
    result.iterations = solveGaussNewton(x, haveData ? &field : nullptr, weights, decideWeights);
  }
  else if (Options.solver == TrackerSolver::LBFGS)
  {
    lbfgs_parameter_t parameters;
    lbfgs_parameter_init(&parameters);
    parameters.m = 8;
    parameters.max_iterations = Options.maxIterations;
    parameters.epsilon = 1e-8;
    parameters.past = 5;
    parameters.delta = 0.1 * Options.tolerance;
    parameters.linesearch = LBFGS_LINESEARCH_MORETHUENTE;
    // Two passes: after the first, the normal test is decided again at the new shape.
    for (int pass = 0; pass < 2; ++pass)
    {
      lbfgsfloatval_t fx = 0;
      // Any stop (converged, iteration limit, line-search failure) leaves x at the best point
      // found, which is what the frame gets.
      lbfgs(static_cast<int>(x.size()), x.data(), &fx, evaluateForLbfgs, nullptr, &objective,
            &parameters);
      if (pass == 0)
        decideWeights(x);
    }
    result.iterations = objective.evaluations;
  }
  else
  {
    // The paper's solver: steepest descent with h < 2 / k_max.
    const double kMax = largestCurvature(objective, x, L);
    double h = kMax > 0 ? 1.9 / kMax : L;
    std::vector<double> gradient(x.size()), before;
    // PD: a vertex that barely moves is frozen. The distance term's gradient has the same size
    // everywhere, so a settled vertex keeps stepping but goes nowhere: over a window of
    // iterations, it freezes when its net motion is under a quarter of the path it stepped,
    // and wakes when a neighbour moves steadily (net motion over half its path).
    constexpr int window = 5;
    std::vector<double> anchor = x, path(nv, 0.0);
    std::vector<std::uint8_t> steady(nv, 0);
    std::vector<double> recent; // energies of the last iterations
    int iteration = 0;
    double previous = std::numeric_limits<double>::infinity();
    for (; iteration < Options.maxIterations; ++iteration)
    {
      double e = objective(x.data(), gradient.data());
      // h < 2 / k_max holds for the curvature where it was estimated; where the energy rises
      // anyway, take the step back and halve h.
      int halvings = 0;
      while (e > previous && halvings < 20 && !before.empty())
      {
        h *= 0.5;
        x = before;
        e = objective(x.data(), gradient.data());
        ++halvings;
      }
      previous = e;
      before = x;
      recent.push_back(e);
      if (recent.size() > 10)
      {
        const double gained = recent[recent.size() - 11] - e;
        // Steepest descent's steps are short (h < 2 / k_max), so its gains are small long before
        // it settles: it stops at a tenth of the relative gain the other solvers stop at.
        if (gained <= 0.1 * Options.tolerance * std::abs(e))
          break;
      }
      for (std::size_t v = 0; v < nv; ++v)
      {
        if (Options.provisionalDetermination && result.frozen[v])
          continue;
        double step2 = 0;
        for (int k = 0; k < 3; ++k)
        {
          const double d = h * gradient[3 * v + k];
          x[3 * v + k] -= d;
          step2 += d * d;
        }
        path[v] += std::sqrt(step2);
      }
      if (Options.provisionalDetermination && iteration % window == window - 1)
      {
        for (std::size_t v = 0; v < nv; ++v)
        {
          double d2 = 0;
          for (int k = 0; k < 3; ++k)
            d2 += (x[3 * v + k] - anchor[3 * v + k]) * (x[3 * v + k] - anchor[3 * v + k]);
          const double net = std::sqrt(d2);
          steady[v] = path[v] > 0 && net > 0.5 * path[v];
          if (!result.frozen[v] && path[v] > 0 && net < 0.25 * path[v])
            result.frozen[v] = 1;
        }
        for (std::size_t v = 0; v < nv; ++v)
          if (result.frozen[v])
            for (std::int64_t u : Mesh.neighbours(v))
              if (steady[u])
              {
                result.frozen[v] = 0; // a neighbour moves: wake up
                break;
              }
        anchor = x;
        std::fill(path.begin(), path.end(), 0.0);
      }
      if (iteration % 25 == 24)
        decideWeights(x);
    }
    result.iterations = iteration + 1;
  }

  result.positions = x;
  energy(x.data(), haveData ? &field : nullptr, weights, nullptr, &result.internalEnergy,
         &result.distanceEnergy);
  if (haveData)
    for (std::size_t v = 0; v < nv; ++v)
      result.residual[v] = sampleData(field, &x[3 * v], v).distance;
  // Both index this frame's points and field, which end here (energy() called from outside
  // must not meet them with another field).
  Cells.clear();
  FrameNormals.clear();
  History.push_back(x);
  if (History.size() > 3)
    History.erase(History.begin());
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

} // namespace dp
