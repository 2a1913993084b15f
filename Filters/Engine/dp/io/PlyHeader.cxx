// SPDX-License-Identifier: BSD-3-Clause
// The PLY header's parser: the keyword lines up to end_header (see PlyHeader.h).
#include "dp/io/PlyHeader.h"

#include "dp/io/FileText.h"
#include "dp/io/PointCloud.h"

#include <functional>
#include <optional>
#include <string_view>

namespace dp::support
{
namespace
{

std::optional<PlyType> parsePlyType(std::string_view name)
{
  if (name == "char" || name == "int8")
    return PlyType::Int8;
  if (name == "uchar" || name == "uint8")
    return PlyType::UInt8;
  if (name == "short" || name == "int16")
    return PlyType::Int16;
  if (name == "ushort" || name == "uint16")
    return PlyType::UInt16;
  if (name == "int" || name == "int32")
    return PlyType::Int32;
  if (name == "uint" || name == "uint32")
    return PlyType::UInt32;
  if (name == "float" || name == "float32")
    return PlyType::Float32;
  if (name == "double" || name == "float64")
    return PlyType::Float64;
  return std::nullopt;
}

// A header line's failure, naming the file and the line.
using HeaderFailure = std::function<void(const std::string& why)>;

// "format <kind> <version>" (after the keyword).
PlyBodyEncoding parseFormatLine(std::string_view rest, const HeaderFailure& fail)
{
  const std::string_view kind = nextToken(rest);
  if (kind == "ascii")
    return PlyBodyEncoding::Ascii;
  if (kind == "binary_little_endian")
    return PlyBodyEncoding::Little;
  if (kind == "binary_big_endian")
    return PlyBodyEncoding::Big;
  fail("unknown format '" + std::string(kind) + "'");
  return PlyBodyEncoding::Ascii; // not reached: fail throws
}

// "element <name> <count>" (after the keyword).
PlyElement parseElementLine(std::string_view rest, std::string_view line, const HeaderFailure& fail)
{
  PlyElement element;
  element.name = std::string(nextToken(rest));
  double count = -1;
  if (element.name.empty() || !parseNumber(nextToken(rest), count) || count < 0 ||
      !wholeNumberWithin(count, LargestCount))
  {
    fail("malformed element line '" + std::string(line) + "'");
  }
  element.count = static_cast<std::size_t>(count);
  return element;
}

// "property <type> <name>" or "property list <count type> <type> <name>" (after the keyword).
PlyProperty parsePropertyLine(std::string_view rest, std::string_view line,
                              const HeaderFailure& fail)
{
  PlyProperty property;
  std::string_view typeName = nextToken(rest);
  if (typeName == "list")
  {
    property.isList = true;
    const auto countType = parsePlyType(nextToken(rest));
    typeName = nextToken(rest);
    if (!countType)
    {
      fail("unknown list count type in '" + std::string(line) + "'");
    }
    property.countType = *countType;
  }
  const auto type = parsePlyType(typeName);
  if (!type)
  {
    fail("unknown property type '" + std::string(typeName) + "'");
  }
  property.type = *type;
  property.name = std::string(nextToken(rest));
  if (property.name.empty())
  {
    fail("property without a name");
  }
  return property;
}

// A format, element or property line (`rest`: after the keyword) into `header`; any other
// keyword fails.
void parseKeywordLine(std::string_view keyword, std::string_view rest, std::string_view line,
                      PlyHeader& header, bool& sawFormat, const HeaderFailure& fail)
{
  if (keyword == "format")
  {
    header.encoding = parseFormatLine(rest, fail);
    sawFormat = true;
  }
  else if (keyword == "element")
    header.elements.push_back(parseElementLine(rest, line, fail));
  else if (keyword == "property")
  {
    if (header.elements.empty())
    {
      fail("property before any element");
    }
    header.elements.back().properties.push_back(parsePropertyLine(rest, line, fail));
  }
  else
  {
    fail("unknown keyword '" + std::string(keyword) + "'");
  }
}

} // namespace

PlyHeader parsePlyHeader(const std::string& path, const std::string& bytes)
{
  PlyHeader header;
  std::string_view text(bytes);
  std::string_view line;
  if (!nextLine(text, line) || line.substr(0, 3) != "ply")
  {
    throw FileError(path, "not a PLY file (it does not start with 'ply')");
  }
  bool sawFormat = false;
  int lineNumber = 1;
  const HeaderFailure fail = [&](const std::string& why)
  { throw FileError(path, "PLY header line " + std::to_string(lineNumber) + ": " + why); };
  while (true)
  {
    if (!nextLine(text, line))
    {
      throw FileError(path, "PLY header has no 'end_header' line (file truncated?)");
    }
    ++lineNumber;
    std::string_view rest = line;
    const std::string_view keyword = nextToken(rest);
    if (keyword == "end_header")
    {
      break;
    }
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info")
    {
      continue;
    }
    parseKeywordLine(keyword, rest, line, header, sawFormat, fail);
  }
  if (!sawFormat)
  {
    throw FileError(path, "PLY header has no 'format' line");
  }
  header.bodyOffset = bytes.size() - text.size();
  return header;
}

} // namespace dp::support
