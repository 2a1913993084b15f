// SPDX-License-Identifier: BSD-3-Clause
#include "dp/io/OptionTable.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace dp
{

namespace
{

std::string number(double v)
{
  std::ostringstream s;
  s.precision(15);
  s << v;
  return s.str();
}

std::string kindName(OptionKind kind)
{
  switch (kind)
  {
  case OptionKind::Integer:
    return "integer";
  case OptionKind::Flag:
    return "flag";
  case OptionKind::Choice:
    return "choice";
  default:
    return "real";
  }
}

std::string panelName(OptionPanel panel)
{
  return panel == OptionPanel::Shown ? "shown" : panel == OptionPanel::Advanced ? "advanced" : "";
}

// A value as JSON: flags as true/false, choices by name.
nlohmann::json jsonValue(const OptionSpec& spec, double v)
{
  if (spec.kind == OptionKind::Flag)
    return v != 0;
  if (spec.kind == OptionKind::Choice)
    return spec.choices.at(static_cast<std::size_t>(v));
  if (spec.kind == OptionKind::Integer)
    return static_cast<long long>(v);
  return v;
}

// Text for a Markdown table's cell: a `|` there would end the cell.
std::string cell(const std::string& text)
{
  std::string out;
  for (char c : text)
    out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

} // namespace

bool OptionSpec::accepts(double value) const
{
  if (!std::isfinite(value))
    return false;
  if (kind != OptionKind::Real && value != std::floor(value))
    return false;
  return (zeroAllowed && value == 0) || (value >= minimum && value <= maximum);
}

std::string OptionSpec::range() const
{
  if (kind == OptionKind::Choice)
  {
    std::string names;
    for (const std::string& c : choices)
      names += (names.empty() ? "" : "|") + c;
    return names;
  }
  if (kind == OptionKind::Flag)
    return "true|false";
  const std::string upper = maximum == Unbounded ? "inf" : number(maximum);
  return (zeroAllowed ? "0 or " : "") + std::string("[") + number(minimum) + ", " + upper + "]";
}

double OptionSpec::clamped(double value, const std::string& what) const
{
  if (std::isnan(value))
    throw std::invalid_argument(what + " " + name + ": NaN is no value");
  double v = (zeroAllowed && value == 0) ? 0.0 : std::min(std::max(value, minimum), maximum);
  return kind == OptionKind::Real ? v : std::round(v);
}

double OptionSpec::parse(std::string_view text, const std::string& what) const
{
  const std::string value(text);
  if (kind == OptionKind::Flag && (value == "true" || value == "on" || value == "yes"))
    return 1;
  if (kind == OptionKind::Flag && (value == "false" || value == "off" || value == "no"))
    return 0;
  for (std::size_t c = 0; c < choices.size(); ++c)
    if (choices[c] == value)
      return static_cast<double>(c);
  char* end = nullptr;
  const double v = std::strtod(value.c_str(), &end);
  if (value.empty() || end != value.c_str() + value.size())
    throw std::invalid_argument(what + " " + name + " wants " + range() + ", not '" + value + "'");
  if (!accepts(v))
    throw std::invalid_argument(option_forms::outOfRange(*this, v, what));
  return v;
}

std::string OptionSpec::said(double value) const
{
  const nlohmann::json v = jsonValue(*this, value);
  return v.is_string() ? v.get<std::string>() : v.dump();
}

namespace option_forms
{

std::string outOfRange(const OptionSpec& spec, double value, const std::string& what)
{
  return what + " " + spec.name + ": " + number(value) + " is out of its range " + spec.range() +
         " (" + spec.doc + ")";
}

std::string valuesJson(const std::vector<const OptionSpec*>& specs,
                       const std::vector<double>& values)
{
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  for (std::size_t i = 0; i < specs.size(); ++i)
    out[specs[i]->name] = jsonValue(*specs[i], values[i]);
  return out.dump(2) + "\n";
}

std::vector<std::pair<std::string, std::string>> jsonMembers(const std::string& json,
                                                             const std::string& source)
{
  nlohmann::json in;
  try
  {
    in = nlohmann::json::parse(json);
  }
  catch (const nlohmann::json::exception& e)
  {
    throw std::invalid_argument(source + ": not JSON: " + e.what());
  }
  if (!in.is_object())
    throw std::invalid_argument(source + ": wants one JSON object of option names and values");
  std::vector<std::pair<std::string, std::string>> members;
  for (const auto& [name, value] : in.items())
    members.emplace_back(name, value.is_string()    ? value.get<std::string>()
                               : value.is_boolean() ? (value.get<bool>() ? "true" : "false")
                                                    : value.dump());
  return members;
}

std::string describeJson(const std::vector<const OptionSpec*>& specs,
                         const std::vector<double>& defaults)
{
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < specs.size(); ++i)
  {
    const OptionSpec& spec = *specs[i];
    nlohmann::ordered_json r;
    r["name"] = spec.name;
    r["property"] = spec.property;
    r["kind"] = kindName(spec.kind);
    r["default"] = jsonValue(spec, defaults[i]);
    r["value"] = defaults[i]; // the number the filter's property holds
    r["minimum"] = spec.minimum;
    r["maximum"] =
        spec.maximum == Unbounded ? nlohmann::ordered_json() : nlohmann::ordered_json(spec.maximum);
    r["zero_allowed"] = spec.zeroAllowed;
    r["unit"] = spec.unit;
    r["doc"] = spec.doc;
    r["panel"] = panelName(spec.panel);
    r["choices"] = spec.choices;
    out.push_back(r);
  }
  return out.dump(2) + "\n";
}

std::string describeMarkdown(const std::vector<const OptionSpec*>& specs,
                             const std::vector<double>& defaults)
{
  std::ostringstream md;
  md << "| option | ParaView | default | range | unit | what |\n"
        "|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < specs.size(); ++i)
  {
    const OptionSpec& spec = *specs[i];
    const std::string shown =
        spec.property.empty()
            ? ""
            : spec.property + (spec.panel == OptionPanel::Advanced ? " (advanced)" : "");
    md << "| `" << spec.name << "` | " << shown << " | " << jsonValue(spec, defaults[i]).dump()
       << " | " << cell(spec.range()) << " | " << spec.unit << " | " << cell(spec.doc) << " |\n";
  }
  return md.str();
}

} // namespace option_forms

} // namespace dp
