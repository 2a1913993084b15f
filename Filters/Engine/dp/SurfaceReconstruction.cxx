// SPDX-License-Identifier: BSD-3-Clause
#include "dp/SurfaceReconstruction.h"

#include "dp/SurfaceSampler.h"
#include "dp/TriangleMesh.h"
#include "dp/detail/KdTree.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <string>

namespace dp
{
namespace
{
struct Input
{
  const double* points;
  const float* normals;
  std::size_t count;
  const detail::KdTree& tree;
  double spacing; // median distance from a point to its nearest neighbour
};

// Signed distance from x to the data's tangent planes: the Gaussian-weighted mean over its k
// nearest points (Hoppe et al.), and the distance to the nearest point (squared).
double planeDistance(const Input& in, const double x[3], std::size_t k, double sigma2,
                     std::uint32_t* ids, double* d2)
{
  const std::size_t found = in.tree.nearest(x, k, ids, d2);
  double sum = 0, weights = 0;
  for (std::size_t j = 0; j < found; ++j)
  {
    const double* p = in.points + 3 * ids[j];
    const float* n = in.normals + 3 * ids[j];
    const double w = std::exp(-(d2[j] - d2[0]) / sigma2);
    sum += w * (n[0] * (x[0] - p[0]) + n[1] * (x[1] - p[1]) + n[2] * (x[2] - p[2]));
    weights += w;
  }
  return sum / weights;
}

// Contouring leaves slivers where the surface cuts a voxel near a corner; slivers make the
// cloth energy stiff and its solves slow. A few rounds of tangential smoothing (each vertex
// halfway to its neighbours' mean, along the surface) followed by projection back onto the
// tangent planes even the triangles out without moving the surface.
void relax(const Input& in, ReconstructedMesh& mesh, std::size_t k, double sigma2)
{
  const std::size_t nv = mesh.positions.size() / 3;
  if (nv == 0)
    return;
  const TriangleMesh topology(mesh.triangles, nv);
  std::vector<double> normals(3 * nv), next(mesh.positions.size());
  for (int round = 0; round < 5; ++round)
  {
    topology.vertexNormals(mesh.positions.data(), normals.data());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv),
                      [&](const tbb::blocked_range<std::size_t>& range)
                      {
                        std::vector<std::uint32_t> ids(k);
                        std::vector<double> d2(k);
                        for (std::size_t v = range.begin(); v != range.end(); ++v)
                        {
                          const double* x = &mesh.positions[3 * v];
                          const double* n = &normals[3 * v];
                          double mean[3] = {0, 0, 0};
                          const auto& ring = topology.neighbours(v);
                          for (std::int64_t u : ring)
                            for (int c = 0; c < 3; ++c)
                              mean[c] += mesh.positions[3 * static_cast<std::size_t>(u) + c];
                          double move[3];
                          for (int c = 0; c < 3; ++c)
                            move[c] = ring.empty()
                                          ? 0.0
                                          : mean[c] / static_cast<double>(ring.size()) - x[c];
                          const double along = move[0] * n[0] + move[1] * n[1] + move[2] * n[2];
                          double y[3];
                          for (int c = 0; c < 3; ++c)
                            y[c] = x[c] + 0.5 * (move[c] - along * n[c]);
                          const double off = planeDistance(in, y, k, sigma2, ids.data(), d2.data());
                          for (int c = 0; c < 3; ++c)
                            next[3 * v + c] = y[c] - off * n[c];
                        }
                      });
    mesh.positions.swap(next);
  }
}

