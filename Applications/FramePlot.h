// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FramePlot.h
 * @brief A PNG plot of per-frame values (the main job's report): panels stacked vertically,
 *        frame index along x, one or more lines per panel, ticks and labels.
 *
 * Drawn into an image in memory (lines by vtkImageCanvasSource2D, text by FreeType through
 * vtkFreeTypeTools) and written by vtkPNGWriter, so it needs no display and no OpenGL.
 * Limits: linear axes only; NaN values leave a gap in their line.
 */
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace dp::cli
{

struct PlotLine
{
  std::string label;
  std::vector<double> values; // one per frame
  std::array<unsigned char, 3> colour{31, 119, 180};
};

struct PlotPanel
{
  std::string yLabel;
  std::vector<PlotLine> lines;
  // Frames marked by a vertical red line across the panel (e.g. frames that failed), with a
  // legend entry when there are any.
  std::vector<std::size_t> marks;
  std::string marksLabel;
};

/** Writes `panels` to `path` (PNG, width x height per panel). Throws std::runtime_error when
 *  the file cannot be written. */
void writeFramePlot(const std::string& path, const std::string& title,
                    const std::vector<PlotPanel>& panels, int width = 960, int panelHeight = 320);

} // namespace dp::cli
