// SPDX-License-Identifier: BSD-3-Clause
// What the main job leaves beside its outputs for one input: report.json and report.png, and
// the views of the take (view.html and the ParaView state).
#pragma once

#include "JobState.h"
#include "MainJob.h"

class vtkPointSequenceSource;

namespace dp::cli
{

/** report.json and report.png, named on stdout; then, unless --no-view or no frame was tracked,
 *  the page and the ParaView state, each named on a line of its own (a failure of theirs is
 *  said and changes nothing else). `points` is the source that read the take's points. */
void writeReport(const Settings& settings, const JobPaths& paths, const JobState& job,
                 vtkPointSequenceSource* points);

} // namespace dp::cli
