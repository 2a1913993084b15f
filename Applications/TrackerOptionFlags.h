// SPDX-License-Identifier: BSD-3-Clause
// The command-line flags of the tracker's options, shared by dynamicpoints and the benchmarks:
// every option of dp::TrackerOptionTable by its name, none spelled out by hand.
//   --set NAME=VALUE   one option (repeatable), e.g. --set graph.yieldRate=0.5
//   --options FILE     a JSON object of options, as --print-options writes it
#pragma once

#include "CommandLine.h"

#include "dp/track/TrackerOptionTable.h"

#include <fstream>
#include <sstream>
#include <string>

namespace dp::cli
{

inline const char* const TrackerOptionHelp =
    R"(  --set NAME=VALUE    a tracker option (repeatable), e.g. --set graph.yieldRate=0.5;
                      --print-options lists them with their values, and
                      Documentation/TrackerOptions.md with their ranges and meaning
  --options FILE      tracker options from a JSON file, as --print-options writes it
  --print-options     print the tracker options, with --set and --options applied, as
                      JSON, and exit
  --describe-options F  print every tracker option's name, default, range, unit and
                      meaning, as json or markdown, and exit
)";

/** Takes `arg` (and its value) if it is a tracker option flag; false if it is not one.
 *  Throws UsageError naming the option and what it accepts. */
inline bool parseTrackerOptionFlag(const std::string& arg, int argc, char** argv, int& i,
                                   dp::TrackerOptions& options)
{
  try
  {
    if (arg == "--set")
    {
      const std::string assignment = optionValue(argc, argv, i);
      const std::size_t equals = assignment.find('=');
      if (equals == std::string::npos)
        throw UsageError("--set wants NAME=VALUE, not '" + assignment + "'");
      dp::setTrackerOption(options, assignment.substr(0, equals), assignment.substr(equals + 1));
      return true;
    }
    if (arg == "--options")
    {
      const std::string file = optionValue(argc, argv, i);
      std::ifstream in(file, std::ios::binary);
      if (!in)
        throw UsageError("--options: cannot read '" + file + "'");
      std::ostringstream text;
      text << in.rdbuf();
      dp::readTrackerOptionsJson(options, text.str(), file);
      return true;
    }
  }
  catch (const std::invalid_argument& e)
  {
    throw UsageError(arg + ": " + e.what());
  }
  return false;
}

} // namespace dp::cli
