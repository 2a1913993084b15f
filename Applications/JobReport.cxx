// SPDX-License-Identifier: BSD-3-Clause
#include "JobReport.h"

#include "CommandLine.h"
#include "Console.h"
#include "Viewer.h"

#include "dp/compress/CompressionOptions.h"
#include "dp/track/TrackerOptionTable.h"

#include "vtkDeformableTrackFilter.h"
#include "vtkPointSequenceSource.h"

#include <chrono>
#include <filesystem>
#include <iostream>
#include <string>
#include <system_error>
#include <vector>

namespace dp::cli
{

namespace
{
namespace fs = std::filesystem;

// The options the run used, by the names --set and --options take (the tables'), and the
// main job's own.
nlohmann::json optionsJson(const Settings& settings)
{
  return {
      {"tracker", nlohmann::json::parse(dp::trackerOptions().valuesJson(settings.tracker))},
      {"compression",
       nlohmann::json::parse(dp::compressionOptions().valuesJson(settings.compression))},
      {"vertices", settings.vertices},
      {"templateFrom",
       settings.templateFrom == vtkDeformableTrackFilter::TEMPLATE_FROM_MESH     ? "mesh"
       : settings.templateFrom == vtkDeformableTrackFilter::TEMPLATE_FROM_POINTS ? "points"
                                                                                 : "auto"},
      {"detailLevels",
       settings.detailLevels < 0 ? nlohmann::json("auto") : nlohmann::json(settings.detailLevels)},
      {"frames", settings.frames > 0 ? nlohmann::json(settings.frames) : nlohmann::json("all")}};
}

// What was tracked: the input and its frames, the template, the detail layer, the options.
nlohmann::json trackedJson(const Settings& settings, const JobState& job)
{
  nlohmann::json report;
  report["input"] = job.inputName;
  report["frames"] = job.frames;
  report["framesTracked"] = job.written.size();
  report["interrupted"] = Interrupted != 0;
  report["template"] = {
      {"source", settings.templateFile.empty() ? "frame 0" : settings.templateFile},
      {"made", job.templateMade},
      {"vertices", job.meshVertices},
      {"triangles", job.meshTriangles}};
  report["detail"] = {{"levels", job.detailLevels},
                      {"asked", settings.detailLevels < 0 ? std::string("automatic")
                                                          : std::to_string(settings.detailLevels)},
                      {"choice", job.detailChoice},
                      {"fineVertices", job.detailLevels > 0 ? job.fineVertices : job.meshVertices}};
  report["boundingBoxDiagonal"] = job.diagonal;
  report["options"] = optionsJson(settings);
  return report;
}

// Each frame's figures ("perFrame"), the frames retried and failed, the median times.
void addFrames(nlohmann::json& report, const std::vector<FrameRecord>& records)
{
  nlohmann::json perFrame = nlohmann::json::array(), failedFrames = nlohmann::json::array();
  std::vector<double> ms;
  int retried = 0;
  for (const FrameRecord& r : records)
  {
    perFrame.push_back(frameJson(r));
    retried += r.figures.retries > 0 ? 1 : 0;
    if (r.failed())
      failedFrames.push_back(r.frame);
    ms.push_back(r.milliseconds());
  }
  report["perFrame"] = perFrame;
  report["framesRetried"] = retried;
  report["framesFailed"] = failedFrames;
  report["medianMillisecondsPerFrame"] = medianOf(ms);
  report["medianStageSecondsPerFrame"] = stageMediansJson(records);
}

// The files written, by what they hold; `viewed`: the views are written too.
nlohmann::json outputsJson(const JobPaths& paths, const JobState& job, const fs::path& plot,
                           bool viewed)
{
  nlohmann::json outputs = {{"tracked", paths.pvd.string()}, {"plot", plot.string()}};
  if (!job.compression.empty())
  {
    outputs["compressed"] = paths.dpz.string();
    outputs["gltf"] = paths.glb.string();
  }
  if (viewed)
  {
    outputs["paraviewState"] = paths.state.string();
    if (!job.pageGlb.empty() && viewerAvailable())
      outputs["page"] = paths.page.string();
  }
  return outputs;
}

// The DynamicPoints ParaView plugin beside this program's build or install
// (bin/../lib/paraview-plugins/DynamicPoints/DynamicPoints.so), empty when there is none.
std::string pluginPath()
{
  std::error_code error;
  const fs::path self = fs::read_symlink("/proc/self/exe", error);
  const fs::path plugin = self.parent_path().parent_path() / "lib" / "paraview-plugins" /
                          "DynamicPoints" / "DynamicPoints.so";
  return !error && fs::exists(plugin) ? plugin.string() : std::string();
}

// The page (view.html: the take in any browser) and the ParaView state, each named on a line
// of its own, the last lines of the job; a failure is said and changes nothing else.
void writeViews(const nlohmann::json& report, const Settings& settings, const JobPaths& paths,
                const JobState& job, vtkPointSequenceSource* points)
{
  try
  {
    StateInputs state;
    state.tracked = fs::absolute(paths.pvd).string();
    state.points = fs::absolute(points->GetDirectoryName() ? points->GetDirectoryName()
                                                           : points->GetFileName())
                       .string();
    state.pattern = points->GetDirectoryName() ? settings.pattern : std::string();
    state.plugin = pluginPath();
    state.largestResidual = job.records.front().maxResidual;
    writeParaViewState(paths.state.string(), state);
    if (!job.pageGlb.empty() && viewerAvailable())
    {
      writeViewerPage(paths.page.string(), job.pageGlb, report);
      std::cout << "Page: " << paths.page.string()
                << " (the take in a browser, from the file system)\n";
    }
    else if (!job.pageGlb.empty())
      std::cerr << "warning: no view.html: this build of dynamicpoints has no three.js "
                   "(Utilities/dp.sh installs it from npm)\n";
    std::cout << "ParaView: paraview --state=" << paths.state.string() << "\n";
  }
  catch (const std::exception& e)
  {
    std::cerr << "warning: " << e.what() << "\n";
  }
}

} // namespace

void writeReport(const Settings& settings, const JobPaths& paths, const JobState& job,
                 vtkPointSequenceSource* points)
{
  nlohmann::json report = trackedJson(settings, job);
  addFrames(report, job.records);
  if (!job.compression.empty())
    report["compression"] = job.compression;
  const fs::path plot = paths.output / "report.png";
  const bool viewed = settings.view && !job.records.empty();
  report["outputs"] = outputsJson(paths, job, plot, viewed);
  report["wallSeconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - job.started).count();
  writeAtomically(paths.output / "report.json", report.dump(1) + "\n");
  writeReportPlot(plot.string(), "DynamicPoints: " + fs::path(job.inputName).filename().string(),
                  job.records, job.diagonal);
  std::cout << "Report: " << (paths.output / "report.json").string() << ", " << plot.string()
            << "\n";
  if (viewed)
    writeViews(report, settings, paths, job, points);
}

} // namespace dp::cli
