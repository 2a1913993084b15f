// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/CoverageTerm.h"

#include "dp/track/RobustKernel.h"

#include "dp/support/Parallel.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace dp
{
namespace
{
constexpr double Pi = 3.14159265358979323846;
// A followed match farther than this from its point (voxels) is searched over the whole surface
// instead: near, the walk's local answer is taken (another part would have to lie within a
// voxel too); far, the part the point was matched to may have moved away from it, and another
// part may be nearer (horse-gallop's passing legs, seed 3: 16.0 and 23.9 mm vertex RMS,
// decimated/noisy, with this limit and without it).
constexpr double TrustedFollow = 1.0;

// The largest change of a coordinate between a and b (n coordinates each).
double largestChange(const double* a, const std::vector<double>& b, std::size_t n)
{
  double largest = 0;
  for (std::size_t i = 0; i < n; ++i)
    largest = std::max(largest, std::abs(a[i] - b[i]));
  return largest;
}

// The closest point of the surface to p: walked to from the last match (`hint`) when `follow`,
// searched for over the whole surface when that finds nothing or lies farther than `trusted`.
// The hint becomes the triangle found, if any.
SurfaceLocator::Hit closestHit(const SurfaceLocator& locator, const double* p, std::int64_t& hint,
                               bool follow, double reach, double trusted)
{
  SurfaceLocator::Hit hit;
  if (follow && hint >= 0)
    hit = locator.follow(p, hint, reach);
  if (hit.triangle < 0 || hit.squaredDistance > trusted * trusted)
    hit = locator.closest(p, reach, hint);
  hint = hit.triangle >= 0 ? hit.triangle : hint;
  return hit;
}

// Whether the mesh's normal at the hit (its vertices' normals interpolated) is within the normal
// test's angle (cosLimit) of the point's normal np.
bool facesLikeThePoint(const SurfaceLocator::Hit& hit, const std::vector<std::int64_t>& tri,
                       const std::vector<double>& normals, const float* np, double cosLimit)
{
  double n[3] = {0, 0, 0};
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k)
      n[k] += hit.barycentric[c] * normals[3 * tri[3 * hit.triangle + c] + k];
  const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  return length > 0 && (n[0] * np[0] + n[1] * np[1] + n[2] * np[2]) >= cosLimit * length;
}
} // namespace

CoverageTerm::CoverageTerm(const SampleView& samples, const TriangleMesh& mesh, double lengthScale,
                           const CoverageOptions& options)
    : Samples(samples), Mesh(mesh), Options(options)
{
  const std::size_t n = samples.count;
  Matches.resize(n);
  Hints.assign(n, -1);
  for (std::size_t i = 0; i < n; ++i)
    Matches[i].point = static_cast<std::uint32_t>(i);
  if (n > 0)
    Scale = options.weight / (static_cast<double>(n) * lengthScale * samples.voxel);
}

bool CoverageTerm::matchesHold(const double* x) const
{
  // Correspondences change only when the mesh moves: skip the search while no vertex has moved
  // a fifth of a voxel since the last one (late, short steps of a solve).
  const std::size_t nv = Mesh.numberOfVertices();
  if (LinearisedAt.size() == 3 * nv)
  {
    const double still = 0.2 * Samples.voxel;
    if (largestChange(x, LinearisedAt, 3 * nv) < still && LinearisedScale == Options.robustScale &&
        LinearisedReach == Options.maxDistance && !WholeSurface)
      return true;
  }
  return false;
}

void CoverageTerm::placeLocator(const double* x)
{
  if (!Built)
    Locator = SurfaceLocator(Mesh, x);
  else
    Locator.refit(x);
  Built = true;
}

