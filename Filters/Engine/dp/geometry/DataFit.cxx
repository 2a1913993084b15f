// SPDX-License-Identifier: BSD-3-Clause
#include "dp/geometry/DataFit.h"

#include "dp/geometry/SurfaceLocator.h"
#include "dp/support/Parallel.h"

#include <algorithm>
#include <cmath>

namespace dp
{

DataFit measureDataFit(const TriangleMesh& mesh, const double* positions,
                       const std::vector<const FrameSamples*>& samples, double reach,
                       std::vector<std::vector<bool>>* within)
{
  const std::size_t nv = mesh.numberOfVertices();
  const bool given = within && !within->empty();
  if (within && !given)
    within->assign(samples.size(), {});
  DataFit fit;
  double sum = 0;
  for (std::size_t t = 0; t < samples.size(); ++t)
  {
    const FrameSamples* s = samples[t];
    if (!s || s->empty())
      continue;
    const SurfaceLocator locator(mesh, positions + 3 * nv * t);
    std::vector<double> d2(s->size(), -1.0);
    const double limit = given ? HUGE_VAL : reach;
    forEachIndex(s->size(),
                 [&](std::size_t i)
                 {
                   if (given && !(*within)[t][i])
                     return;
                   const SurfaceLocator::Hit hit = locator.closest(&s->points[3 * i], limit);
                   if (hit.triangle >= 0)
                     d2[i] = hit.squaredDistance;
                 });
    if (within && !given)
      (*within)[t].assign(s->size(), false);
    for (std::size_t i = 0; i < d2.size(); ++i)
    {
      if (given && !(*within)[t][i])
        continue;
      if (d2[i] < 0)
      {
        ++fit.beyondReach;
        continue;
      }
      sum += d2[i];
      ++fit.samples;
      if (within && !given)
        (*within)[t][i] = true;
    }
  }
  fit.rms = fit.samples > 0 ? std::sqrt(sum / static_cast<double>(fit.samples)) : 0.0;
  return fit;
}

} // namespace dp
