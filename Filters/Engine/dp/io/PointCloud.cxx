// SPDX-License-Identifier: BSD-3-Clause
#include "dp/io/PointCloud.h"

#include <algorithm>
#include <cmath>

namespace dp
{

void PointCloud::addFace(const std::int64_t* ids, std::size_t count)
{
  if (faceOffsets.empty())
  {
    faceOffsets.push_back(0);
  }
  faceConnectivity.insert(faceConnectivity.end(), ids, ids + count);
  faceOffsets.push_back(static_cast<std::int64_t>(faceConnectivity.size()));
}

void PointCloud::validate() const
{
  const std::size_t n = numberOfPoints();
  if (points.size() % 3 != 0)
  {
    throw std::logic_error("point coordinates are not a multiple of 3");
  }
  if (!normals.empty() && normals.size() != 3 * n)
  {
    throw std::logic_error("normals do not match the number of points");
  }
  if (!colors.empty() && colors.size() != static_cast<std::size_t>(colorComponents) * n)
  {
    throw std::logic_error("colours do not match the number of points");
  }
  for (const auto& a : attributes)
  {
    if (a.components < 1 || a.values.size() != static_cast<std::size_t>(a.components) * n)
    {
      throw std::logic_error("attribute '" + a.name + "' does not match the number of points");
    }
  }
  if (!faceOffsets.empty() &&
      faceOffsets.back() != static_cast<std::int64_t>(faceConnectivity.size()))
  {
    throw std::logic_error("face offsets do not match the connectivity");
  }
  for (std::int64_t id : faceConnectivity)
  {
    if (id < 0 || static_cast<std::size_t>(id) >= n)
    {
      throw std::logic_error("face index " + std::to_string(id) + " out of range [0, " +
                             std::to_string(n) + ")");
    }
  }
}

namespace
{

// Compacts an interleaved array in place (comps values per point), keeping the tuples of the
// points that survive: point i moves to newIndex[i], or is dropped when that is -1.
template <typename Values>
void compactTuples(Values& values, std::size_t comps, const std::vector<std::int64_t>& newIndex,
                   std::size_t kept)
{
  if (values.empty())
  {
    return;
  }
  for (std::size_t i = 0; i < newIndex.size(); ++i)
  {
    if (newIndex[i] >= 0)
    {
      std::copy_n(values.begin() + i * comps, comps, values.begin() + newIndex[i] * comps);
    }
  }
  values.resize(kept * comps);
}

// Keeps the faces all of whose points survive, renumbered by newIndex; no faces left: none.
void keepFacesOfSurvivors(PointCloud& cloud, const std::vector<std::int64_t>& newIndex)
{
  std::vector<std::int64_t> offsets{0};
  std::vector<std::int64_t> conn;
  conn.reserve(cloud.faceConnectivity.size());
  for (std::size_t f = 0; f + 1 < cloud.faceOffsets.size(); ++f)
  {
    const auto begin = cloud.faceConnectivity.begin() + cloud.faceOffsets[f];
    const auto end = cloud.faceConnectivity.begin() + cloud.faceOffsets[f + 1];
    if (std::all_of(begin, end, [&](std::int64_t id) { return newIndex[id] >= 0; }))
    {
      for (auto it = begin; it != end; ++it)
      {
        conn.push_back(newIndex[*it]);
      }
      offsets.push_back(static_cast<std::int64_t>(conn.size()));
    }
  }
  cloud.faceOffsets = offsets.size() > 1 ? std::move(offsets) : std::vector<std::int64_t>{};
  cloud.faceConnectivity = std::move(conn);
}

} // namespace

std::size_t dropNonFinitePoints(PointCloud& cloud)
{
  const std::size_t n = cloud.numberOfPoints();
  std::vector<std::int64_t> newIndex(n, -1);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n; ++i)
  {
    const double* p = &cloud.points[3 * i];
    if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))
    {
      newIndex[i] = static_cast<std::int64_t>(kept++);
    }
  }
  if (kept == n)
  {
    return 0;
  }
  compactTuples(cloud.points, 3, newIndex, kept);
  compactTuples(cloud.normals, 3, newIndex, kept);
  compactTuples(cloud.colors, static_cast<std::size_t>(cloud.colorComponents), newIndex, kept);
  for (auto& a : cloud.attributes)
  {
    compactTuples(a.values, static_cast<std::size_t>(a.components), newIndex, kept);
  }
  if (!cloud.faceOffsets.empty())
  {
    keepFacesOfSurvivors(cloud, newIndex);
  }
  return n - kept;
}

} // namespace dp
