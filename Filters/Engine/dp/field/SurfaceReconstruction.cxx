// SPDX-License-Identifier: BSD-3-Clause
#include "dp/field/SurfaceReconstruction.h"

#include "dp/field/SignedField.h"
#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/HandleRemoval.h"
#include "dp/geometry/IsotropicRemesher.h"
#include "dp/geometry/NormalEstimation.h"
#include "dp/geometry/SurfaceNoise.h"
#include "dp/support/KdTree.h"
#include "dp/support/Vec3.h"

#include <openvdb/openvdb.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace dp
{
namespace
{
using support::cross;
using support::operator+;
using support::operator-;
using support::operator*;
using Vec3 = support::Vec3;
using support::FieldInput;
using support::FineMesh;
using support::meshField;
using support::NarrowBand;

constexpr double VoxelPerSpacing = 1.5; // the fine voxel, in median point spacings

// Keeps the triangles of the largest edge-connected piece (and of the pieces with at least
// `share` of its triangles) and drops unused vertices.
void keepLargePieces(FineMesh& mesh, double share)
{
  const std::size_t nt = mesh.triangles.size();
  std::unordered_map<std::uint64_t, int> edgeOwner;
  edgeOwner.reserve(3 * nt);
  std::vector<int> parent(nt);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int t)
  {
    while (parent[t] != t)
      t = parent[t] = parent[parent[t]];
    return t;
  };
  for (std::size_t t = 0; t < nt; ++t)
    for (int e = 0; e < 3; ++e)
    {
      const auto a = static_cast<std::uint64_t>(mesh.triangles[t][e]);
      const auto b = static_cast<std::uint64_t>(mesh.triangles[t][(e + 1) % 3]);
      const std::uint64_t key = std::min(a, b) << 32 | std::max(a, b);
      auto [it, inserted] = edgeOwner.emplace(key, static_cast<int>(t));
      if (!inserted)
        parent[find(static_cast<int>(t))] = find(it->second);
    }
  std::vector<std::size_t> size(nt, 0);
  for (std::size_t t = 0; t < nt; ++t)
    ++size[find(static_cast<int>(t))];
  const int largest =
      nt == 0 ? -1 : static_cast<int>(std::max_element(size.begin(), size.end()) - size.begin());
  std::vector<int> index(mesh.positions.size(), -1);
  FineMesh kept;
  for (std::size_t t = 0; t < nt; ++t)
  {
    const int piece = find(static_cast<int>(t));
    if (piece != largest && !(share < 1 && static_cast<double>(size[piece]) >=
                                               share * static_cast<double>(size[largest])))
      continue;
    std::array<int, 3> tri{};
    for (int e = 0; e < 3; ++e)
    {
      int& i = index[mesh.triangles[t][e]];
      if (i < 0)
      {
        i = static_cast<int>(kept.positions.size());
        kept.positions.push_back(mesh.positions[mesh.triangles[t][e]]);
      }
      tri[e] = i;
    }
    kept.triangles.push_back(tri);
  }
  mesh = std::move(kept);
}

// Drops the triangles all of whose corners are farther than `reach` from every point: where the
// data end (an open surface), the band's own end, not a surface of the data.
void dropUnsupported(FineMesh& mesh, const FieldInput& in, double reach)
{
  std::vector<char> far(mesh.positions.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.positions.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& range)
                    {
                      for (std::size_t v = range.begin(); v != range.end(); ++v)
                      {
                        double d2 = 0;
                        in.tree.nearest(mesh.positions[v].data(), &d2);
                        far[v] = d2 > reach * reach;
                      }
                    });
  mesh.triangles.erase(std::remove_if(mesh.triangles.begin(), mesh.triangles.end(),
                                      [&](const std::array<int, 3>& t)
                                      { return far[t[0]] && far[t[1]] && far[t[2]]; }),
                       mesh.triangles.end());
}

} // namespace

