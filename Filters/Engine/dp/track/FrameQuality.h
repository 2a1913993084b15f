// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FrameQuality.h
 * @brief How well a tracked frame explains its data, from both directions: what the tracker
 *        uses to see that a frame failed (a limb lost, a part captured by the wrong data), and
 *        what the output and report carry per frame.
 *
 *   unexplained  the share of the frame's well-spread points farther than `reach` from the mesh
 *                surface, with three quarters of their 12 nearest points: a patch of data the
 *                mesh has let go of (a lost limb shows here, while the paper's mesh -> points
 *                energy stays low); points beyond the reach alone, scattered by noise or by
 *                detail finer than the template (fingertips, folds), do not count;
 *   unsupported  the share of the mesh (by vertex area) farther than `reach` from any point:
 *                mesh where there are no data (holes in the data, or a part in the wrong place);
 *   departed     the part of it the solve took off its data: within half `reach` of a point
 *                where the solve started, and most of its neighbours too (a part; a vertex
 *                alone over a hole's rim is none). A hole is no departure: there the start lies
 *                over the same missing data;
 *   tear         the most a stiff edge grew beyond its template length, in mean template edge
 *                lengths (largestEdgeGrowth): a limb caught by another limb's data as it passes
 *                is stretched between them in a strip that covers almost nothing, which neither
 *                share sees.
 *
 * Judged against the data's noise: the reach is at least six times the layer thickness the frame's
 * points have (FrameData::noise; at most three times the reach asked), and stray points (flying
 * pixels, stray returns: isolated or off the layer) count for neither share, so a frame that fits
 * as well as its noise allows explains its points.
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
  double departed = 0;
  double tear = 0;
  std::size_t samples = 0; // the points the unexplained share is of (stray ones left out)
  double noise = 0;        // the data's layer thickness, measured (SurfaceNoise.h)
  double reach = 0;        // the distance beyond which a point or a vertex was far
};

/** The quality of positions x (3 per vertex) against the frame; `mass` per vertex sums to 1;
 *  `start` (3 per vertex; null: nothing departs) where the solve started. The tear needs the
 *  rest shape and the stiffnesses: left 0 here (largestEdgeGrowth). */
FrameQuality assessFrame(const FrameData& frame, const TriangleMesh& mesh, const double* x,
                         const std::vector<double>& mass, double reach,
                         const double* start = nullptr);

/** The most any edge of `x` grew beyond its length in `rest`, in mean `rest` edge lengths, each
 *  edge's growth weighed by its stretch stiffness's scale (`scales` per edge, at most 1; empty:
 *  all 1). The surfaces tracked here (bodies, cloth, a collapse) stay well under two; edges made
 *  soft to stretch (creases, where a reconstruction joined two parts) may stretch more, and
 *  count less. */
double largestEdgeGrowth(const TriangleMesh& mesh, const std::vector<double>& rest,
                         const std::vector<double>& x, const std::vector<double>& scales);

} // namespace dp
