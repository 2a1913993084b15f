// SPDX-License-Identifier: BSD-3-Clause
#include "dp/geometry/BoundingBox.h"

#include <algorithm>
#include <cmath>

namespace dp
{

double boundingBoxDiagonal(const std::vector<double>& positions)
{
  return boundingBoxDiagonal(positions.data(), positions.size() / 3);
}

double boundingBoxDiagonal(const double* positions, std::size_t count)
{
  if (count == 0)
    return 0.0;
  double lo[3] = {positions[0], positions[1], positions[2]}, hi[3] = {lo[0], lo[1], lo[2]};
  for (std::size_t i = 0; i < 3 * count; i += 3)
    for (int k = 0; k < 3; ++k)
    {
      lo[k] = std::min(lo[k], positions[i + k]);
      hi[k] = std::max(hi[k], positions[i + k]);
    }
  return std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                   (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

} // namespace dp
