// SPDX-License-Identifier: BSD-3-Clause
#include "dp/field/SignedField.h"

#include "dp/field/OutsideBand.h"
#include "dp/field/PointBand.h"
#include "dp/support/Vec3.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace dp::support
{
namespace
{
// Signed distance from x to the data's tangent planes: the Gaussian-weighted mean over its k
// nearest points (Hoppe et al.), and the squared distances to those points.
double planeDistance(const FieldInput& in, const double x[3], std::size_t k, double sigma2,
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

constexpr int CoarseRatio = 4; // coarse voxel / fine voxel, for finding the holes

// The plane distance in voxels, clamped to the band, at every active voxel of `grid` but those
// of holes.
void evaluate(const FieldInput& in, openvdb::FloatGrid& grid, double h, std::size_t k,
              double sigma2)
{
  openvdb::tree::LeafManager<openvdb::FloatTree> leaves(grid.tree());
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, leaves.leafCount()),
      [&](const tbb::blocked_range<std::size_t>& range)
      {
        std::vector<std::uint32_t> ids(k);
        std::vector<double> d2(k);
        for (std::size_t l = range.begin(); l != range.end(); ++l)
          for (auto it = leaves.leaf(l).beginValueOn(); it; ++it)
          {
            if (*it == UnknownHoleValue)
              continue;
            const openvdb::Coord c = it.getCoord();
            const double x[3] = {h * c.x(), h * c.y(), h * c.z()};
            const double distance = planeDistance(in, x, k, sigma2, ids.data(), d2.data()) / h;
            it.setValue(static_cast<float>(std::clamp(distance, -NarrowBand, NarrowBand)));
          }
      });
}

// Throws when the grid at voxel size h would hold more voxels than the options allow.
void checkGridSize(double voxels, double h, const ReconstructionOptions& options)
{
  if (voxels > static_cast<double>(options.maxActiveVoxels))
    throw std::runtime_error("surface reconstruction: the grid at voxel size " + std::to_string(h) +
                             " would exceed " + std::to_string(options.maxActiveVoxels) +
                             " voxels");
}

// The band: every voxel within NarrowBand voxels of a point, active, with no value yet.
openvdb::FloatGrid::Ptr pointBand(const FieldInput& in, double h,
                                  const ReconstructionOptions& options)
{
  const float background = static_cast<float>(NarrowBand);
  openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(background);
  support::seedPointVoxels(grid->tree(), in.points, in.count, h, background);
  const int reach = static_cast<int>(NarrowBand);
  checkGridSize(support::bandVoxelBound(grid->tree(), reach), h, options);
  support::dilateBand(grid->tree(), reach);
  return grid;
}

// Holes: on a coarse grid, the cells that a morphological closing of the points' cells adds
// (gaps in the data narrower than about twice `reach`, and concave corners). Their voxels
// outside the band are made active with the value UnknownHoleValue and returned: the plane
// distance far from the data is unreliable (a wrongly oriented patch, or data passing through
// itself, would grow sheets there), so they are interpolated later, harmonically, between the
// band and the pieces outside it.
std::vector<openvdb::Coord> addHoleVoxels(openvdb::FloatGrid& grid, const FieldInput& in, double h,
                                          double reach, const ReconstructionOptions& options)
{
  std::vector<openvdb::Coord> holes;
  const double H = CoarseRatio * h;
  const int closing = static_cast<int>(std::ceil(reach / H));
  if (closing <= 0)
    return holes;
  openvdb::MaskGrid::Ptr cells = openvdb::MaskGrid::create();
  support::seedPointVoxels(cells->tree(), in.points, in.count, H, true);
  // The closing's dilation is bounded before it is built: a tiny voxel makes `closing` huge.
  // (The fine voxels it adds are counted after, with the band's.)
  checkGridSize(support::bandVoxelBound(cells->tree(), closing), h, options);
  openvdb::MaskGrid::Ptr closed = cells->deepCopy();
  support::dilateBand(closed->tree(), closing);
  openvdb::tools::erodeActiveValues(closed->tree(), closing, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                    openvdb::tools::IGNORE_TILES);
  closed->tree().topologyDifference(cells->tree());
  auto acc = grid.getAccessor();
  const int half = CoarseRatio / 2;
  for (auto it = closed->cbeginValueOn(); it; ++it)
  {
    // The cell's voxels (the cell of coarse voxel c is centred on CoarseRatio c).
    const openvdb::Coord c = it.getCoord();
    for (int i = -half; i < CoarseRatio - half; ++i)
      for (int j = -half; j < CoarseRatio - half; ++j)
        for (int l = -half; l < CoarseRatio - half; ++l)
        {
          const openvdb::Coord v(CoarseRatio * c.x() + i, CoarseRatio * c.y() + j,
                                 CoarseRatio * c.z() + l);
          if (!acc.isValueOn(v))
          {
            acc.setValueOn(v, UnknownHoleValue);
            holes.push_back(v);
          }
        }
  }
  return holes;
}

// Normals against the pieces: each border voxel of the band (next to a piece whose border
// mostly agrees) asks the three points nearest to it whether their planes put it on its
// piece's side (the nearest only: beyond a thin part, those of its far side answer). A point
// that most of its voxels find on the wrong side has its normal the wrong way round (a patch
// oriented against the rest); those points are returned.
std::vector<std::uint32_t> wronglyOrientedPoints(const FieldInput& in, const OutsideBand& outside,
                                                 double h, std::size_t k)
{
  std::vector<std::pair<openvdb::Coord, bool>> voxels; // border voxel, its piece inside
  outside.borderOfSettledPieces(voxels);
  std::vector<std::atomic<int>> support(in.count);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, voxels.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& range)
                    {
                      std::vector<std::uint32_t> ids(k);
                      std::vector<double> d2(k);
                      for (std::size_t b = range.begin(); b != range.end(); ++b)
                      {
                        const auto& [v, inside] = voxels[b];
                        const double x[3] = {h * v.x(), h * v.y(), h * v.z()};
                        const std::size_t found =
                            in.tree.nearest(x, std::min<std::size_t>(k, 3), ids.data(), d2.data());
                        for (std::size_t j = 0; j < found; ++j)
                        {
                          const double* p = in.points + 3 * ids[j];
                          const float* n = in.normals + 3 * ids[j];
                          const double along =
                              n[0] * (x[0] - p[0]) + n[1] * (x[1] - p[1]) + n[2] * (x[2] - p[2]);
                          support[ids[j]] += (along < 0) == inside ? 1 : -1;
                        }
                      }
                    });
  std::vector<std::uint32_t> flipped;
  for (std::size_t i = 0; i < in.count; ++i)
    if (support[i] < 0)
      flipped.push_back(static_cast<std::uint32_t>(i));
  return flipped;
}

