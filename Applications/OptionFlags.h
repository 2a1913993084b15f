// SPDX-License-Identifier: BSD-3-Clause
// The command-line flags of the option tables, shared by dynamicpoints and the benchmarks: every
// option of dp::trackerOptions() and dp::compressionOptions() by its name, none spelled out by
// hand.
//   --set NAME=VALUE   one option (repeatable), e.g. --set graph.yieldRate=0.5,
//                      --set compression.layout=shapes
//   --options FILE     a JSON object of options, as --print-options writes it
#pragma once

#include "CommandLine.h"

#include "dp/compress/CompressionOptions.h"
#include "dp/track/TrackerOptionTable.h"

#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>
#include <string>

namespace dp::cli
{

/** The options a run takes from the tables; `compression` is null where the program compresses
 *  nothing (the tracker's benchmark). */
struct TableOptions
{
  dp::TrackerOptions* tracker = nullptr;
  dp::CompressionOptions* compression = nullptr;
};

inline const char* const OptionHelp =
    R"(  --set NAME=VALUE    a tracker or compression option (repeatable), e.g.
                      --set graph.yieldRate=0.5, --set compression.layout=shapes;
                      --print-options lists them with their values, and
                      Documentation/TrackerOptions.md and Compression.md with their
                      ranges and meaning
  --options FILE      options from a JSON file, as --print-options writes it
  --print-options     print the options, with --set and --options applied, as JSON,
                      and exit
  --describe-options F  print every option's name, default, range, unit and meaning,
                      as json or markdown, and exit
)";

/** Sets option `name` (a tracker or, where `into` has them, a compression option) from text. */
inline void setTableOption(const TableOptions& into, const std::string& name,
                           const std::string& text)
{
  if (into.compression && dp::compressionOptions().has(name))
    dp::compressionOptions().set(*into.compression, name, text);
  else
    dp::trackerOptions().set(*into.tracker, name, text);
}

/** A flag that is a shortcut for one option (--fit-growth P: compression.fitGrowth): its value
 *  set as --set would, an error said as the flag's (UsageError). */
inline void setShortcut(const std::string& arg, int argc, char** argv, int& i,
                        const TableOptions& into, const std::string& name)
{
  const std::string text = optionValue(argc, argv, i);
  try
  {
    setTableOption(into, name, text);
  }
  catch (const std::invalid_argument& e)
  {
    throw UsageError(arg + ": " + e.what());
  }
}

/** Takes `arg` (and its value) if it is an option-table flag; false if it is not one. Throws
 *  UsageError naming the option and what it accepts. */
inline bool parseTableOptionFlag(const std::string& arg, int argc, char** argv, int& i,
                                 const TableOptions& into)
{
  try
  {
    if (arg == "--set")
    {
      const std::string assignment = optionValue(argc, argv, i);
      const std::size_t equals = assignment.find('=');
      if (equals == std::string::npos)
        throw UsageError("--set wants NAME=VALUE, not '" + assignment + "'");
      setTableOption(into, assignment.substr(0, equals), assignment.substr(equals + 1));
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
      for (const auto& [name, value] : dp::option_forms::jsonMembers(text.str(), file))
      {
        try
        {
          setTableOption(into, name, value);
        }
        catch (const std::invalid_argument& e)
        {
          throw std::invalid_argument(file + ": " + e.what());
        }
      }
      return true;
    }
  }
  catch (const std::invalid_argument& e)
  {
    throw UsageError(arg + ": " + e.what());
  }
  return false;
}

/** The options' values as one flat JSON object (tracker options, then compression options). */
inline nlohmann::ordered_json tableOptionsJson(const dp::TrackerOptions& tracker,
                                               const dp::CompressionOptions* compression)
{
  nlohmann::ordered_json all =
      nlohmann::ordered_json::parse(dp::trackerOptions().valuesJson(tracker));
  if (!compression)
    return all;
  const nlohmann::ordered_json more =
      nlohmann::ordered_json::parse(dp::compressionOptions().valuesJson(*compression));
  for (const auto& [name, value] : more.items())
    all[name] = value;
  return all;
}

/** The compression options for --help: name, range, default (`defaults`: the program's) and
 *  what each does, wrapped to the help's width. */
inline std::string compressionOptionHelp(const dp::CompressionOptions& defaults)
{
  std::string out;
  for (const auto& option : dp::compressionOptions())
  {
    std::string text = option.range() + " (default " + option.said(option.get(defaults)) +
                       (option.unit.empty() ? "" : " " + option.unit) + "): " + option.doc;
    out += "  " + option.name + "\n";
    std::string line = "                     ";
    std::istringstream words(text);
    for (std::string word; words >> word;)
    {
      if (line.size() + word.size() + 1 > 90)
      {
        out += line + "\n";
        line = "                     ";
      }
      line += " " + word;
    }
    out += line + "\n";
  }
  return out;
}

} // namespace dp::cli
