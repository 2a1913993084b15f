// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file TrackerOptionTable.h
 * @brief Every tracker option described once (an OptionTable over TrackerOptions): its name (the
 *        dotted path in TrackerOptions), kind, range, unit, one-line documentation, and where it
 *        is shown (the ParaView property that drives it and whether the panel shows it by
 *        default). Its default is the value in a default-constructed TrackerOptions.
 *
 * Everything else is derived from this table: the tracker's validation (checkTrackerOptions), the
 * filter's accessors (vtkDeformableTrackFilter::SetTrackerOption and the named ones over it), the
 * ParaView panel's properties, the command line (`--set NAME=VALUE`, `--options FILE.json`,
 * `--print-options`), report.json's record of the options a run used, the benchmark's flags, and
 * the documentation's table (Documentation/TrackerOptions.md).
 *
 * Adding an option: a field in TrackerOptions.h and a row in TrackerOptionTable.cxx (with a
 * property name where the panel shows it, and the panel's text: withHelp, shownWith); then
 * `build/bin/dp-option-code write .` writes the named accessors, the panel's property and the
 * documentation's row (OptionCode.h; a test fails until it has).
 */
#pragma once

#include "dp/io/OptionTable.h"
#include "dp/track/TrackerOptions.h"

namespace dp
{

using TrackerOptionDescription = OptionDescription<TrackerOptions>;

/** The table, in the order the documentation lists it. */
const OptionTable<TrackerOptions>& trackerOptions();

/** Throws std::invalid_argument naming the first option out of its range (NaN included), with
 *  the range it wants; also the conditions that tie two options together. */
void checkTrackerOptions(const TrackerOptions& options);

} // namespace dp
