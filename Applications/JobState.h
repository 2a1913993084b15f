// SPDX-License-Identifier: BSD-3-Clause
// What the main job on one input keeps as it goes: where its files are and what each stage found,
// which its summaries on the console and its report are made of.
#pragma once

#include "FrameReport.h"

#include "dp/export/GltfExport.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace dp::cli
{

/** The files the main job writes for one input, in its OUTPUT folder. */
struct JobPaths
{
  explicit JobPaths(const std::filesystem::path& folder)
      : output(folder), pvd(output / "tracked.pvd"), dpz(output / "tracked.dpz"),
        glb(output / "tracked.glb"), page(output / "view.html"), state(output / "paraview-state.py")
  {
  }
  const std::filesystem::path output, pvd, dpz, glb, page, state;
};

/** What the main job on one input found so far, stage by stage. */
struct JobState
{
  const std::chrono::steady_clock::time_point started = std::chrono::steady_clock::now();
  std::string inputName;
  int frames = 0;
  bool failed = false;
  std::vector<std::pair<double, std::string>> written; // (time, file) of each frame written
  std::vector<FrameRecord> records;
  double diagonal = 0;
  long long meshVertices = 0, meshTriangles = 0;
  std::string templateMade; // what the template was made from, and how
  int detailLevels = 0;
  long long fineVertices = 0;
  std::string detailChoice; // what the detail layer's levels were chosen from
  dp::GlbSummary glbWritten;
  std::vector<unsigned char> pageGlb; // the plain .glb's bytes, for the page
  nlohmann::json compression;         // report.json's "compression"
};

} // namespace dp::cli
