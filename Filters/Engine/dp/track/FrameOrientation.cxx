// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/FrameOrientation.h"

#include "dp/geometry/SurfaceLocator.h"
#include "dp/geometry/TriangleMesh.h"
#include "dp/support/Parallel.h"
#include "dp/track/FrameData.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace dp
{

namespace
{
// A sure vote on a data normal's orientation: the shape's surface within this many voxels, at
// most 45 degrees from parallel or antiparallel (cosine).
constexpr double SureReach = 2.0;
constexpr double SureCosine = 0.7;

// Each subsample point's votes (searched in parallel): +1 agrees, -1 disagrees, 0 no surface
// near. `vote`: any surface within 3 voxels; `sure`: the sure vote.
struct Votes
{
  std::vector<std::int8_t> vote, sure;
};

Votes votesOf(const FrameData& frame, const TriangleMesh& mesh, const std::vector<double>& x,
              double voxel)
{
  const SurfaceLocator locator(mesh, x.data());
  std::vector<double> normals(x.size());
  mesh.vertexNormals(x.data(), normals.data());
  const auto& tri = mesh.triangles();
  const std::vector<std::uint32_t>& spread = frame.spread();
  Votes v{std::vector<std::int8_t>(spread.size(), 0), std::vector<std::int8_t>(spread.size(), 0)};
  forEachIndex(spread.size(),
               [&](std::size_t i)
               {
                 const std::uint32_t p = spread[i];
                 const SurfaceLocator::Hit hit = locator.closest(frame.point(p), 3 * voxel);
                 if (hit.triangle < 0)
                   return;
                 double n[3] = {0, 0, 0};
                 for (int c = 0; c < 3; ++c)
                   for (int k = 0; k < 3; ++k)
                     n[k] += hit.barycentric[c] * normals[3 * tri[3 * hit.triangle + c] + k];
                 const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                 const double along = n[0] * frame.normal(p)[0] + n[1] * frame.normal(p)[1] +
                                      n[2] * frame.normal(p)[2];
                 v.vote[i] = along >= 0 ? 1 : -1;
                 if (hit.squaredDistance <= SureReach * SureReach * voxel * voxel &&
                     std::abs(along) >= SureCosine * length)
                   v.sure[i] = v.vote[i];
               });
  return v;
}

// Flips each part most of whose votes disagree (counted in order); returns which were flipped.
std::vector<bool> flipDisagreeingParts(FrameData& frame, const std::vector<std::int8_t>& vote)
{
  const std::vector<std::uint32_t>& spread = frame.spread();
  const std::size_t parts = std::max<std::size_t>(1, frame.numberOfParts());
  std::vector<double> agree(parts, 0), disagree(parts, 0);
  for (std::size_t i = 0; i < spread.size(); ++i)
  {
    const std::uint32_t part = frame.numberOfParts() > 0 ? frame.part(spread[i]) : 0;
    if (vote[i] != 0)
      (vote[i] > 0 ? agree : disagree)[part] += 1;
  }
  std::vector<bool> flipped(parts, false);
  for (std::uint32_t part = 0; part < parts; ++part)
    if (disagree[part] > agree[part])
    {
      flipped[part] = true;
      if (frame.numberOfParts() > 0)
        frame.flipNormals(part);
      else
        frame.flipNormals();
    }
  return flipped;
}
} // namespace

void orientToShape(FrameData& frame, const TriangleMesh& mesh, const std::vector<double>& x,
                   double voxel)
{
  if (frame.spread().empty())
    return;
  Votes votes = votesOf(frame, mesh, x, voxel);
  const std::vector<bool> flipped = flipDisagreeingParts(frame, votes.vote);
  if (frame.numberOfParts() == 0)
    return; // normals given: no orientation tree to mend
  // The sure votes as the normals now stand.
  const std::vector<std::uint32_t>& spread = frame.spread();
  for (std::size_t i = 0; i < spread.size(); ++i)
    if (flipped[frame.part(spread[i])])
      votes.sure[i] = static_cast<std::int8_t>(-votes.sure[i]);
  frame.mendOrientation(votes.sure);
}

} // namespace dp
