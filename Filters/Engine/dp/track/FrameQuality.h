// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FrameQuality.h
 * @brief How well a tracked frame explains its data, from both directions: what the tracker
 *        uses to see that a frame failed (a limb lost, a part captured by the wrong data), and
 *        what the output and report carry per frame.
 *
 *   unexplained  the share of the frame's well-spread points farther than `reach` from the mesh
 *                surface: data the mesh has let go of (a lost limb shows here, while the paper's
 *                mesh -> points energy stays low);
 *   unsupported  the share of the mesh (by vertex area) farther than `reach` from any point:
 *                mesh where there are no data (holes in the data, or a part in the wrong place).
 *
 * With well-spread points both are shares of surface area. Limits: data the scanner saw but the
 * template lacks (a prop, a second person) count as unexplained; holes as unsupported.
 */
#pragma once

#include "dp/geometry/TriangleMesh.h"
#include "dp/track/FrameData.h"

#include <vector>

namespace dp
{

struct FrameQuality
{
  double unexplained = 0;
  double unsupported = 0;
};

/** The quality of positions x (3 per vertex) against the frame; `mass` per vertex sums to 1. */
FrameQuality assessFrame(const FrameData& frame, const TriangleMesh& mesh, const double* x,
                         const std::vector<double>& mass, double reach);

} // namespace dp
