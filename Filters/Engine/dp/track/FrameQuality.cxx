// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/FrameQuality.h"

#include "dp/track/Parallel.h"
#include "dp/track/SurfaceLocator.h"

#include <algorithm>
#include <cmath>

namespace dp
{

FrameQuality assessFrame(const FrameData& frame, const TriangleMesh& mesh, const double* x,
                         const std::vector<double>& mass, double reach)
{
  FrameQuality q;
  if (frame.empty())
    return q;
  const SurfaceLocator locator(mesh, x);
  const auto& spread = frame.spread();
  std::vector<std::uint8_t> far(spread.size(), 0);
  forEachIndex(spread.size(), [&](std::size_t i)
               { far[i] = locator.closest(frame.point(spread[i]), reach).triangle < 0; });
  std::size_t count = 0;
  for (std::uint8_t f : far)
    count += f;
  q.unexplained =
      spread.empty() ? 0.0 : static_cast<double>(count) / static_cast<double>(spread.size());
  const std::size_t nv = mesh.numberOfVertices();
  std::vector<double> lonely(nv, 0.0);
  forEachIndex(nv,
               [&](std::size_t v)
               {
                 double d2 = 0;
                 frame.nearest(x + 3 * v, &d2);
                 lonely[v] = d2 > reach * reach ? mass[v] : 0.0;
               });
  for (double m : lonely)
    q.unsupported += m;
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
