// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file RigidAlignment.h
 * @brief Moves a shape rigidly onto the frame's data before a deformable solve without the
 *        coarse level: point-to-plane ICP of the whole mesh, minimising the distance term
 *        sum_v c_v D_v(R x_v + t)^2 over a rotation R and a translation t with each vertex's
 *        quadric (its tangent planes held) as its model, each step kept only if the term falls.
 *
 * It moves only along the rigid motions the data pin down at least a fifth as firmly as the
 * firmest (on a flat or round part, sliding along the surface changes no plane distance, and a
 * step there would follow the noise: a waving sheet slid along its waves). Rotations act on
 * r / radius so both halves of the 6x6 system have the same units and the result does not depend
 * on the data's scale.
 */
#pragma once

#include "dp/track/DistanceTerm.h"

#include <vector>

namespace dp
{

/** Aligns x (3 per vertex) in place; returns the steps kept. */
int alignRigidly(std::vector<double>& x, const DistanceTerm& distance);

} // namespace dp
