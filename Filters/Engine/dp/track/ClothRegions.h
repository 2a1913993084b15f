// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file ClothRegions.h
 * @brief The cloth's stiffness by region of the template (ThicknessSoftening, CreaseSoftening):
 *        softer stretch on thick parts (a trunk, whose skin slides) and in creases (armpits,
 *        crotch), from the template's medial balls (LocalThickness) measured against its
 *        thickness (the 90th percentile of the inner radii).
 *
 * Beyond the paper (one stiffness everywhere). Thick parts: per vertex a softness in [0, 1] (the
 * smoothstep of the inner radius between `from` and `to`), per edge the mean of its ends', per
 * hinge that of its shared edge; only where the inner ball met the surface's other side (a sheet
 * or an open template keeps its stiffness). Creases: an edge with an end whose outer radius is
 * below `width` times the thickness has its stretch stiffness multiplied by `stretch`.
 */
#pragma once

#include "dp/track/ClothEnergy.h"
#include "dp/track/TrackerOptions.h"

namespace dp
{

class TriangleMesh;

/** Sets `cloth`'s stiffness scales by region of the template `positions` (3 per vertex of
 *  `mesh`); nothing when both softenings are off (factors 1). */
void softenByRegion(ClothEnergy& cloth, const TriangleMesh& mesh, const double* positions,
                    const ThicknessSoftening& thick, const CreaseSoftening& creases);

} // namespace dp
