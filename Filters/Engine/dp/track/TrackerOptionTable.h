// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file TrackerOptionTable.h
 * @brief Every tracker option described once: its name (the dotted path in TrackerOptions),
 *        kind, range, unit, one-line documentation, and where it is shown (the ParaView
 *        property that drives it and whether the panel shows it by default). Its default is the
 *        value in a default-constructed TrackerOptions (TrackerOptions.h), read from there.
 *
 * Everything else is derived from this table or checked against it: the tracker's validation
 * (checkTrackerOptions), the filter's accessors (vtkDeformableTrackFilter::SetTrackerOption and
 * the named setters over it), the command line (`--set NAME=VALUE`, `--options FILE.json`,
 * `--print-options`), the benchmark's flags, and the documentation table
 * (Documentation/TrackerOptions.md). A test compares the ParaView XML with it.
 *
 * Adding an option: a field in TrackerOptions.h and a row in TrackerOptionTable.cxx; where the
 * ParaView panel should show it, a property in the XML and two accessors in the filter.
 */
#pragma once

#include "dp/track/TrackerOptions.h"

#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace dp
{

enum class OptionKind
{
  Real,
  Integer,
  Flag,  // 0 or 1
  Choice // an index into `choices`
};

/** Where ParaView's panel shows an option (every option is also on the command line, in C++
 *  and in Python, through its name). */
enum class OptionPanel
{
  Shown,    // the panel's default view
  Advanced, // behind the panel's gear
  None      // no property: `--set`, SetTrackerOption or TrackerOptions only
};

struct TrackerOptionDescription
{
  std::string name;     // the dotted path in TrackerOptions: "graph.yieldRate"
  std::string property; // the filter's and ParaView's name ("Plasticity"); empty: none
  OptionKind kind = OptionKind::Real;
  double minimum = 0; // the range, inclusive
  double maximum = 0;
  bool zeroAllowed = false; // 0 (automatic, or off) is accepted below the minimum
  std::string unit;         // "world units", "voxels", "degrees", "" (none)
  std::string doc;          // one line
  OptionPanel panel = OptionPanel::None;
  std::vector<std::string> choices; // Choice: the names, by the value the filter uses
  std::function<double(const TrackerOptions&)> get;
  std::function<void(TrackerOptions&, double)> set;

  bool accepts(double value) const;
  std::string range() const; // "[0, 1]", "0 or [100, 1e+09]", "planes|points"
};

/** The table, in the order the documentation lists it. */
const std::vector<TrackerOptionDescription>& trackerOptionTable();

/** The option of that name or ParaView property name; std::invalid_argument if none. */
const TrackerOptionDescription& trackerOption(std::string_view nameOrProperty);

/** Throws std::invalid_argument naming the first option out of its range (NaN included), with
 *  the range it wants; also the conditions that tie two options together. */
void checkTrackerOptions(const TrackerOptions& options);

/** Sets an option from text: a number, true/false/on/off for a flag, a choice's name or index.
 *  Throws std::invalid_argument naming the option and what it accepts. */
void setTrackerOption(TrackerOptions& options, std::string_view name, std::string_view text);

/** The options as one flat JSON object, {"graph.yieldRate": 0.3, ...}: choices by name, flags as
 *  true/false. readTrackerOptionsJson reads it back (any subset of the names). */
std::string trackerOptionsJson(const TrackerOptions& options);
void readTrackerOptionsJson(TrackerOptions& options, const std::string& json,
                            const std::string& source);

/** The table as JSON (name, property, kind, default, range, unit, doc, panel, choices): what the
 *  tests compare the ParaView XML and the documentation with. */
std::string trackerOptionTableJson();

/** The table as the Markdown of Documentation/TrackerOptions.md. */
std::string trackerOptionTableMarkdown();

} // namespace dp
