// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file OptionTable.h
 * @brief A table that describes every option of an options struct once: its name, kind, range,
 *        unit, one-line documentation and where ParaView's panel shows it, with accessors into
 *        the struct. Its default is the value in a default-constructed struct, read from there.
 *
 * Everything a front end needs follows from a table: validation (check), text and JSON values
 * (set, valuesJson, readJson: the command line's `--set NAME=VALUE` and `--options FILE`, a
 * report's record of the options a run used), a filter's generic accessor (clamped), and the
 * descriptions (describeJson, which the tests compare the ParaView XML with; describeMarkdown,
 * the documentation's table). The tables: dp::trackerOptions() (TrackerOptionTable.h) and
 * dp::compressionOptions() (CompressionOptions.h).
 *
 * Every value is held as a double: integers, flags (0/1) and choices (an index) included.
 */
#pragma once

#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
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

/** Where ParaView's panel shows an option (every option is also reached by its name on the
 *  command line, in C++ and in Python). */
enum class OptionPanel
{
  Shown,    // the panel's default view
  Advanced, // behind the panel's gear
  None      // no property: the name only
};

/** An upper bound that is none ("inf" in a range). */
constexpr double Unbounded = std::numeric_limits<double>::max();

/** What a table says of one option, apart from where the struct holds it. */
struct OptionSpec
{
  std::string name;     // the dotted path in the struct: "graph.yieldRate"
  std::string property; // the filter's and ParaView's name ("Plasticity"); empty: none
  OptionKind kind = OptionKind::Real;
  double minimum = 0; // the range, inclusive
  double maximum = 0;
  bool zeroAllowed = false; // 0 (automatic, or off) is accepted below the minimum
  std::string unit;         // "world units", "voxels", "degrees", "" (none)
  std::string doc;          // one line
  OptionPanel panel = OptionPanel::None;
  std::vector<std::string> choices; // Choice: the names, by the value the filter uses
  // How the panel and the VTK class present it (OptionCode.h writes both from these):
  std::string label;                     // the panel's label; empty: ParaView's own
  std::string help;                      // their longer documentation; empty: `doc`
  std::vector<std::string> choiceLabels; // the panel's entries; empty: `choices`
  std::string shownWith;                 // "CoarseLevel=1": shown only while that holds

  bool accepts(double value) const;
  std::string range() const; // "[0, 1]", "0 or [100, 1e+09]", "planes|points"
  /** The nearest value in range (a filter's setter clamps as vtkSetClampMacro does); NaN is
   *  refused (std::invalid_argument naming the option; `what`: "tracker option"). */
  double clamped(double value, const std::string& what) const;
  /** A value from text: a number, true/false/on/off for a flag, a choice's name or index.
   *  Throws std::invalid_argument naming the option (`what`: "tracker option") and its range. */
  double parse(std::string_view text, const std::string& what) const;
  /** The value as users read it: a choice's name, true/false, a number. */
  std::string said(double value) const;
};

/** The table's forms over specs and values, shared by every OptionTable. */
namespace option_forms
{
std::string valuesJson(const std::vector<const OptionSpec*>& specs,
                       const std::vector<double>& values);
/** A JSON object's members as (name, value as text) pairs; throws std::invalid_argument
 *  naming `source` when the text is not one JSON object. */
std::vector<std::pair<std::string, std::string>> jsonMembers(const std::string& json,
                                                             const std::string& source);
std::string describeJson(const std::vector<const OptionSpec*>& specs,
                         const std::vector<double>& defaults);
std::string describeMarkdown(const std::vector<const OptionSpec*>& specs,
                             const std::vector<double>& defaults);
std::string outOfRange(const OptionSpec& spec, double value, const std::string& what);
} // namespace option_forms

template <typename Options>
struct OptionDescription : OptionSpec
{
  std::function<double(const Options&)> get;
  std::function<void(Options&, double)> set;

  /** The row with its presentation (OptionSpec's last fields), written after its maker. */
  OptionDescription withHelp(const char* text) const { return with(&OptionSpec::help, text); }
  OptionDescription withLabel(const char* text) const { return with(&OptionSpec::label, text); }
  OptionDescription shownWith(const char* condition) const
  {
    return with(&OptionSpec::shownWith, condition);
  }
  OptionDescription withChoiceLabels(std::vector<std::string> labels) const
  {
    OptionDescription row = *this;
    row.choiceLabels = std::move(labels);
    return row;
  }

private:
  OptionDescription with(std::string OptionSpec::*field, const char* text) const
  {
    OptionDescription row = *this;
    row.*field = text;
    return row;
  }
};

/** The rows' makers: each binds a double, integer or bool member reached by `field` (a callable
 *  returning a reference to it, e.g. `[](auto& o) -> auto& { return o.graph.nodes; }`). */
template <typename Options>
struct OptionRows
{
  using Row = OptionDescription<Options>;

  template <typename Field>
  static Row real(const char* name, const char* property, OptionPanel panel, double lo, double hi,
                  const char* unit, const char* doc, Field field)
  {
    Row row;
    row.name = name;
    row.property = property;
    row.kind = OptionKind::Real;
    row.minimum = lo;
    row.maximum = hi;
    row.unit = unit;
    row.doc = doc;
    row.panel = panel;
    row.get = [field](const Options& o)
    { return static_cast<double>(field(const_cast<Options&>(o))); };
    row.set = [field](Options& o, double v)
    {
      auto& member = field(o);
      using T = std::decay_t<decltype(member)>;
      if constexpr (std::is_same_v<T, bool>)
        member = v != 0;
      else
        member = static_cast<T>(v);
    };
    return row;
  }

  template <typename Field>
  static Row integer(const char* name, const char* property, OptionPanel panel, double lo,
                     double hi, const char* doc, Field field)
  {
    Row row = real(name, property, panel, lo, hi, "", doc, field);
    row.kind = OptionKind::Integer;
    return row;
  }

  template <typename Field>
  static Row flag(const char* name, const char* property, OptionPanel panel, const char* doc,
                  Field field)
  {
    Row row = real(name, property, panel, 0, 1, "", doc, field);
    row.kind = OptionKind::Flag;
    return row;
  }

  /** A choice held as an enum (or an integer) of values 0 .. choices - 1. */
  template <typename Field>
  static Row choice(const char* name, const char* property, OptionPanel panel,
                    std::vector<std::string> choices, const char* doc, Field field)
  {
    Row row;
    row.name = name;
    row.property = property;
    row.kind = OptionKind::Choice;
    row.maximum = static_cast<double>(choices.size()) - 1;
    row.doc = doc;
    row.panel = panel;
    row.choices = std::move(choices);
    row.get = [field](const Options& o)
    { return static_cast<double>(field(const_cast<Options&>(o))); };
    row.set = [field](Options& o, double v)
    {
      auto& member = field(o);
      member = static_cast<std::decay_t<decltype(member)>>(static_cast<int>(v));
    };
    return row;
  }

  /** 0 (automatic, or off) accepted below the row's minimum. */
  static Row automatic(Row row)
  {
    row.zeroAllowed = true;
    return row;
  }
};

/** A table as forms that other files restate read it (OptionCode.h): its rows and their
 *  defaults, and the name of the VTK classes' generic accessor ("TrackerOption": SetTrackerOption,
 *  GetTrackerOption). */
struct OptionCodeTable
{
  std::vector<const OptionSpec*> specs;
  std::vector<double> defaults;
  std::string accessorFamily;
};

template <typename Options>
class OptionTable
{
public:
  using Row = OptionDescription<Options>;

  /** `what` names the table's options in messages: "tracker option". */
  OptionTable(std::string what, std::vector<Row> rows)
      : What(std::move(what)), Rows(std::move(rows))
  {
  }

  const std::vector<Row>& rows() const { return Rows; }
  const std::string& what() const { return What; }
  auto begin() const { return Rows.begin(); }
  auto end() const { return Rows.end(); }

  /** The option of that name or ParaView property name; std::invalid_argument if none. */
  const Row& find(std::string_view nameOrProperty) const
  {
    if (const Row* row = lookup(nameOrProperty))
      return *row;
    throw std::invalid_argument("no " + What + " '" + std::string(nameOrProperty) + "'");
  }
  bool has(std::string_view nameOrProperty) const { return lookup(nameOrProperty) != nullptr; }

  /** Throws std::invalid_argument naming the first option out of its range (NaN included). */
  void check(const Options& options) const
  {
    for (const Row& row : Rows)
      if (!row.accepts(row.get(options)))
        throw std::invalid_argument(option_forms::outOfRange(row, row.get(options), What));
  }

  /** Sets an option from text (OptionSpec::parse). */
  void set(Options& options, std::string_view name, std::string_view text) const
  {
    const Row& row = find(name);
    row.set(options, row.parse(text, What));
  }

  /** The options as one flat JSON object, {"graph.yieldRate": 0.3, ...}: choices by name, flags
   *  as true/false. readJson reads it back (any subset of the names). */
  std::string valuesJson(const Options& options) const
  {
    return option_forms::valuesJson(specs(), values(options));
  }
  void readJson(Options& options, const std::string& json, const std::string& source) const
  {
    for (const auto& [name, text] : option_forms::jsonMembers(json, source))
    {
      try
      {
        set(options, name, text);
      }
      catch (const std::invalid_argument& e)
      {
        throw std::invalid_argument(source + ": " + e.what());
      }
    }
  }

  /** The table as JSON (name, property, kind, default, range, unit, doc, panel, choices): what
   *  the tests compare the ParaView XML and the documentation with. */
  std::string describeJson() const
  {
    return option_forms::describeJson(specs(), values(Options{}));
  }
  /** The table as Markdown, the documentation's. */
  std::string describeMarkdown() const
  {
    return option_forms::describeMarkdown(specs(), values(Options{}));
  }

  /** The rows and their defaults as OptionCode.h's forms read them; `accessorFamily` names the
   *  VTK classes' generic accessor ("TrackerOption"). */
  OptionCodeTable codeTable(std::string accessorFamily) const
  {
    return {specs(), values(Options{}), std::move(accessorFamily)};
  }

private:
  const Row* lookup(std::string_view nameOrProperty) const
  {
    for (const Row& row : Rows)
      if (row.name == nameOrProperty || (!row.property.empty() && row.property == nameOrProperty))
        return &row;
    return nullptr;
  }
  std::vector<const OptionSpec*> specs() const
  {
    std::vector<const OptionSpec*> out;
    for (const Row& row : Rows)
      out.push_back(&row);
    return out;
  }
  std::vector<double> values(const Options& options) const
  {
    std::vector<double> out;
    for (const Row& row : Rows)
      out.push_back(row.get(options));
    return out;
  }

  std::string What;
  std::vector<Row> Rows;
};

} // namespace dp