namespace
{
void validateReconstruction(const double* points, const float* normals, std::size_t count,
                            const ReconstructionOptions& options)
{
  if (count < 16)
    throw std::invalid_argument("surface reconstruction needs at least 16 points, not " +
                                std::to_string(count));
  if (options.targetVertices < MinimumTemplateVertices ||
      options.targetVertices > MaximumTemplateVertices)
    throw std::invalid_argument(
        "surface reconstruction: a target of " + std::to_string(options.targetVertices) +
        " vertices is out of range [" + std::to_string(MinimumTemplateVertices) + ", " +
        std::to_string(MaximumTemplateVertices) + "]");
  if (!(options.voxelSize >= 0 && std::isfinite(options.voxelSize)) ||
      !(options.holeReach >= 0 && std::isfinite(options.holeReach)))
    throw std::invalid_argument("surface reconstruction: voxelSize and holeReach must be finite "
                                "and not negative");
  if (!(options.keptPieceShare > 0 && options.keptPieceShare <= 1))
    throw std::invalid_argument("surface reconstruction: keptPieceShare must be in (0, 1], not " +
                                std::to_string(options.keptPieceShare));
  for (std::size_t i = 0; i < 3 * count; ++i)
    if (!std::isfinite(points[i]) || !std::isfinite(normals[i]))
      throw std::invalid_argument("surface reconstruction: point " + std::to_string(i / 3) +
                                  " has a non-finite coordinate or normal");
}

// The typical sample spacing: the median nearest-neighbour distance of a subsample.
double typicalSpacing(const support::KdTree& tree, const double* points, std::size_t count)
{
  std::vector<double> gaps;
  const std::size_t stride = std::max<std::size_t>(1, count / 2000);
  for (std::size_t i = 0; i < count; i += stride)
  {
    std::uint32_t ids[2];
    double d2[2];
    if (tree.nearest(points + 3 * i, 2, ids, d2) == 2 && d2[1] > 0)
      gaps.push_back(std::sqrt(d2[1]));
  }
  if (gaps.empty())
    throw std::invalid_argument("surface reconstruction: all points coincide");
  std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2),
                   gaps.end());
  return gaps[gaps.size() / 2];
}

// How far the field is smoothed: at the fine voxel (1.5 point spacings) over the nearest few
// points, as clean samples allow; over a layer of noise (thicker than a fifth of the spacing along
// the surface), the voxel at least four times its thickness (finer, the layer's noise leaves
// small handles and folds: on simulated 4- and 10-camera rigs, twice gave genus 30, four 0 to 10)
// and each voxel's planes averaged over a disc of four thicknesses' radius (32 points at least),
// along normals fitted over the same disc (a camera's normals, from neighbouring pixels, are as
// noisy as its depths), turned the way the given ones face.
struct Smoothing
{
  double voxel = 0;
  std::size_t neighbours = 0;
  SurfaceNoise noise;
  std::vector<float> normals; // empty: the given ones
};

constexpr double Pi = 3.141592653589793;
constexpr double AllRound = 0.2;   // the mean normal's length under which data are seen all round
constexpr double NoisyLayer = 0.2; // thickness over surface spacing beyond which it is smoothed
constexpr double NoiseVoxel = 4.0; // the voxel, in thicknesses
constexpr double NoiseReach = 4.0; // the averaging disc's radius, in thicknesses
constexpr std::size_t FewestNoisyNeighbours = 32, MostNeighbours = 96;

bool noisy(const SurfaceNoise& noise)
{
  return noise.thickness > NoisyLayer * noise.surfaceSpacing;
}

Smoothing smoothingFor(const double* points, const float* normals, std::size_t count,
                       double spacing, const SurfaceNoise& noise,
                       const ReconstructionOptions& options)
{
  Smoothing s;
  s.voxel = options.voxelSize > 0 ? options.voxelSize : VoxelPerSpacing * spacing;
  s.neighbours = std::max<std::size_t>(1, std::min(options.neighbours, count));
  s.noise = noise;
  if (!noisy(noise))
    return s;
  if (options.voxelSize <= 0)
    s.voxel = std::max(s.voxel, NoiseVoxel * s.noise.thickness);
  const double radius = std::max(NoiseReach * s.noise.thickness, s.voxel);
  const double share = radius / s.noise.surfaceSpacing;
  s.neighbours = std::clamp<std::size_t>(static_cast<std::size_t>(Pi * share * share),
                                         FewestNoisyNeighbours, std::min(MostNeighbours, count));
  s.normals = unorientedNormals(points, count, s.neighbours);
  for (std::size_t i = 0; i < count; ++i)
  {
    float* n = &s.normals[3 * i];
    const float* given = normals + 3 * i;
    if (n[0] * given[0] + n[1] * given[1] + n[2] * given[2] < 0)
      n[0] = -n[0], n[1] = -n[1], n[2] = -n[2];
  }
  return s;
}

