// SPDX-License-Identifier: BSD-3-Clause
// The main job's per-frame record and what report.json and report.png make of it.
#pragma once

#include "dp/track/FrameFigures.h"

#include "vtkDataObject.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace dp::cli
{

/** A tracked frame in the table and the report: its distance to the points, and what the track
 *  filter said of it (its field data, read back by the table that wrote it: dp::FrameFigures). */
struct FrameRecord
{
  int frame;
  double time, rmsResidual, maxResidual;
  dp::FrameFigures figures;
  double detailSeconds = 0; // the detail layer's fit (vtkSurfaceDetailFilter), 0 without one
  bool failed() const { return figures.failed > 0; }
  /** The frame's time: its tracking and its detail layer. */
  double milliseconds() const { return 1000 * (figures.seconds + detailSeconds); }
};

/** The one-value field-data array `name` of `data` (NaN when absent). */
double fieldValue(vtkDataObject* data, const char* name);
/** The track filter's figures of a frame, read from its output's field data. */
dp::FrameFigures figuresOf(vtkDataObject* mesh);
/** The upper median (0 for none). */
double medianOf(std::vector<double> values);
/** A frame in report.json: its distance to the points, then every figure of dp::FrameFigures. */
nlohmann::json frameJson(const FrameRecord& r);
/** Each stage's median seconds over the frames. */
nlohmann::json stageMediansJson(const std::vector<FrameRecord>& records);
/** report.png: the distance to the points (in % of `diagonal` when it is positive), the
 *  quality, the largest stretch and the time, per frame, the failed frames marked. */
void writeReportPlot(const std::string& path, const std::string& title,
                     const std::vector<FrameRecord>& records, double diagonal);

} // namespace dp::cli
