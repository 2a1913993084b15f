// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file CompressionFigures.h
 * @brief A compressed take's figures, declared once: what the codec filter writes as field data
 *        (one one-value array per figure, named as in fields()), what the main job copies into
 *        report.json's "compression" under the same names, and what the documentation lists.
 *
 * A figure that does not apply (no colour, no detail layer, a target of the motion's, so no
 * distance to the data) is NaN and is written nowhere.
 */
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

namespace dp
{

struct CompressedSequence;

struct CompressionFigures
{
  static constexpr double None = std::numeric_limits<double>::quiet_NaN();

  double components = 0;
  double layout = 0; // 0 trajectories, 1 shapes
  double paperD0 = 0, paperD1 = 0, paperRatio = 0;
  double bitsPerVertexFrame = 0;
  double quantisedPlainBits = 0;
  double kgError = 0, maxError = 0, maxErrorRelative = 0, rmsError = 0;
  double componentsPerFrame = 0;
  double colourBytes = None, colourTolerance = None;
  // Against the data (the measure `data`): the RMS distance to it before and after, the growth.
  double distanceToDataInput = None, distanceToDataDecompressed = None, distanceToDataGrowth = None;
  double slid = None; // 1: the take slid along its surface was kept (fewer bits)
  // The detail layer.
  double detailLevels = None, detailBytes = None, detailStep = None;
  double detailDistanceToDataInput = None, detailDistanceToDataDecompressed = None,
         detailDistanceToDataGrowth = None;

  /** A figure: its name (field data and report.json), the member holding it, a description,
   *  and whether it is a count (report.json writes it as an integer). */
  struct Field
  {
    const char* name;
    double CompressionFigures::*value;
    const char* doc;
    bool count = false;
  };
  static const std::vector<Field>& fields();

  /** The codec's own figures of `sequence` (of `frames` frames); the rest stay None for the
   *  caller to fill. */
  static CompressionFigures of(const CompressedSequence& sequence, std::size_t frames);

  /** The figures as a Markdown table (field data and report.json, what): the documentation's. */
  static std::string markdown();
};

} // namespace dp
