// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FrameFigures.h
 * @brief One tracked frame's figures, declared once: what the track filter writes as field data
 *        (one one-value array per figure, named as in fields()), what the main job reads back
 *        into this same record and writes into report.json (the same names, first letter in
 *        lower case), and what the documentation lists.
 *
 * The figures of a FrameResult a user reads per frame: its data, its solve, its time by stage
 * and its quality (FrameQuality, RecoveryPolicy). Plain numbers (counts and flags too), so one
 * table serves every consumer.
 */
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace dp
{

struct FrameResult;

struct FrameFigures
{
  double frameIndex = 0;
  double points = 0;           // the frame's points
  double iterations = 0;       // the fine level's steps (the kept attempt)
  double coarseIterations = 0; // the coarse level's steps (the kept attempt)
  double internalEnergy = 0;
  double distanceEnergy = 0;
  double seconds = 0;           // the frame's wall time
  double overlappedSeconds = 0; // of its data's preparation, what ran beside the frame before
  double dataSeconds = 0;       // field, normals, subsample
  double predictionSeconds = 0; // the kept attempt's stages
  double coarseSeconds = 0;
  double fineSeconds = 0;
  double qualitySeconds = 0;
  double retrySeconds = 0; // the other attempts
  double emptyFrame = 0;
  double unexplained = 0;    // share of the points beyond the reach from the mesh
  double unsupported = 0;    // share of the mesh beyond the reach from the points
  double largestStretch = 0; // of a stiff edge, in mean edge lengths (above 2: torn)
  double retries = 0;
  double failed = 0;
  double dataReach = 0; // how far from the mesh a point still counts as explained
  double dataNoise = 0; // the data's layer thickness, measured around the frame's points
  double seen = 0;      // share of the mesh the data see (within the reach of a point)

  enum class Kind
  {
    Number,
    Count,
    Flag // 0 or 1
  };
  /** A figure: its name (field data), the member holding it, its kind, a one-line description. */
  struct Field
  {
    const char* name;
    double FrameFigures::*value;
    Kind kind;
    const char* doc;
  };
  static const std::vector<Field>& fields();
  /** The stage times, in the order fields() lists them (DataSeconds ... RetrySeconds). */
  static const std::vector<Field>& stages();

  /** A tracked frame's figures; `reach` in world units (Tracker: recovery.reach voxels). */
  static FrameFigures of(const FrameResult& result, std::size_t frame, double reach);

  /** A field's name as report.json spells it: "LargestStretch" -> "largestStretch". */
  static std::string reportKey(const char* name);

  /** The figures as a Markdown table (field data, report.json, what): the documentation's. */
  static std::string markdown();
};

} // namespace dp
