// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DetailOptions.h
 * @brief The detail layer's options, described once (OptionTable.h): how many subdivision levels,
 *        how far a fine vertex may move, how smooth the membrane, which data are another
 *        surface's. vtkSurfaceDetailFilter's accessors, its ParaView properties and the
 *        documentation's table are written from dp::detailOptions() (OptionCode.h).
 *
 * The reach is in mean edge lengths of the tracked mesh (the filter turns it into world units
 * with meanEdgeLength); the others are DisplacementFitOptions' as they are.
 */
#pragma once

#include "dp/detail/DisplacementFit.h"
#include "dp/io/OptionTable.h"

namespace dp
{

/** The subdivision levels that mean "measure them on the first frame" (chooseDetailLevels). */
constexpr int AutomaticDetailLevels = -1;

struct DetailOptions
{
  int levels = AutomaticDetailLevels; // 0: none (the tracked mesh passes through)
  double reach = 1;                   // mean edge lengths of the tracked mesh
  double smoothness = DisplacementFitOptions{}.smoothness;
  double normalAngle = DisplacementFitOptions{}.normalAngle; // degrees
};

/** The detail layer's option table. */
const OptionTable<DetailOptions>& detailOptions();

} // namespace dp