// A closed surface's handles (bridges the noise or the closing made between parts close to each
// other, tunnels in a layer) cut where they are thinnest (HandleRemoval.h), and the surface
// remeshed again over the cut one, evenly shaped at the same count. Returns the cuts.
std::size_t cutHandles(support::RemeshedSurface& remeshed, const ReconstructionOptions& options)
{
  if (!remeshed.closed)
    return 0;
  const auto indexed = [](const support::RemeshedSurface& r)
  {
    support::IndexedMesh m;
    for (std::size_t v = 0; v + 2 < r.positions.size(); v += 3)
      m.positions.push_back({r.positions[v], r.positions[v + 1], r.positions[v + 2]});
    for (std::size_t t = 0; t + 2 < r.triangles.size(); t += 3)
      m.triangles.push_back({static_cast<int>(r.triangles[t]), static_cast<int>(r.triangles[t + 1]),
                             static_cast<int>(r.triangles[t + 2])});
    return m;
  };
  support::IndexedMesh coarse = indexed(remeshed);
  const std::size_t cuts =
      support::removeHandles(coarse, options.handleLoop * boundingBoxDiagonal(remeshed.positions));
  if (cuts == 0)
    return 0;
  remeshed = support::remeshIsotropic(coarse, options.targetVertices);
  // The remeshing of the caps' fans may pinch off a sliver of a piece: the surface is one.
  support::IndexedMesh one = indexed(remeshed);
  keepLargePieces(one, 1.0);
  remeshed.positions.clear();
  remeshed.triangles.clear();
  for (const auto& p : one.positions)
    remeshed.positions.insert(remeshed.positions.end(), p.begin(), p.end());
  for (const auto& t : one.triangles)
    remeshed.triangles.insert(remeshed.triangles.end(), t.begin(), t.end());
  return cuts;
}

// Whether the data's normals cancel out on the whole (their mean shorter than a fifth): a
// surface seen all round, as a rig sees its subject; one seen from one side leans its way (half
// a sphere's mean normal is half as long as each).
bool seenAllRound(const FieldInput& in)
{
  double sum[3] = {0, 0, 0};
  for (std::size_t i = 0; i < in.count; ++i)
    for (int c = 0; c < 3; ++c)
      sum[c] += in.normals[3 * i + c];
  return std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]) <
         AllRound * static_cast<double>(in.count);
}

// Turns the triangles the way the data's normals face (outward for estimateNormals' and a
// scanner's), by a vote of every triangle for the normal of the point nearest to it. (The
// tracker compares the template's normals with the data's.)
void orientLikeTheData(ReconstructedMesh& mesh, const FieldInput& in)
{
  double vote = 0;
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
  {
    Vec3 corner[3];
    for (int e = 0; e < 3; ++e)
    {
      const double* p = &mesh.positions[3 * static_cast<std::size_t>(mesh.triangles[t + e])];
      corner[e] = {p[0], p[1], p[2]};
    }
    const Vec3 n = cross(corner[1] - corner[0], corner[2] - corner[0]);
    const Vec3 centre = (1.0 / 3.0) * (corner[0] + corner[1] + corner[2]);
    const float* m = in.normals + 3 * in.tree.nearest(centre.data());
    vote += n[0] * m[0] + n[1] * m[1] + n[2] * m[2];
  }
  if (vote < 0)
    for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
      std::swap(mesh.triangles[t + 1], mesh.triangles[t + 2]);
}

// The points of a noisy cloud (a sensor's) without its stray returns: isolated points and flying
// pixels off the layer would each grow a patch of surface, or open the outside to the inside.
// Returns how many were left out (none for a clean cloud).
std::size_t leaveOutStrayPoints(const double*& points, const float*& normals, std::size_t& count,
                                const SurfaceNoise& noise, std::vector<double>& keptPoints,
                                std::vector<float>& keptNormals)
{
  if (!noisy(noise))
    return 0;
  const std::vector<std::uint32_t> kept = pointsOnTheSurface(points, count);
  if (kept.size() == count || kept.size() < 16)
    return 0;
  for (std::uint32_t i : kept)
  {
    keptPoints.insert(keptPoints.end(), points + 3 * i, points + 3 * i + 3);
    keptNormals.insert(keptNormals.end(), normals + 3 * i, normals + 3 * i + 3);
  }
  const std::size_t left = count - kept.size();
  points = keptPoints.data();
  normals = keptNormals.data();
  count = kept.size();
  return left;
}

