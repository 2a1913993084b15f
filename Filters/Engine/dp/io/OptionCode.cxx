// SPDX-License-Identifier: BSD-3-Clause
#include "dp/io/OptionCode.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace dp
{

namespace
{

constexpr const char* BeginMarker = "BEGIN generated options:";
constexpr const char* EndMarker = "END generated options";

// The shortest text that reads back as the same double; whole numbers without an exponent.
std::string number(double v)
{
  if (v == std::floor(v) && std::fabs(v) < 1e15)
    return std::to_string(static_cast<long long>(v));
  for (int digits = 1; digits < 17; ++digits)
  {
    std::ostringstream s;
    s.precision(digits);
    s << v;
    if (std::stod(s.str()) == v)
      return s.str();
  }
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

// Whether the panel gets a slider (a range domain's max): not over a range a slider could not
// be used on, one reaching 1000 or more, or 100 times a positive default.
bool sliderRange(const OptionSpec& spec, double value)
{
  if (spec.maximum == Unbounded || spec.maximum >= 1000)
    return false;
  return !(spec.kind == OptionKind::Real && value > 0 && spec.maximum / value >= 100);
}

// `text` broken into lines of at most `width` characters (words kept whole).
std::vector<std::string> wrapped(const std::string& text, std::size_t width)
{
  std::vector<std::string> lines;
  std::istringstream words(text);
  std::string word, line;
  while (words >> word)
  {
    if (!line.empty() && line.size() + 1 + word.size() > width)
    {
      lines.push_back(line);
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty())
    lines.push_back(line);
  return lines;
}

std::string xmlEscaped(const std::string& text)
{
  std::string out;
  for (char c : text)
    out += c == '&'   ? "&amp;"
           : c == '<' ? "&lt;"
           : c == '>' ? "&gt;"
           : c == '"' ? "&quot;"
                      : std::string(1, c);
  return out;
}

const std::string& helpOf(const OptionSpec& spec)
{
  return spec.help.empty() ? spec.doc : spec.help;
}

// The C++ type the accessors take and give.
std::string cxxType(OptionKind kind)
{
  return kind == OptionKind::Real ? "double" : kind == OptionKind::Flag ? "vtkTypeBool" : "int";
}

std::string accessorsOf(const OptionSpec& spec, const std::string& family)
{
  const std::string& p = spec.property;
  const std::string type = cxxType(spec.kind);
  std::ostringstream out;
  out << "  ///@{\n";
  const std::vector<std::string> doc =
      wrapped(helpOf(spec) + " (" + spec.name + "; range " + spec.range() +
                  (spec.unit.empty() ? "" : ", " + spec.unit) + ")",
              92);
  for (std::size_t i = 0; i < doc.size(); ++i)
    out << (i == 0 ? "  /** " : "   *  ") << doc[i] << (i + 1 == doc.size() ? " */\n" : "\n");
  out << "  void Set" << p << "(" << type << " value) { this->Set" << family << "(\"" << p
      << "\", value); }\n";
  out << "  " << type << " Get" << p << "() { return ";
  if (type == "double")
    out << "this->Get" << family << "(\"" << p << "\"); }\n";
  else
    out << "static_cast<" << type << ">(this->Get" << family << "(\"" << p << "\")); }\n";
  if (spec.kind == OptionKind::Flag)
    out << "  vtkBooleanMacro(" << p << ", vtkTypeBool);\n";
  out << "  ///@}\n";
  return out.str();
}

std::string domainOf(const OptionSpec& spec, double value)
{
  if (spec.kind == OptionKind::Flag)
    return "        <BooleanDomain name=\"bool\" />\n";
  if (spec.kind == OptionKind::Choice)
  {
    std::ostringstream out;
    out << "        <EnumerationDomain name=\"enum\">\n";
    for (std::size_t i = 0; i < spec.choices.size(); ++i)
    {
      const std::string& text =
          i < spec.choiceLabels.size() ? spec.choiceLabels[i] : spec.choices[i];
      out << "          <Entry value=\"" << i << "\" text=\"" << xmlEscaped(text) << "\" />\n";
    }
    out << "        </EnumerationDomain>\n";
    return out.str();
  }
  const std::string tag = spec.kind == OptionKind::Integer ? "IntRangeDomain" : "DoubleRangeDomain";
  std::ostringstream out;
  out << "        <" << tag << " name=\"range\" min=\""
      << number(spec.zeroAllowed ? 0 : spec.minimum) << "\"";
  if (sliderRange(spec, value))
    out << " max=\"" << number(spec.maximum) << "\"";
  out << " />\n";
  return out.str();
}

std::string propertyOf(const OptionSpec& spec, double value)
{
  const std::string tag =
      spec.kind == OptionKind::Real ? "DoubleVectorProperty" : "IntVectorProperty";
  std::ostringstream out;
  out << "      <" << tag << " name=\"" << spec.property << "\"";
  if (!spec.label.empty())
    out << " label=\"" << xmlEscaped(spec.label) << "\"";
  out << " command=\"Set" << spec.property << "\" number_of_elements=\"1\" default_values=\""
      << number(value) << "\"";
  if (spec.panel == OptionPanel::Advanced)
    out << " panel_visibility=\"advanced\"";
  out << ">\n" << domainOf(spec, value) << "        <Documentation>\n";
  for (const std::string& line : wrapped(xmlEscaped(helpOf(spec)), 88))
    out << "          " << line << "\n";
  out << "        </Documentation>\n";
  const std::size_t is = spec.shownWith.find('=');
  if (is != std::string::npos)
    out << "        <Hints>\n"
        << "          <PropertyWidgetDecorator type=\"GenericDecorator\" mode=\"visibility\" "
           "property=\""
        << spec.shownWith.substr(0, is) << "\" value=\"" << spec.shownWith.substr(is + 1)
        << "\" />\n"
        << "        </Hints>\n";
  out << "      </" << tag << ">\n";
  return out.str();
}

std::vector<std::string> splitNames(const std::string& text)
{
  std::vector<std::string> names;
  std::istringstream in(text);
  for (std::string name; std::getline(in, name, ',');)
    if (!name.empty())
      names.push_back(name);
  return names;
}

OptionRegion parseRegion(const std::string& line, const std::string& source)
{
  std::string rest = line.substr(line.find(BeginMarker) + std::string(BeginMarker).size());
  rest = rest.substr(0, rest.find("-->")); // an XML or Markdown comment's end
  std::istringstream words(rest);
  OptionRegion region;
  std::string word;
  words >> region.table;
  if (region.table.empty())
    throw std::invalid_argument(source + ": a region names no table: " + line);
  if (words >> word && word == "except" && words >> word)
    region.except = splitNames(word);
  return region;
}

} // namespace

std::vector<std::size_t> presentedRows(const OptionCodeTable& table,
                                       const std::vector<std::string>& except)
{
  std::vector<std::size_t> rows;
  for (std::size_t i = 0; i < table.specs.size(); ++i)
  {
    const std::string& property = table.specs[i]->property;
    if (!property.empty() && std::find(except.begin(), except.end(), property) == except.end())
      rows.push_back(i);
  }
  return rows;
}

std::string vtkAccessors(const OptionCodeTable& table, const std::vector<std::string>& except)
{
  std::string out = "  // clang-format off\n";
  for (std::size_t i : presentedRows(table, except))
    out += accessorsOf(*table.specs[i], table.accessorFamily);
  return out + "  // clang-format on\n";
}

std::string paraviewProperties(const OptionCodeTable& table, const std::vector<std::string>& except)
{
  std::string out;
  for (std::size_t i : presentedRows(table, except))
    out += propertyOf(*table.specs[i], table.defaults[i]);
  return out;
}

std::string rewriteOptionRegions(const std::string& text, const std::string& source,
                                 const std::function<std::string(const OptionRegion&)>& generate)
{
  std::istringstream in(text);
  std::string out, line;
  bool inside = false;
  std::size_t number = 0;
  while (std::getline(in, line))
  {
    ++number;
    const bool begins = line.find(BeginMarker) != std::string::npos;
    const bool ends = line.find(EndMarker) != std::string::npos;
    if ((begins && inside) || (ends && !inside))
      throw std::invalid_argument(
          source + ":" + std::to_string(number) +
          (inside ? ": a region begins inside another" : ": a region ends that did not begin"));
    if (ends)
      inside = false;
    if (!inside)
      out += line + (in.eof() ? "" : "\n");
    if (begins)
    {
      out += generate(parseRegion(line, source));
      inside = true;
    }
  }
  if (inside)
    throw std::invalid_argument(source + ": a region does not end ('" + EndMarker + "')");
  return out;
}

} // namespace dp
