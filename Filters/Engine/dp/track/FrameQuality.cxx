// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/FrameQuality.h"

#include "dp/track/Parallel.h"
#include "dp/track/SurfaceLocator.h"

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

} // namespace dp
