// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/FrameQuality.h"

#include "dp/geometry/SurfaceLocator.h"
#include "dp/support/Parallel.h"

#include <algorithm>
#include <cmath>

namespace dp
{

namespace
{
// The reach, in the data's layer thicknesses, beyond which a point is far from the mesh.
constexpr double NoiseReach = 6.0;
// The nearest points around a far point, three quarters of which must be far for it to count.
constexpr std::size_t PatchPoints = 12;

// Marks each well-spread point: 0 stray (not judged), 1 within `reach` of the mesh, 2 beyond.
std::vector<std::uint8_t> markFarPoints(const FrameData& frame, const SurfaceLocator& locator,
                                        double reach)
{
  const auto& spread = frame.spread();
  const auto& stray = frame.strayInSpread();
  std::vector<std::uint8_t> far(spread.size(), 0);
  forEachIndex(spread.size(),
               [&](std::size_t i)
               {
                 // A stray point (a flying pixel, a stray return) is no surface to explain.
                 far[i] = stray.empty() || !stray[i]
                              ? 1 + (locator.closest(frame.point(spread[i]), reach).triangle < 0)
                              : 0;
               });
  return far;
}

// A far point counts when the surface around it is far too (most of its nearest points): a
// part the mesh let go of, not a point beyond the reach by noise or by detail the template's
// resolution cannot hold (scattered fingertips, folds). The others become near (1).
void keepFarPatches(const FrameData& frame, const SurfaceLocator& locator, double reach,
                    std::vector<std::uint8_t>& far)
{
  const auto& spread = frame.spread();
  forEachIndex(spread.size(),
               [&](std::size_t i)
               {
                 if (far[i] != 2)
                   return;
                 std::uint32_t ids[PatchPoints];
                 double d2[PatchPoints];
                 const std::size_t n = frame.nearest(frame.point(spread[i]), PatchPoints, ids, d2);
                 std::size_t farAround = 0;
                 for (std::size_t j = 0; j < n; ++j)
                   farAround += locator.closest(frame.point(ids[j]), reach).triangle < 0;
                 if (4 * farAround < 3 * PatchPoints)
                   far[i] = 1;
               });
}

// The unexplained share and the points it is of (q.unexplained, q.samples).
void measureUnexplained(const FrameData& frame, const SurfaceLocator& locator, double reach,
                        FrameQuality& q)
{
  std::vector<std::uint8_t> far = markFarPoints(frame, locator, reach);
  keepFarPatches(frame, locator, reach, far);
  std::size_t count = 0, judged = 0;
  for (std::uint8_t f : far)
  {
    judged += f > 0;
    count += f == 2;
  }
  q.samples = judged;
  q.unexplained = judged == 0 ? 0.0 : static_cast<double>(count) / static_cast<double>(judged);
}

// The unsupported share of the mesh and the part of it that departed from its data
// (q.unsupported, q.departed).
void measureUnsupported(const FrameData& frame, const TriangleMesh& mesh, const double* x,
                        const std::vector<double>& mass, double reach, const double* start,
                        FrameQuality& q)
{
  const std::size_t nv = mesh.numberOfVertices();
  std::vector<double> lonely(nv, 0.0), left(nv, 0.0);
  const auto distance2 = [&](const double* p)
  {
    double d2 = 0;
    frame.nearest(p, &d2);
    return d2;
  };
  forEachIndex(nv,
               [&](std::size_t v)
               {
                 const double d2 = distance2(x + 3 * v);
                 if (!(d2 > reach * reach))
                   return;
                 lonely[v] = mass[v];
                 // Departed: on its data where the solve started (within half the reach: a
                 // vertex over a hole's rim, near reach either way, does not count).
                 if (start && distance2(start + 3 * v) <= 0.25 * reach * reach)
                   left[v] = mass[v];
               });
  // A vertex departed counts where its neighbours departed too (a part that left its data), not
  // alone (a vertex over a hole's rim, a fold the template cannot hold).
  for (std::size_t v = 0; v < nv; ++v)
  {
    q.unsupported += lonely[v];
    if (!(left[v] > 0))
      continue;
    const std::vector<std::int64_t>& around = mesh.neighbours(v);
    std::size_t leftAround = 0;
    for (std::int64_t w : around)
      leftAround += left[static_cast<std::size_t>(w)] > 0;
    if (2 * leftAround >= around.size())
      q.departed += left[v];
  }
}
} // namespace

FrameQuality assessFrame(const FrameData& frame, const TriangleMesh& mesh, const double* x,
                         const std::vector<double>& mass, double reach, const double* start)
{
  FrameQuality q;
  if (frame.empty())
    return q;
  // A noisy layer's points lie off any surface by a few thicknesses: the reach follows it, up
  // to three times the reach asked (a frame of garbage is no layer to follow).
  reach = std::max(reach, std::min(NoiseReach * frame.noise().thickness, 3 * reach));
  q.noise = frame.noise().thickness;
  q.reach = reach;
  const SurfaceLocator locator(mesh, x);
  measureUnexplained(frame, locator, reach, q);
  measureUnsupported(frame, mesh, x, mass, reach, start, q);
  return q;
}

double largestEdgeGrowth(const TriangleMesh& mesh, const std::vector<double>& rest,
                         const std::vector<double>& x, const std::vector<double>& scales)
{
  auto length = [](const std::vector<double>& p, std::int64_t a, std::int64_t b)
  {
    const double d[3] = {p[3 * a] - p[3 * b], p[3 * a + 1] - p[3 * b + 1],
                         p[3 * a + 2] - p[3 * b + 2]};
    return std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  };
  const auto& edges = mesh.edges();
  double largest = 0, sum = 0;
  for (std::size_t i = 0; i < edges.size(); ++i)
  {
    const double before = length(rest, edges[i][0], edges[i][1]);
    const double scale = scales.empty() ? 1.0 : std::min(scales[i], 1.0);
    sum += before;
    largest = std::max(largest, scale * (length(x, edges[i][0], edges[i][1]) - before));
  }
  return edges.empty() ? 0.0 : largest * static_cast<double>(edges.size()) / sum;
}

} // namespace dp
