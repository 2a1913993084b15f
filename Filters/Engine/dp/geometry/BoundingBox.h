// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file BoundingBox.h
 * @brief The size of a set of points: the diagonal of its axis-aligned bounding box, the length
 *        the engine's defaults are relative to (voxel = diagonal / 200, the reconstruction's
 *        and the benchmark's tolerances).
 */
#pragma once

#include <cstddef>
#include <vector>

namespace dp
{

/** Length of the diagonal of the bounding box of x y z triples. */
double boundingBoxDiagonal(const std::vector<double>& positions);
/** The same for `count` points (3 numbers each); 0 for none. */
double boundingBoxDiagonal(const double* positions, std::size_t count);

} // namespace dp