// The fine surface at the smoothing's voxel: the field's zero crossing (its closing widened where
// data seen all round look open), its crossings far from the data dropped and its largest
// piece (or pieces: keptPieceShare) kept. Throws when nothing is left.
FineMesh fineSurface(const FieldInput& in, const Smoothing& smoothing, double diagonal,
                     const ReconstructionOptions& options)
{
  const double h = smoothing.voxel;
  double reach = std::max(options.holeReach * diagonal, 2 * NarrowBand * h);
  const std::size_t k = smoothing.neighbours;
  bool open = false;
  FineMesh fine = meshField(in, h, reach, k, options, open);
  // Data seen all round but for a cap no camera reached (the top of a head, a sole) look open
  // at first: a closing twice and four times as wide bridges the cap. Data seen from one side
  // (a single sensor, a dome) are open in truth, and keep the first surface: their normals lean
  // one way on the whole, where all round they cancel.
  for (int widen = 0; open && widen < 2 && options.holeReach > 0 && seenAllRound(in); ++widen)
  {
    reach *= 2;
    bool still = false;
    FineMesh wider = meshField(in, h, reach, k, options, still);
    if (!still)
    {
      fine = std::move(wider);
      open = false;
    }
  }
  // Open data: the crossings where the band ends (at least NarrowBand voxels from the points)
  // are no surface of the data. Closed, a bridge across a hole reaches as far from the data as
  // the closing reached from each side of it.
  dropUnsupported(fine, in, open ? (NarrowBand - 0.5) * h : 2 * reach);
  keepLargePieces(fine, options.keptPieceShare);
  if (fine.triangles.size() < 4)
    throw std::runtime_error("surface reconstruction found no surface in " +
                             std::to_string(in.count) + " points");
  return fine;
}

// The remeshed surface as the reconstruction's result, with the smoothing that made it.
ReconstructedMesh meshOf(support::RemeshedSurface&& remeshed, const Smoothing& smoothing)
{
  ReconstructedMesh mesh;
  mesh.voxelSize = smoothing.voxel;
  mesh.noise = smoothing.noise;
  mesh.neighbours = smoothing.neighbours;
  mesh.smoothedForNoise = !smoothing.normals.empty();
  mesh.positions = std::move(remeshed.positions);
  mesh.triangles = std::move(remeshed.triangles);
  mesh.closed = remeshed.closed;
  return mesh;
}

} // namespace

ReconstructedMesh reconstructSurface(const double* points, const float* normals, std::size_t count,
                                     const ReconstructionOptions& options)
{
  validateReconstruction(points, normals, count, options);
  const SurfaceNoise noise = measureSurfaceNoise(points, count);
  std::vector<double> keptPoints;
  std::vector<float> keptNormals;
  const std::size_t strayPoints =
      leaveOutStrayPoints(points, normals, count, noise, keptPoints, keptNormals);
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });

  const std::vector<double> all(points, points + 3 * count);
  const double diagonal = boundingBoxDiagonal(all);
  if (!(diagonal > 0))
    throw std::invalid_argument("surface reconstruction: all points coincide");

  const support::KdTree tree(points, count);
  const double spacing = typicalSpacing(tree, points, count);
  const Smoothing smoothing = smoothingFor(points, normals, count, spacing, noise, options);
  const FieldInput in{points, smoothing.normals.empty() ? normals : smoothing.normals.data(), count,
                      tree, spacing};
  const FineMesh fine = fineSurface(in, smoothing, diagonal, options);

  // Isotropic remeshing to the wanted count, every vertex on the fine surface.
  support::RemeshedSurface remeshed = support::remeshIsotropic(fine, options.targetVertices);
  const std::size_t handles = options.handleLoop > 0 ? cutHandles(remeshed, options) : 0;
  ReconstructedMesh mesh = meshOf(std::move(remeshed), smoothing);
  mesh.handlesCut = handles;
  mesh.strayPoints = strayPoints;
  orientLikeTheData(mesh, in);
  return mesh;
}

} // namespace dp
