// SPDX-License-Identifier: BSD-3-Clause
#include "dp/detail/DetailLevels.h"

#include "dp/geometry/DataFit.h"
#include "dp/geometry/TriangleMesh.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace dp
{

double meanEdgeLength(const std::vector<std::int64_t>& triangles, const double* positions)
{
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3)
    for (int k = 0; k < 3; ++k)
    {
      const std::int64_t a = triangles[t + k], b = triangles[t + (k + 1) % 3];
      if (a >= b) // each interior edge once (seen from its two triangles as a-b and b-a)
        continue;
      const double* x = positions + 3 * a;
      const double* y = positions + 3 * b;
      sum += std::sqrt((x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) +
                       (x[2] - y[2]) * (x[2] - y[2]));
      ++count;
    }
  return count > 0 ? sum / static_cast<double>(count) : 0.0;
}

int levelsForDensity(std::size_t baseVertices, std::size_t captureVertices)
{
  if (baseVertices == 0 || captureVertices <= baseVertices)
    return 0;
  const double levels =
      std::log(static_cast<double>(captureVertices) / static_cast<double>(baseVertices)) /
      std::log(4.0);
  return std::clamp(static_cast<int>(std::lround(levels)), 0, MaximumAutomaticLevels);
}

DetailLevelChoice chooseDetailLevels(const std::vector<std::int64_t>& triangles,
                                     const std::vector<double>& positions, const FrameSurface& data,
                                     const FrameSamples& samples, std::size_t captureVertices,
                                     const DisplacementFitOptions& options)
{
  DetailLevelChoice choice;
  const std::size_t baseVertices = positions.size() / 3;
  choice.candidate = levelsForDensity(baseVertices, captureVertices);
  char text[400];
  if (choice.candidate == 0 || samples.empty())
  {
    std::snprintf(text, sizeof(text),
                  "none: the data (%zu %s) resolve no finer than the tracked mesh's %zu vertices",
                  captureVertices, samples.empty() ? "points, no samples" : "vertices or points",
                  baseVertices);
    choice.summary = text;
    return choice;
  }
  const TriangleMesh base(triangles, baseVertices);
  choice.baseDistance = measureDataFit(base, positions.data(), {&samples}, options.reach).rms;
  const SubdivisionMap map(triangles, baseVertices, choice.candidate);
  const DisplacementFitter fitter(map);
  const std::size_t n = map.fineVertices();
  std::vector<double> fine(3 * n), normals(3 * n), displaced(3 * n);
  map.subdivide(positions.data(), fine.data(), normals.data());
  const DisplacementFit fit = fitter.fit(fine.data(), normals.data(), data, options);
  displaceAlongNormals(fine.data(), normals.data(), fit.displacement.data(), n, displaced.data());
  const TriangleMesh fineMesh(map.fineTriangles(), n);
  choice.fineDistance = measureDataFit(fineMesh, displaced.data(), {&samples}, options.reach).rms;
  const bool gains = choice.fineDistance <= (1 - DetailGainThreshold) * choice.baseDistance;
  choice.levels = gains ? choice.candidate : 0;
  std::snprintf(text, sizeof(text),
                "%d level(s): frame 0's data lie %.3g from %d level(s) of detail (%zu vertices) "
                "and %.3g from the tracked mesh%s",
                choice.levels, choice.fineDistance, choice.candidate, n, choice.baseDistance,
                gains ? "" : ", too little gain for the bits: no detail layer");
  choice.summary = text;
  return choice;
}

} // namespace dp