// The mesh of the zero crossing at voxel size h, before the vertex-count loop judges it.
ReconstructedMesh meshAt(const Input& in, double h, const ReconstructionOptions& options)
{
  // Band half-width in voxels: wide enough to bridge the gaps between samples.
  const double band = std::max(2.5, 1.5 * in.spacing / h);
  const int reach = static_cast<int>(std::ceil(band));
  const double estimate = static_cast<double>(in.count) * std::pow(2.0 * reach + 1, 3);
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(static_cast<float>(band));
  {
    auto acc = grid->getAccessor();
    for (std::size_t i = 0; i < in.count; ++i)
      acc.setValueOn(openvdb::Coord(static_cast<int>(std::floor(in.points[3 * i] / h + 0.5)),
                                    static_cast<int>(std::floor(in.points[3 * i + 1] / h + 0.5)),
                                    static_cast<int>(std::floor(in.points[3 * i + 2] / h + 0.5))),
                     static_cast<float>(band));
  }
  if (estimate > static_cast<double>(options.maxActiveVoxels) &&
      static_cast<double>(grid->activeVoxelCount()) * std::pow(2.0 * reach + 1, 3) >
          static_cast<double>(options.maxActiveVoxels))
    throw std::runtime_error("surface reconstruction: the grid at voxel size " + std::to_string(h) +
                             " would exceed " + std::to_string(options.maxActiveVoxels) +
                             " voxels");
  openvdb::tools::dilateActiveValues(grid->tree(), reach, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                     openvdb::tools::IGNORE_TILES);

  // Each active voxel: the Gaussian-weighted mean of its nearest points' signed plane
  // distances, in voxels; voxels farther than the band from every point go back to background.
  openvdb::tree::LeafManager<openvdb::FloatTree> leaves(grid->tree());
  const std::size_t k = std::max<std::size_t>(1, std::min(options.neighbours, in.count));
  const double sigma2 = std::pow(std::max(h, in.spacing), 2);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.leafCount()),
                    [&](const tbb::blocked_range<std::size_t>& range)
                    {
                      std::vector<std::uint32_t> ids(k);
                      std::vector<double> d2(k);
                      for (std::size_t l = range.begin(); l != range.end(); ++l)
                        for (auto it = leaves.leaf(l).beginValueOn(); it; ++it)
                        {
                          const openvdb::Coord c = it.getCoord();
                          const double x[3] = {h * c.x(), h * c.y(), h * c.z()};
                          const double distance =
                              planeDistance(in, x, k, sigma2, ids.data(), d2.data());
                          if (d2[0] > band * band * h * h)
                          {
                            it.setValue(static_cast<float>(band));
                            it.setValueOff();
                            continue;
                          }
                          it.setValue(static_cast<float>(std::clamp(distance / h, -band, band)));
                        }
                    });

  std::vector<openvdb::Vec3s> vertices;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*grid, vertices, triangles, quads, 0.0, 0.0);

  ReconstructedMesh mesh;
  mesh.voxelSize = h;
  mesh.positions.reserve(3 * vertices.size());
  for (const auto& v : vertices)
    for (int c = 0; c < 3; ++c)
      mesh.positions.push_back(h * static_cast<double>(v[c]));
  auto at = [&](std::int64_t i) { return &mesh.positions[3 * static_cast<std::size_t>(i)]; };
  auto distance2 = [](const double* a, const double* b)
  {
    return (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
           (a[2] - b[2]) * (a[2] - b[2]);
  };
  std::vector<std::int64_t> all;
  for (const auto& t : triangles)
    all.insert(all.end(), {t[0], t[1], t[2]});
  for (const auto& q : quads)
  {
    // Split along the shorter diagonal: better-shaped triangles.
    if (distance2(at(q[0]), at(q[2])) <= distance2(at(q[1]), at(q[3])))
      all.insert(all.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
    else
      all.insert(all.end(), {q[0], q[1], q[3], q[1], q[2], q[3]});
  }

  // Drop crossings away from the data (where the band ends inside the shape).
  const std::size_t nv = vertices.size();
  std::vector<std::uint8_t> nearData(nv, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv),
                    [&](const tbb::blocked_range<std::size_t>& range)
                    {
                      for (std::size_t v = range.begin(); v != range.end(); ++v)
                      {
                        double d2 = 0;
                        in.tree.nearest(&mesh.positions[3 * v], &d2);
                        nearData[v] = d2 <= std::pow(0.6 * band * h, 2);
                      }
                    });
  std::vector<std::int64_t> kept;
  for (std::size_t t = 0; t < all.size(); t += 3)
  {
    const std::int64_t a = all[t], b = all[t + 1], c = all[t + 2];
    if (a == b || b == c || a == c || !nearData[a] || !nearData[b] || !nearData[c])
      continue;
    kept.insert(kept.end(), {a, b, c});
  }

  // The largest connected piece (union-find over the triangles' vertices).
  std::vector<std::int64_t> parent(nv);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::int64_t v)
  {
    while (parent[v] != v)
      v = parent[v] = parent[parent[v]];
    return v;
  };
  for (std::size_t t = 0; t < kept.size(); t += 3)
    for (int e = 1; e < 3; ++e)
      parent[find(kept[t + e])] = find(kept[t]);
  std::vector<std::size_t> size(nv, 0);
  for (std::size_t t = 0; t < kept.size(); t += 3)
    ++size[find(kept[t])];
  const auto largest =
      static_cast<std::int64_t>(std::max_element(size.begin(), size.end()) - size.begin());

  std::vector<std::int64_t> index(nv, -1);
  std::vector<double> positions;
  for (std::size_t t = 0; t < kept.size(); t += 3)
  {
    if (find(kept[t]) != largest)
      continue;
    for (int e = 0; e < 3; ++e)
    {
      std::int64_t& i = index[kept[t + e]];
      if (i < 0)
      {
        i = static_cast<std::int64_t>(positions.size() / 3);
        positions.insert(positions.end(), at(kept[t + e]), at(kept[t + e]) + 3);
      }
      mesh.triangles.push_back(i);
    }
  }
  mesh.positions = std::move(positions);
  relax(in, mesh, k, sigma2);

  // Orientation: face normals along the data's normals (a vote of every triangle).
  double vote = 0;
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
  {
    const double* a = at(mesh.triangles[t]);
    const double* b = at(mesh.triangles[t + 1]);
    const double* c = at(mesh.triangles[t + 2]);
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                         u[0] * w[1] - u[1] * w[0]};
    const double centre[3] = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3,
                              (a[2] + b[2] + c[2]) / 3};
    const float* m = in.normals + 3 * in.tree.nearest(centre);
    vote += n[0] * m[0] + n[1] * m[1] + n[2] * m[2];
  }
  if (vote < 0)
    for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
      std::swap(mesh.triangles[t + 1], mesh.triangles[t + 2]);
  return mesh;
}
} // namespace