void CoverageTerm::linearise(const double* x)
{
  if (Matches.empty() || matchesHold(x))
    return;
  const std::size_t nv = Mesh.numberOfVertices();
  LinearisedAt.assign(x, x + 3 * nv);
  LinearisedScale = Options.robustScale;
  LinearisedReach = Options.maxDistance;
  placeLocator(x);
  std::vector<double> normals(3 * nv);
  Mesh.vertexNormals(x, normals.data());
  const double cosLimit = std::cos(Options.normalTestDegrees * Pi / 180.0);
  const auto& tri = Mesh.triangles();
  const bool follow = Options.followMatches && !WholeSurface;
  WholeSurface = false;
  const double reach = Options.maxDistance > 0 ? Options.maxDistance : HUGE_VAL;
  const double trusted = TrustedFollow * Samples.voxel;
  const RobustKernel kernel{RobustKernel::Kind::GemanMcClure, Options.robustScale};
  forEachIndex(Matches.size(),
               [&](std::size_t i)
               {
                 Match& m = Matches[i];
                 m.triangle = -1;
                 m.weight = 0;
                 const double* p = Samples.point(m.point);
                 const SurfaceLocator::Hit hit =
                     closestHit(Locator, p, Hints[i], follow, reach, trusted);
                 if (hit.triangle < 0)
                   return;
                 if (Options.normalTestDegrees < 180 &&
                     !facesLikeThePoint(hit, tri, normals, Samples.normal(m.point), cosLimit))
                   return;
                 m.triangle = hit.triangle;
                 std::copy(hit.barycentric, hit.barycentric + 3, m.barycentric);
                 m.weight = 1;
                 if (kernel.active())
                   m.weight = kernel.weightOfSquaredRatio(hit.squaredDistance /
                                                          (kernel.scale * kernel.scale));
               });
}

double CoverageTerm::pull(const double* x, const Match& m, Pull& p) const
{
  const auto& tri = Mesh.triangles();
  const double* point = Samples.point(m.point);
  const float* normal = Samples.normal(m.point);
  for (int k = 0; k < 3; ++k)
  {
    p.n[k] = normal[k];
    p.r[k] = -point[k];
    for (int c = 0; c < 3; ++c)
      p.r[k] += m.barycentric[c] * x[3 * tri[3 * m.triangle + c] + k];
  }
  p.along = p.n[0] * p.r[0] + p.n[1] * p.r[1] + p.n[2] * p.r[2];
  p.c = Scale * m.weight;
  const double mu = Options.pointToPoint;
  return 0.5 * p.c *
         (p.along * p.along + mu * (p.r[0] * p.r[0] + p.r[1] * p.r[1] + p.r[2] * p.r[2]));
}

double CoverageTerm::evaluate(const double* x, double* gradient) const
{
  const auto& tri = Mesh.triangles();
  const double mu = Options.pointToPoint;
  double e = 0;
  for (const Match& m : Matches)
  {
    if (m.triangle < 0)
      continue;
    Pull p;
    e += pull(x, m, p);
    if (!gradient)
      continue;
    // d/ds = c (n (n.r) + mu r), spread over the triangle's vertices by the barycentric weights.
    double g[3];
    for (int k = 0; k < 3; ++k)
      g[k] = p.c * (p.n[k] * p.along + mu * p.r[k]);
    for (int v = 0; v < 3; ++v)
      for (int k = 0; k < 3; ++k)
        gradient[3 * tri[3 * m.triangle + v] + k] += m.barycentric[v] * g[k];
  }
  return e;
}

double CoverageTerm::addModel(const double* x, support::BlockSparseMatrix& hessian,
                              double* gradient) const
{
  const auto& tri = Mesh.triangles();
  const double mu = Options.pointToPoint;
  double e = 0;
  for (const Match& m : Matches)
  {
    if (m.triangle < 0)
      continue;
    Pull p;
    e += pull(x, m, p);
    const double *n = p.n, *r = p.r, along = p.along, c = p.c;
    // Block (a, b) of the matrix: c b_a b_b (n n^T + mu I). The diagonal model keeps only
    // c b_a (n n^T + mu I) on each vertex's block: since the b_a are convex weights,
    // |sum_a b_a y_a|^2 <= sum_a b_a |y_a|^2, so it bounds the term from above (a majorizer):
    // a step that lowers it lowers the term, and vertices are not coupled.
    const std::int64_t* t = &tri[3 * m.triangle];
    for (int a = 0; a < 3; ++a)
    {
      for (int k = 0; k < 3; ++k)
        gradient[3 * t[a] + k] += m.barycentric[a] * c * (n[k] * along + mu * r[k]);
      for (int b = a; b < 3; ++b)
      {
        if (DiagonalModel && b != a)
          continue;
        const double w = c * m.barycentric[a] * (DiagonalModel ? 1.0 : m.barycentric[b]);
        if (w == 0)
          continue;
        double block[9];
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            block[3 * i + j] = w * (n[i] * n[j] + (i == j ? mu : 0.0));
        // One add covers (a, b) and (b, a): the matrix is stored symmetric.
        hessian.addBlock(hessian.slotOf(t[a], t[b]), block);
      }
    }
  }
  return e;
}

void CoverageTerm::couplings(std::vector<std::array<std::int64_t, 2>>& pairs) const
{
  if (!DiagonalModel)
    pairs.insert(pairs.end(), Mesh.edges().begin(), Mesh.edges().end());
}

} // namespace dp
