// SPDX-License-Identifier: BSD-3-Clause
// The main job on one input: read, track, write frame by frame, compress, report.
#pragma once

#include "dp/compress/CompressionOptions.h"
#include "dp/field/TemplateMesh.h"
#include "dp/track/TrackerOptions.h"

#include "vtkDeformableTrackFilter.h"
#include "vtkSurfaceDetailFilter.h"

#include <string>
#include <vector>

namespace dp::cli
{

struct Settings
{
  std::vector<std::string> inputs; // as given; a batch when more than one
  std::string input, pattern = "*", output = "dynamicpoints-output", templateFile;
  int vertices = static_cast<int>(dp::TemplateOptions{}.targetVertices);
  int detailLevels = vtkSurfaceDetailFilter::AUTOMATIC; // --detail-levels; -1: from the data
  int templateFrom = vtkDeformableTrackFilter::TEMPLATE_AUTO;
  long long frames = 0; // 0: all
  bool quiet = false;
  bool meshopt = false;
  bool view = true; // view.html and paraview-state.py (--no-view: neither)
  // What to print instead of running: "values" (--print-options), "json" or "markdown"
  // (--describe-options), "report" (--describe-report).
  std::string printOptions;
  dp::TrackerOptions tracker; // --set, --options
  // --set compression.*, --fit-growth, --error-target, --colour-tolerance; judged against the
  // data unless told otherwise.
  dp::CompressionOptions compression = againstData();

  static dp::CompressionOptions againstData()
  {
    dp::CompressionOptions o;
    o.measure = dp::CompressionMeasure::DistanceToData;
    return o;
  }
};

/** One input's whole job; an error it did not foresee is its failure (said on stderr), not the
 *  batch's. Returns the exit status: 0, 1, or 130 when interrupted. */
int runJob(const Settings& settings);

} // namespace dp::cli
