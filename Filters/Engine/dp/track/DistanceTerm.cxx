// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/DistanceTerm.h"

#include "dp/track/RobustKernel.h"

#include "dp/geometry/SurfaceLocator.h"

#include "dp/support/Parallel.h"

#include <cmath>

namespace dp
{
namespace
{
constexpr double Pi = 3.14159265358979323846;
// Planes: how far from a data point (in voxels) its tangent plane stands for the surface.
constexpr double PlaneReach = 2.0;
// Reciprocal test: how much nearer (in voxels) another part of the mesh may be to a vertex's
// nearest point before the vertex no longer answers for it.
constexpr double ReciprocalTolerance = 2.0;

double squaredDistance(const double* a, const double* b)
{
  const double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
  return d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

// Whether the vertex at `vertex` answers for its nearest point `point`: no part of the surface
// is nearer to the point by more than `tolerance` (else the point is another part's data, and
// the vertex's own surface is unseen: the back of a body seen from the front).
bool answersForItsPoint(const SurfaceLocator& surface, const double* vertex, const double* point,
                        double tolerance)
{
  const double toVertex = std::sqrt(squaredDistance(vertex, point));
  if (toVertex <= tolerance)
    return true;
  const SurfaceLocator::Hit hit = surface.closest(point, toVertex - tolerance);
  return hit.triangle < 0;
}

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
} // namespace

DistanceTerm::DistanceTerm(const FrameData& frame, const TriangleMesh& mesh,
                           const std::vector<double>& mass, double lengthScale,
                           const DistanceTermOptions& options)
    : Frame(frame), Mesh(mesh), Mass(mass), Options(options), Scale(options.weight / lengthScale),
      Voxel(frame.voxelSize()), Weights(mesh.numberOfVertices(), frame.empty() ? 0.0 : 1.0),
      Cells(mesh.numberOfVertices()), Quadric(mesh.numberOfVertices()),
      Stiffness(mesh.numberOfVertices(), 0.0)
{
}

DistanceSample DistanceTerm::sample(const double* p, std::size_t v) const
{
  if (Options.measure == DistanceMeasure::Planes)
    return Frame.field().sampleToPlanes(p, Frame.normals(), PlaneReach * Voxel, &Cells[v]);
  return Frame.field().sample(p, &Cells[v]);
}

double DistanceTerm::penalty(double distance) const
{
  return Options.squared ? 0.5 * distance * distance / Voxel : distance;
}

void DistanceTerm::vertexValues(const double* x, double* values) const
{
  forEachIndex(Mass.size(),
               [&](std::size_t v)
               {
                 values[v] = 0;
                 if (Weights[v] == 0)
                   return;
                 values[v] = Scale * Mass[v] * Weights[v] * penalty(sample(x + 3 * v, v).distance);
               });
}

double DistanceTerm::evaluate(const double* x, double* gradient) const
{
  if (Frame.empty())
    return 0;
  // Vertices in parallel, each writing only its own entries; the sum is taken afterwards in
  // vertex order, so any thread count gives the same bits.
  std::vector<double> values(Mass.size(), 0.0);
  forEachIndex(Mass.size(),
               [&](std::size_t v)
               {
                 if (Weights[v] == 0)
                   return;
                 const DistanceSample s = sample(x + 3 * v, v);
                 const double w = Scale * Mass[v] * Weights[v];
                 values[v] = w * penalty(s.distance);
                 if (gradient)
                 {
                   const double slope = Options.squared ? s.distance / Voxel : 1.0;
                   for (int k = 0; k < 3; ++k)
                     gradient[3 * v + k] += w * slope * s.gradient[k];
                 }
               });
  double e = 0;
  for (double value : values)
    e += value;
  return e;
}

double DistanceTerm::addModel(const double* x, support::BlockSparseMatrix& hessian,
                              double* gradient) const
{
  const std::size_t nv = Mass.size();
  const bool planes = Options.measure == DistanceMeasure::Planes;
  // Vertex v's squared distance near x is the quadric Q_v(d) = D^2 + 2 b.d + d^T M d (its tangent
  // planes held, as in ICP; for the distance to the points: (D + g.d)^2), and its penalty
  // c/2 Q_v with c = w / voxel (squared) or w / max(D, voxel) (the paper's D, reweighted: the
  // fixed point minimises the sum of D).
  std::vector<double> values(nv, 0.0);
  forEachIndex(nv,
               [&](std::size_t v)
               {
                 Stiffness[v] = 0;
                 Quadric[v] = PlaneQuadric();
                 if (Frame.empty() || Weights[v] == 0)
                   return;
                 DistanceSample s;
                 if (planes)
                   s = Frame.field().sampleToPlanes(&x[3 * v], Frame.normals(), PlaneReach * Voxel,
                                                    &Cells[v], &Quadric[v]);
                 else
                 {
                   s = Frame.field().sample(&x[3 * v], &Cells[v]);
                   Quadric[v] = quadricOf(s);
                 }
                 const double w = Scale * Mass[v] * Weights[v];
                 values[v] = w * penalty(s.distance);
                 Stiffness[v] = w / (Options.squared ? Voxel : std::max(s.distance, Voxel));
               });
  double e = 0;
  for (std::size_t v = 0; v < nv; ++v)
  {
    e += values[v];
    const double c = Stiffness[v];
    if (c == 0)
      continue;
    const PlaneQuadric& q = Quadric[v];
    const double block[9] = {c * q.matrix[0], c * q.matrix[1], c * q.matrix[2],
                             c * q.matrix[1], c * q.matrix[3], c * q.matrix[4],
                             c * q.matrix[2], c * q.matrix[4], c * q.matrix[5]};
    hessian.addToDiagonalBlock(static_cast<std::int64_t>(v), block);
    for (int k = 0; k < 3; ++k)
      gradient[3 * v + k] += c * q.vector[k];
  }
  return e;
}

double DistanceTerm::promised(std::size_t v, const double d[3]) const
{
  return 0.5 * Stiffness[v] * Quadric[v](d);
}

std::size_t DistanceTerm::decide(const double* x)
{
  if (Frame.empty())
    return 0;
  const std::size_t nv = Mass.size();
  std::vector<double> normals(3 * nv);
  Mesh.vertexNormals(x, normals.data());
  const RobustKernel kernel{RobustKernel::Kind::GemanMcClure, Options.robustScale};
  const double cosLimit = std::cos(Options.normalTestDegrees * Pi / 180.0);
  if (Options.reciprocal && !SurfaceBuilt)
    Surface = SurfaceLocator(Mesh, x);
  else if (Options.reciprocal)
    Surface.refit(x);
  SurfaceBuilt = SurfaceBuilt || Options.reciprocal;
  const double tolerance = ReciprocalTolerance * Voxel;
  std::vector<std::uint8_t> changed(nv, 0);
  forEachIndex(
      nv,
      [&](std::size_t v)
      {
        const DistanceSample s = Frame.field().sample(&x[3 * v], &Cells[v]);
        bool keep = Options.outlierDistance <= 0 || s.distance <= Options.outlierDistance;
        if (keep && Options.normalTestDegrees < 180)
        {
          const float* n = Frame.normal(static_cast<std::size_t>(s.nearest));
          keep = normals[3 * v] * n[0] + normals[3 * v + 1] * n[1] + normals[3 * v + 2] * n[2] >=
                 cosLimit;
        }
        // A stray point (a flying pixel, a stray return) is no surface to pull to.
        keep = keep && !Frame.isStray(static_cast<std::size_t>(s.nearest));
        if (keep && Options.reciprocal)
          keep = answersForItsPoint(Surface, &x[3 * v],
                                    Frame.point(static_cast<std::size_t>(s.nearest)), tolerance);
        double weight = keep ? 1.0 : 0.0;
        if (keep && kernel.active())
        {
          const double u = sample(&x[3 * v], v).distance / kernel.scale;
          weight = kernel.weightOfSquaredRatio(u * u);
        }
        changed[v] = (Weights[v] != 0) != keep;
        Weights[v] = weight;
      });
  std::size_t count = 0;
  for (std::uint8_t c : changed)
    count += c;
  return count;
}

} // namespace dp
