// SPDX-License-Identifier: BSD-3-Clause
#include "dp/geometry/MeshDistortion.h"

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/SurfaceLocator.h"
#include "dp/geometry/TriangleMesh.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace dp
{
namespace
{

// A surface to measure against: its triangles without repeated vertices, the closest-point
// search over them, and its vertex normals.
class Target
{
public:
  explicit Target(const MeshSurface& s)
      : Mesh(usableTriangles(s), s.vertices), Locator(Mesh, s.positions), Normals(3 * s.vertices)
  {
    Mesh.vertexNormals(s.positions, Normals.data());
  }

  // |e|^2 and (e . n)^2 from p to the closest point of the surface.
  void errors(const double* p, double& d1, double& d2) const
  {
    const SurfaceLocator::Hit hit = Locator.closest(p);
    double n[3] = {0, 0, 0}, e[3];
    for (int c = 0; c < 3; ++c)
    {
      for (int k = 0; k < 3; ++k)
        n[c] += hit.barycentric[k] *
                Normals[3 * static_cast<std::size_t>(Mesh.triangles()[3 * hit.triangle + k]) + c];
      e[c] = p[c] - hit.point[c];
    }
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const double along = length > 0 ? (e[0] * n[0] + e[1] * n[1] + e[2] * n[2]) / length : 0;
    d1 = hit.squaredDistance;
    d2 = length > 0 ? along * along : d1;
  }

private:
  static std::vector<std::int64_t> usableTriangles(const MeshSurface& s)
  {
    std::vector<std::int64_t> kept;
    for (std::size_t t = 0; t < s.triangleCount; ++t)
    {
      const std::int64_t* v = s.triangles + 3 * t;
      if (v[0] != v[1] && v[1] != v[2] && v[0] != v[2])
        kept.insert(kept.end(), v, v + 3);
    }
    return kept;
  }
  TriangleMesh Mesh;
  SurfaceLocator Locator;
  std::vector<double> Normals;
};

// Mean squared errors of `from`'s samples against `to`, summed in fixed blocks (the same sums
// for any thread count).
void meanErrors(const PointCloud& from, const Target& to, double& d1, double& d2)
{
  const std::size_t n = from.numberOfPoints(), block = 1024;
  const std::size_t blocks = (n + block - 1) / block;
  std::vector<double> sums1(blocks, 0), sums2(blocks, 0);
  tbb::parallel_for(std::size_t(0), blocks,
                    [&](std::size_t b)
                    {
                      for (std::size_t i = b * block; i < std::min(n, (b + 1) * block); ++i)
                      {
                        double e1, e2;
                        to.errors(&from.points[3 * i], e1, e2);
                        sums1[b] += e1;
                        sums2[b] += e2;
                      }
                    });
  d1 = d2 = 0;
  for (std::size_t b = 0; b < blocks; ++b)
  {
    d1 += sums1[b];
    d2 += sums2[b];
  }
  d1 /= static_cast<double>(n);
  d2 /= static_cast<double>(n);
}

double psnr(double peak, double mse)
{
  return mse > 0 ? 10 * std::log10(peak * peak / mse) : std::numeric_limits<double>::infinity();
}
} // namespace

double MeshDistortion::d1Psnr() const
{
  return psnr(peak, d1);
}
double MeshDistortion::d2Psnr() const
{
  return psnr(peak, d2);
}

MeshDistortion meshDistortion(const MeshSurface& reference, const MeshSurface& test,
                              std::size_t samples)
{
  const PointCloud a = sampleMeshSurface(reference, samples);
  const PointCloud b = sampleMeshSurface(test, samples);
  if (a.numberOfPoints() == 0 || b.numberOfPoints() == 0)
    throw std::invalid_argument(a.numberOfPoints() == 0 ? "the reference mesh has no area"
                                                        : "the mesh measured has no area");
  double ab1, ab2, ba1, ba2;
  meanErrors(a, Target(test), ab1, ab2);
  meanErrors(b, Target(reference), ba1, ba2);
  MeshDistortion d;
  d.d1 = std::max(ab1, ba1);
  d.d2 = std::max(ab2, ba2);
  d.peak = boundingBoxDiagonal(reference.positions, reference.vertices);
  d.samples = samples;
  return d;
}

} // namespace dp