// The field evaluated again (with `corrected`, the normals after flipping) on the band's voxels
// whose neighbours may include a flipped point.
void reevaluateAround(openvdb::FloatGrid& grid, const FieldInput& corrected,
                      const std::vector<std::uint32_t>& flipped, double h, std::size_t k,
                      double sigma2)
{
  openvdb::MaskGrid::Ptr touched = openvdb::MaskGrid::create();
  {
    auto acc = touched->getAccessor();
    for (std::uint32_t i : flipped)
      acc.setValueOn(voxelOf(corrected.points + 3 * i, h));
  }
  openvdb::tools::dilateActiveValues(touched->tree(), static_cast<int>(NarrowBand) + 2,
                                     openvdb::tools::NN_FACE_EDGE_VERTEX,
                                     openvdb::tools::IGNORE_TILES);
  auto acc = grid.getAccessor();
  std::vector<std::uint32_t> ids(k);
  std::vector<double> d2(k);
  for (auto it = touched->cbeginValueOn(); it; ++it)
  {
    const openvdb::Coord c = it.getCoord();
    if (!acc.isValueOn(c) || acc.getValue(c) == UnknownHoleValue)
      continue;
    const double x[3] = {h * c.x(), h * c.y(), h * c.z()};
    const double distance = planeDistance(corrected, x, k, sigma2, ids.data(), d2.data()) / h;
    acc.setValue(c, static_cast<float>(std::clamp(distance, -NarrowBand, NarrowBand)));
  }
}

// The field's zero crossing as triangles in world units (quads split along their shorter
// diagonal, degenerate triangles dropped).
FineMesh zeroCrossing(const openvdb::FloatGrid& grid, double h)
{
  std::vector<openvdb::Vec3s> vertices;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(grid, vertices, triangles, quads, 0.0, 0.0);

  FineMesh mesh;
  mesh.positions.reserve(vertices.size());
  for (const auto& v : vertices)
    mesh.positions.push_back({h * v[0], h * v[1], h * v[2]});
  auto add = [&](unsigned a, unsigned b, unsigned c)
  {
    if (a != b && b != c && a != c)
      mesh.triangles.push_back({static_cast<int>(a), static_cast<int>(b), static_cast<int>(c)});
  };
  for (const auto& t : triangles)
    add(t[0], t[1], t[2]);
  for (const auto& q : quads)
  {
    // Split along the shorter diagonal: better-shaped triangles.
    const auto& p = mesh.positions;
    if (norm(p[q[0]] - p[q[2]]) <= norm(p[q[1]] - p[q[3]]))
    {
      add(q[0], q[1], q[2]);
      add(q[0], q[2], q[3]);
    }
    else
    {
      add(q[0], q[1], q[3]);
      add(q[1], q[2], q[3]);
    }
  }
  return mesh;
}
} // namespace

FineMesh meshField(const FieldInput& in, double h, double reach, std::size_t k,
                   const ReconstructionOptions& options, bool& open)
{
  const float background = static_cast<float>(NarrowBand);
  openvdb::FloatGrid::Ptr grid = pointBand(in, h, options);
  const double sigma2 = std::pow(std::max(h, in.spacing), 2);
  const std::vector<openvdb::Coord> holes = addHoleVoxels(*grid, in, h, reach, options);
  checkGridSize(static_cast<double>(grid->activeVoxelCount()), h, options);

  OutsideBand outside(*grid);
  evaluate(in, *grid, h, k, sigma2);
  outside.findPieces(*grid);
  const std::vector<std::uint32_t> flipped = wronglyOrientedPoints(in, outside, h, k);
  if (!flipped.empty())
  {
    std::vector<float> corrected(in.normals, in.normals + 3 * in.count);
    for (std::uint32_t i : flipped)
      for (int c = 0; c < 3; ++c)
        corrected[3 * i + c] = -corrected[3 * i + c];
    FieldInput again = in;
    again.normals = corrected.data();
    reevaluateAround(*grid, again, flipped, h, k, sigma2);
    outside.findPieces(*grid);
  }
  outside.settle(*grid, background);
  open = outside.open();
  interpolateHoles(*grid, holes, background);
  return zeroCrossing(*grid, h);
}

} // namespace dp::support
