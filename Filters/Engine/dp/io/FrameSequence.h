// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FrameSequence.h
 * @brief The list of files (and times) that make up a point sequence.
 *
 * Three ways in, as a VTK/ParaView user expects:
 *  - a folder plus a glob pattern (`*`, `?`, `[abc]`), sorted naturally (`2.ply` before `10.ply`);
 *  - a ParaView `.series` JSON file (`{"file-series-version":"1.0","files":[{"name","time"}]}`),
 *    names relative to the .series file's folder;
 *  - an explicit list of paths, kept in the given order.
 * Frames without an explicit time get `index * frameInterval`.
 *
 * Only names are listed here: no frame file is opened, so building a sequence costs
 * O(number of files) directory work and nothing per point.
 */
#pragma once

#include <string>
#include <vector>

namespace dp
{

struct Frame
{
  std::string path;
  double time = 0.0;
};

class FrameSequence
{
public:
  /** Files in `directory` whose names match `pattern` and have a readable extension. */
  static FrameSequence fromDirectory(const std::string& directory, const std::string& pattern = "*",
                                     double frameInterval = 1.0);
  /** Frames and times listed in a ParaView .series JSON file. */
  static FrameSequence fromSeriesFile(const std::string& seriesPath);
  /** The given files in the given order. */
  static FrameSequence fromFiles(const std::vector<std::string>& paths, double frameInterval = 1.0);

  const std::vector<Frame>& frames() const { return Frames; }
  std::size_t size() const { return Frames.size(); }
  bool empty() const { return Frames.empty(); }
  const Frame& operator[](std::size_t i) const { return Frames[i]; }

  /** Index of the frame to show at `time`: the last frame whose time is <= time (clamped). */
  std::size_t frameAtTime(double time) const;

private:
  std::vector<Frame> Frames;
};

/** "Natural" order: digit runs compare as numbers, so frame2 < frame10. */
bool naturalLess(const std::string& a, const std::string& b);

/** Shell-style glob match of a file name: `*`, `?` and `[...]` character classes. */
bool globMatch(const std::string& pattern, const std::string& name);

} // namespace dp
