// SPDX-License-Identifier: BSD-3-Clause
#include "dp/detail/FrameSurface.h"

#include "dp/geometry/NormalEstimation.h"
#include "dp/geometry/SurfaceLocator.h"
#include "dp/support/KdTree.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace dp
{
namespace
{

double dot(const double* a, const double* b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// The nearest points a point query averages over.
constexpr std::size_t PointNeighbours = 12;
// A point query's weights (Gaussians of the distance from the line) must add up to this for the
// crossing to count fully; less gives a smaller weight.
constexpr double FullWeight = 1.5;
// Line steps of a mesh query at most; it stops once a step is under this share of the reach.
constexpr int MeshSteps = 6;
constexpr double StepTolerance = 1e-3;
// A crossing's point must lie this close to the surface (a share of the reach).
constexpr double OnSurface = 1e-2;
// orientAgainst asks at most this many of the mesh's vertices.
constexpr std::size_t OrientationVotes = 4096;

std::vector<std::int64_t> usableTriangles(const MeshSurface& s)
{
  std::vector<std::int64_t> kept;
  kept.reserve(3 * s.triangleCount);
  for (std::size_t t = 0; t < s.triangleCount; ++t)
  {
    const std::int64_t* v = s.triangles + 3 * t;
    for (int k = 0; k < 3; ++k)
      if (v[k] < 0 || static_cast<std::size_t>(v[k]) >= s.vertices)
        throw std::invalid_argument("triangle " + std::to_string(t) + " uses vertex " +
                                    std::to_string(v[k]) + " of " + std::to_string(s.vertices));
    if (v[0] != v[1] && v[1] != v[2] && v[0] != v[2])
      kept.insert(kept.end(), v, v + 3);
  }
  return kept;
}

// Refuses a frame without points or with a coordinate that is not finite.
void checkPoints(const double* points, std::size_t count, const char* what)
{
  if (count == 0)
    throw std::invalid_argument(std::string("the frame has no ") + what);
  for (std::size_t i = 0; i < 3 * count; ++i)
    if (!std::isfinite(points[i]))
      throw std::invalid_argument(std::string(what) + " " + std::to_string(i / 3) +
                                  " has a coordinate that is not finite");
}

} // namespace

struct FrameSurface::Data
{
  // A mesh frame.
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;
  std::optional<SurfaceLocator> locator;
  std::vector<double> faceNormals; // unit, 3 per triangle
  // A point frame.
  std::unique_ptr<support::KdTree> tree;
  std::vector<float> normals;
  bool oriented = true;
  double sign = 1; // -1: the data's orientation is turned around

  Crossing crossMesh(const double p[3], const double n[3], double reach,
                     double minimumCosine) const;
  Crossing crossPoints(const double p[3], const double n[3], double reach, double minimumCosine,
                       double radius) const;
  // The data's unit normal nearest q, and its cosine with n (NaN: nothing within reach).
  double facing(const double q[3], const double n[3], double reach) const;
};

FrameSurface::FrameSurface(std::unique_ptr<Data> data) : D(std::move(data)) {}
FrameSurface::FrameSurface(FrameSurface&&) noexcept = default;
FrameSurface& FrameSurface::operator=(FrameSurface&&) noexcept = default;
FrameSurface::~FrameSurface() = default;

FrameSurface FrameSurface::ofMesh(const MeshSurface& mesh)
{
  checkPoints(mesh.positions, mesh.vertices, "vertex");
  auto d = std::make_unique<Data>();
  d->positions.assign(mesh.positions, mesh.positions + 3 * mesh.vertices);
  d->triangles = usableTriangles(mesh);
  if (d->triangles.empty())
    throw std::invalid_argument("the frame's mesh has no triangle");
  d->locator.emplace(d->triangles, mesh.vertices, d->positions.data());
  const auto& tri = d->triangles;
  d->faceNormals.resize(tri.size());
  for (std::size_t t = 0; t < tri.size(); t += 3)
  {
    const double* a = &d->positions[3 * tri[t]];
    const double* b = &d->positions[3 * tri[t + 1]];
    const double* c = &d->positions[3 * tri[t + 2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double* m = &d->faceNormals[t];
    m[0] = u[1] * v[2] - u[2] * v[1];
    m[1] = u[2] * v[0] - u[0] * v[2];
    m[2] = u[0] * v[1] - u[1] * v[0];
    const double length = std::sqrt(dot(m, m));
    for (int k = 0; k < 3; ++k)
      m[k] = length > 0 ? m[k] / length : 0.0;
  }
  return FrameSurface(std::move(d));
}

FrameSurface FrameSurface::ofPoints(const double* points, std::size_t count, const float* normals)
{
  checkPoints(points, count, "point");
  auto d = std::make_unique<Data>();
  d->positions.assign(points, points + 3 * count);
  d->oriented = normals != nullptr;
  d->normals = normals ? std::vector<float>(normals, normals + 3 * count)
                       : unorientedNormals(d->positions.data(), count);
  d->tree = std::make_unique<support::KdTree>(d->positions.data(), count);
  return FrameSurface(std::move(d));
}

std::size_t FrameSurface::size() const
{
  return D->positions.size() / 3;
}

double FrameSurface::Data::facing(const double q[3], const double n[3], double reach) const
{
  if (locator)
  {
    const SurfaceLocator::Hit hit = locator->closest(q, reach);
    return hit.triangle < 0 ? NAN : dot(&faceNormals[3 * hit.triangle], n);
  }
  if (!tree)
    return NAN;
  double d2 = 0;
  const std::uint32_t i = tree->nearest(q, &d2);
  if (d2 > reach * reach)
    return NAN;
  const double m[3] = {normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]};
  return dot(m, n);
}

bool FrameSurface::orientAgainst(const double* positions, const double* normals, std::size_t count,
                                 double reach)
{
  if (!D->oriented || count == 0)
    return false;
  const std::size_t stride = std::max<std::size_t>(1, count / OrientationVotes);
  long long votes = 0;
  for (std::size_t i = 0; i < count; i += stride)
  {
    const double c = D->facing(positions + 3 * i, normals + 3 * i, reach);
    votes += std::isnan(c) ? 0 : (c * D->sign > 0 ? 1 : -1);
  }
  if (votes >= 0)
    return false;
  D->sign = -D->sign;
  return true;
}

FrameSurface::Crossing FrameSurface::Data::crossMesh(const double p[3], const double n[3],
                                                     double reach, double minimumCosine) const
{
  double s = 0, q[3] = {p[0], p[1], p[2]};
  std::int64_t hint = -1;
  for (int step = 0; step < MeshSteps; ++step)
  {
    const SurfaceLocator::Hit hit = locator->closest(q, 2 * reach, hint);
    if (hit.triangle < 0)
      return {};
    hint = hit.triangle;
    double m[3];
    for (int k = 0; k < 3; ++k)
      m[k] = sign * faceNormals[3 * hit.triangle + k];
    const double c = dot(m, n);
    if (c < minimumCosine)
      return {};
    const double e[3] = {hit.point[0] - q[0], hit.point[1] - q[1], hit.point[2] - q[2]};
    const double along = dot(e, m) / c;
    if (std::abs(along) < StepTolerance * reach)
    {
      // q is on the plane of its closest triangle: a crossing if it is on the surface too, not
      // on the plane of a triangle at the rim of a hole.
      if (hit.squaredDistance > std::pow(OnSurface * reach, 2))
        return {};
      return {true, s, 1.0};
    }
    s += along;
    if (std::abs(s) > reach)
      return {};
    for (int k = 0; k < 3; ++k)
      q[k] = p[k] + s * n[k];
  }
  return {};
}

FrameSurface::Crossing FrameSurface::Data::crossPoints(const double p[3], const double n[3],
                                                       double reach, double minimumCosine,
                                                       double radius) const
{
  Crossing out;
  if (!tree)
    return out;
  std::uint32_t index[PointNeighbours];
  double d2[PointNeighbours];
  double s = 0;
  for (int pass = 0; pass < 2; ++pass)
  {
    const double q[3] = {p[0] + s * n[0], p[1] + s * n[1], p[2] + s * n[2]};
    const std::size_t found = tree->nearest(q, PointNeighbours, index, d2);
    double sum = 0, weights = 0;
    for (std::size_t j = 0; j < found; ++j)
    {
      const double* x = &positions[3 * index[j]];
      double m[3] = {normals[3 * index[j]] * sign, normals[3 * index[j] + 1] * sign,
                     normals[3 * index[j] + 2] * sign};
      double c = dot(m, n);
      if (!oriented && c < 0)
      {
        c = -c;
        for (double& v : m)
          v = -v;
      }
      if (c < minimumCosine)
        continue;
      const double e[3] = {x[0] - q[0], x[1] - q[1], x[2] - q[2]};
      const double normal = dot(e, n);
      const double tangential2 = std::max(0.0, dot(e, e) - normal * normal);
      const double w = std::exp(-tangential2 / (radius * radius));
      const double ep[3] = {x[0] - p[0], x[1] - p[1], x[2] - p[2]};
      sum += w * dot(ep, m) / c;
      weights += w;
    }
    if (!(weights > 1e-3))
      return out;
    s = sum / weights;
    if (std::abs(s) > reach)
      return out;
    out.weight = std::min(1.0, weights / FullWeight);
  }
  out.found = true;
  out.distance = s;
  return out;
}

FrameSurface::Crossing FrameSurface::cross(const double p[3], const double n[3], double reach,
                                           double minimumCosine, double radius) const
{
  return D->locator ? D->crossMesh(p, n, reach, minimumCosine)
                    : D->crossPoints(p, n, reach, minimumCosine, radius);
}

} // namespace dp
