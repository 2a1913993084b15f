// SPDX-License-Identifier: BSD-3-Clause
#include "FrameReport.h"

#include "FramePlot.h"

#include "vtkDataArray.h"
#include "vtkFieldData.h"

#include <algorithm>
#include <cmath>

namespace dp::cli
{

namespace
{
// A figure in report.json: counts as integers, flags as true/false.
nlohmann::json figureJson(const dp::FrameFigures& figures, const dp::FrameFigures::Field& field)
{
  const double v = figures.*field.value;
  if (field.kind == dp::FrameFigures::Kind::Flag)
    return v > 0;
  if (field.kind == dp::FrameFigures::Kind::Count)
    return static_cast<long long>(v);
  return v;
}
} // namespace

double fieldValue(vtkDataObject* data, const char* name)
{
  vtkDataArray* a = vtkArrayDownCast<vtkDataArray>(data->GetFieldData()->GetAbstractArray(name));
  return a && a->GetNumberOfTuples() > 0 ? a->GetComponent(0, 0) : std::nan("");
}

dp::FrameFigures figuresOf(vtkDataObject* mesh)
{
  dp::FrameFigures figures;
  for (const dp::FrameFigures::Field& field : dp::FrameFigures::fields())
    figures.*field.value = fieldValue(mesh, field.name);
  return figures;
}

// The upper median (0 for none): report.json's per-frame medians.
double medianOf(std::vector<double> values)
{
  if (values.empty())
    return 0.0;
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

nlohmann::json frameJson(const FrameRecord& r)
{
  nlohmann::json frame = {{"frame", r.frame},
                          {"time", r.time},
                          {"rmsResidual", r.rmsResidual},
                          {"maxResidual", r.maxResidual}};
  for (const dp::FrameFigures::Field& field : dp::FrameFigures::fields())
    frame[dp::FrameFigures::reportKey(field.name)] = figureJson(r.figures, field);
  frame["detailSeconds"] = r.detailSeconds;
  return frame;
}

nlohmann::json stageMediansJson(const std::vector<FrameRecord>& records)
{
  nlohmann::json medians = nlohmann::json::object();
  for (const dp::FrameFigures::Field& stage : dp::FrameFigures::stages())
  {
    std::vector<double> seconds;
    for (const FrameRecord& r : records)
      seconds.push_back(r.figures.*stage.value);
    medians[dp::FrameFigures::reportKey(stage.name)] = medianOf(std::move(seconds));
  }
  std::vector<double> detail;
  for (const FrameRecord& r : records)
    detail.push_back(r.detailSeconds);
  medians["detailSeconds"] = medianOf(std::move(detail));
  return medians;
}

void writeReportPlot(const std::string& path, const std::string& title,
                     const std::vector<FrameRecord>& records, double diagonal)
{
  std::vector<double> rms, largest, ms, unexplained, unsupported, stretch;
  std::vector<std::size_t> failed;
  for (const FrameRecord& r : records)
  {
    unexplained.push_back(100 * r.figures.unexplained);
    unsupported.push_back(100 * r.figures.unsupported);
    stretch.push_back(r.figures.largestStretch);
    if (r.failed())
      failed.push_back(static_cast<std::size_t>(r.frame));
    rms.push_back(diagonal > 0 ? 100 * r.rmsResidual / diagonal : r.rmsResidual);
    largest.push_back(diagonal > 0 ? 100 * r.maxResidual / diagonal : r.maxResidual);
    ms.push_back(r.milliseconds());
  }
  const dp::cli::PlotPanel residualPanel{
      "distance to the points, % of diagonal",
      {{"RMS", rms, {31, 119, 180}}, {"largest", largest, {255, 127, 14}}},
      {},
      ""};
  const dp::cli::PlotPanel qualityPanel{"beyond 3 voxels, %",
                                        {{"points far from mesh", unexplained, {148, 103, 189}},
                                         {"mesh far from points", unsupported, {140, 86, 75}}},
                                        failed,
                                        "failed frame"};
  const dp::cli::PlotPanel stretchPanel{"largest stretch, edge lengths (2: torn)",
                                        {{"stiffest edge's growth", stretch, {23, 190, 207}}},
                                        failed,
                                        "failed frame"};
  const dp::cli::PlotPanel timePanel{
      "tracking time, ms", {{"per frame", ms, {44, 160, 44}}}, {}, ""};
  dp::cli::writeFramePlot(path, title, {residualPanel, qualityPanel, stretchPanel, timePanel});
}

} // namespace dp::cli