ReconstructedMesh reconstructSurface(const double* points, const float* normals, std::size_t count,
                                     const ReconstructionOptions& options)
{
  if (count < 16)
    throw std::invalid_argument("surface reconstruction needs at least 16 points, not " +
                                std::to_string(count));
  if (options.targetVertices < 20)
    throw std::invalid_argument("surface reconstruction: a target of " +
                                std::to_string(options.targetVertices) +
                                " vertices is too few (at least 20)");
  for (std::size_t i = 0; i < 3 * count; ++i)
    if (!std::isfinite(points[i]) || !std::isfinite(normals[i]))
      throw std::invalid_argument("surface reconstruction: point " + std::to_string(i / 3) +
                                  " has a non-finite coordinate or normal");
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });

  const detail::KdTree tree(points, count);
  // The typical sample spacing: the median nearest-neighbour distance of a subsample.
  std::vector<double> gaps;
  const std::size_t stride = std::max<std::size_t>(1, count / 2000);
  for (std::size_t i = 0; i < count; i += stride)
  {
    std::uint32_t ids[2];
    double d2[2];
    if (tree.nearest(points + 3 * i, 2, ids, d2) == 2)
      gaps.push_back(std::sqrt(d2[1]));
  }
  std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2),
                   gaps.end());
  const double spacing = gaps[gaps.size() / 2];
  const Input in{points, normals, count, tree, spacing};

  const std::vector<double> all(points, points + 3 * count);
  const double diagonal = boundingBoxDiagonal(all);
  if (!(diagonal > 0))
    throw std::invalid_argument("surface reconstruction: all points coincide");
  // A surface meshed at voxel h has about area / h^2 vertices; a first guess, then rescale.
  double h = diagonal / std::sqrt(static_cast<double>(options.targetVertices));
  ReconstructedMesh best;
  for (int attempt = 0; attempt < 5; ++attempt)
  {
    ReconstructedMesh mesh = meshAt(in, h, options);
    const double vertices = static_cast<double>(mesh.positions.size() / 3);
    const double wanted = static_cast<double>(options.targetVertices);
    if (best.positions.empty() ||
        std::abs(vertices - wanted) <
            std::abs(static_cast<double>(best.positions.size() / 3) - wanted))
      best = std::move(mesh);
    if (vertices > 0 && std::abs(vertices - wanted) <= 0.25 * wanted)
      break;
    h *= vertices > 0 ? std::clamp(std::sqrt(vertices / wanted), 0.25, 4.0) : 0.5;
  }
  if (best.triangles.empty())
    throw std::runtime_error("surface reconstruction found no surface in " + std::to_string(count) +
                             " points");
  return best;
}

} // namespace dp
