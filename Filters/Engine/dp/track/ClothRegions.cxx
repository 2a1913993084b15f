// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/ClothRegions.h"

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/LocalThickness.h"
#include "dp/geometry/TriangleMesh.h"

#include <algorithm>
#include <vector>

namespace dp
{

void softenByRegion(ClothEnergy& cloth, const TriangleMesh& mesh, const double* positions,
                    const ThicknessSoftening& thick, const CreaseSoftening& creases)
{
  const bool softThick = thick.stretch != 1.0 || thick.bend != 1.0;
  const bool softCreases = creases.stretch != 1.0 && creases.width > 0;
  if (!softThick && !softCreases)
    return;
  const std::size_t n = mesh.numberOfVertices();
  const double largest = 0.5 * boundingBoxDiagonal(positions, n);
  const std::vector<double> ball = medialRadii(mesh, positions, largest, 0);
  const std::vector<double> inner = smoothOverRings(mesh, ball, 3);
  std::vector<double> sorted = inner;
  const auto rank = sorted.begin() + static_cast<std::ptrdiff_t>(0.9 * static_cast<double>(n - 1));
  std::nth_element(sorted.begin(), rank, sorted.end());
  const double thickness = *rank;
  std::vector<double> softness(n, 0.0);
  if (softThick)
    for (std::size_t v = 0; v < n; ++v)
    {
      // Thick only where the ball inside met the other side: where it met nothing (a sheet, a
      // template open there) the surface is no trunk, and its stiffness is kept.
      if (!(ball[v] < largest))
        continue;
      const double s =
          std::clamp((inner[v] / thickness - thick.from) / (thick.to - thick.from), 0.0, 1.0);
      softness[v] = s * s * (3 - 2 * s);
    }
  std::vector<bool> crease(n, false);
  if (softCreases)
  {
    // One smoothing pass: a crease is a few vertices wide.
    const std::vector<double> outer = medialRadii(mesh, positions, largest, 1, MedialSide::Outside);
    for (std::size_t v = 0; v < n; ++v)
      crease[v] = outer[v] < creases.width * thickness;
  }
  const auto blend = [](double factor, double s) { return 1.0 + s * (factor - 1.0); };
  std::vector<double> stretch, bend;
  for (const auto& e : mesh.edges())
    stretch.push_back(blend(thick.stretch, 0.5 * (softness[e[0]] + softness[e[1]])) *
                      (crease[e[0]] || crease[e[1]] ? creases.stretch : 1.0));
  for (const auto& h : mesh.hinges())
    bend.push_back(blend(thick.bend, 0.5 * (softness[h[0]] + softness[h[1]])));
  cloth.setStiffnessScales(std::move(stretch), std::move(bend));
}

} // namespace dp
