// SPDX-License-Identifier: BSD-3-Clause
// PLY reader (Turk's format: ASCII, binary little and big endian): the body the header
// (PlyHeader.cxx) describes, its vertices and faces into a PointCloud.
#include "dp/io/FileText.h"
#include "dp/io/PlyHeader.h"
#include "dp/io/PointCloudIO.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace dp
{
namespace
{

using support::PlyBodyEncoding;
using support::PlyElement;
using support::PlyHeader;
using support::PlyProperty;
using support::PlyType;
using support::sizeOf;

template <typename T>
T loadSwapped(const char* p, bool swap)
{
  char bytes[sizeof(T)];
  std::memcpy(bytes, p, sizeof(T));
  if (swap)
  {
    std::reverse(bytes, bytes + sizeof(T));
  }
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

double decode(const char* p, PlyType t, bool swap)
{
  switch (t)
  {
  case PlyType::Int8:
    return static_cast<std::int8_t>(*p);
  case PlyType::UInt8:
    return static_cast<std::uint8_t>(*p);
  case PlyType::Int16:
    return loadSwapped<std::int16_t>(p, swap);
  case PlyType::UInt16:
    return loadSwapped<std::uint16_t>(p, swap);
  case PlyType::Int32:
    return loadSwapped<std::int32_t>(p, swap);
  case PlyType::UInt32:
    return loadSwapped<std::uint32_t>(p, swap);
  case PlyType::Float32:
    return loadSwapped<float>(p, swap);
  case PlyType::Float64:
    return loadSwapped<double>(p, swap);
  }
  return 0.0;
}

// Where a vertex property goes in the PointCloud.
enum class Slot
{
  Skip,
  X,
  Y,
  Z,
  NX,
  NY,
  NZ,
  Red,
  Green,
  Blue,
  Alpha,
  Attribute
};

Slot slotFor(const std::string& name)
{
  static const std::pair<const char*, Slot> names[] = {{"x", Slot::X},
                                                       {"y", Slot::Y},
                                                       {"z", Slot::Z},
                                                       {"nx", Slot::NX},
                                                       {"ny", Slot::NY},
                                                       {"nz", Slot::NZ},
                                                       {"normal_x", Slot::NX},
                                                       {"normal_y", Slot::NY},
                                                       {"normal_z", Slot::NZ},
                                                       {"red", Slot::Red},
                                                       {"green", Slot::Green},
                                                       {"blue", Slot::Blue},
                                                       {"alpha", Slot::Alpha},
                                                       {"diffuse_red", Slot::Red},
                                                       {"diffuse_green", Slot::Green},
                                                       {"diffuse_blue", Slot::Blue}};
  for (const auto& [n, s] : names)
  {
    if (name == n)
    {
      return s;
    }
  }
  return Slot::Attribute;
}

// Reads values one at a time from either encoding, reporting truncation with context.
class BodyReader
{
public:
  BodyReader(const std::string& path, const std::string& bytes, const PlyHeader& header)
      : Path(path), Body(std::string_view(bytes).substr(header.bodyOffset)), Mode(header.encoding)
  {
  }

  // Returns false when the data ran out (truncated file).
  bool read(PlyType type, double& value)
  {
    if (Mode == PlyBodyEncoding::Ascii)
    {
      const std::string_view token = support::nextToken(Body);
      if (token.empty())
      {
        return false;
      }
      if (!support::parseNumber(token, value))
      {
        throw FileError(Path, "PLY body: '" + std::string(token) + "' is not a number");
      }
      return true;
    }
    const std::size_t size = sizeOf(type);
    if (Body.size() < size)
    {
      return false;
    }
    value = decode(Body.data(), type, Mode == PlyBodyEncoding::Big);
    Body.remove_prefix(size);
    return true;
  }

  bool isBinary() const { return Mode != PlyBodyEncoding::Ascii; }
  std::size_t remaining() const { return Body.size(); }
  const char* cursor() const { return Body.data(); }
  void advance(std::size_t n) { Body.remove_prefix(n); }

private:
  std::string Path;
  std::string_view Body;
  PlyBodyEncoding Mode;
};

[[noreturn]] void truncated(const std::string& path, const PlyElement& element, std::size_t item)
{
  throw FileError(path, "PLY data ends early (truncated file): the header declares " +
                            std::to_string(element.count) + " '" + element.name +
                            "' elements but the data stops inside number " +
                            std::to_string(item + 1));
}

// A list's length as read: a whole number from 0 to what the data left can hold (each entry takes
// at least a byte), else an error naming the element; casting anything else is undefined.
std::size_t listLength(const std::string& path, const PlyElement& element, std::size_t item,
                       double value, const BodyReader& reader)
{
  if (!(value >= 0) || value != std::floor(value) ||
      value > static_cast<double>(reader.remaining()))
  {
    throw FileError(path, "PLY '" + element.name + "' element number " + std::to_string(item + 1) +
                              " has a list length of " + std::to_string(value) +
                              ", not a count the file can hold");
  }
  return static_cast<std::size_t>(value);
}

// Where each property of the vertex element goes.
struct VertexLayout
{
  std::vector<Slot> slots;         // per property
  std::vector<int> attributeIndex; // per property: its attribute in the cloud (-1: none)
  int colorCount = 0;              // colour channels declared
  bool colorIsFloat = false;       // channels in [0,1], not [0,255]
};

// The layout of a vertex element; the cloud's arrays sized for its `count` vertices. Throws
// when x, y or z is missing.
VertexLayout layOutVertices(const std::string& path, const PlyElement& element, PointCloud& cloud)
{
  VertexLayout layout;
  layout.attributeIndex.assign(element.properties.size(), -1);
  bool hasXYZ[3] = {false, false, false};
  bool hasNormal = false;
  for (std::size_t p = 0; p < element.properties.size(); ++p)
  {
    const PlyProperty& prop = element.properties[p];
    Slot slot = prop.isList ? Slot::Skip : slotFor(prop.name);
    if (slot >= Slot::X && slot <= Slot::Z)
      hasXYZ[static_cast<int>(slot) - static_cast<int>(Slot::X)] = true;
    if (slot >= Slot::NX && slot <= Slot::NZ)
      hasNormal = true;
    if (slot >= Slot::Red && slot <= Slot::Alpha)
    {
      ++layout.colorCount;
      layout.colorIsFloat =
          layout.colorIsFloat || prop.type == PlyType::Float32 || prop.type == PlyType::Float64;
    }
    if (slot == Slot::Attribute)
    {
      layout.attributeIndex[p] = static_cast<int>(cloud.attributes.size());
      cloud.attributes.push_back({prop.name, 1, {}});
    }
    layout.slots.push_back(slot);
  }
  if (!hasXYZ[0] || !hasXYZ[1] || !hasXYZ[2])
    throw FileError(path, "PLY 'vertex' element lacks one of the properties x, y, z");
  const std::size_t n = element.count;
  cloud.points.assign(3 * n, 0.0);
  if (hasNormal)
    cloud.normals.assign(3 * n, 0.0f);
  if (layout.colorCount >= 3)
  {
    cloud.colorComponents = layout.colorCount >= 4 ? 4 : 3;
    cloud.colors.assign(cloud.colorComponents * n, 255);
  }
  for (auto& a : cloud.attributes)
    a.values.resize(n);
  return layout;
}

// Stores the value of property p of vertex i where the layout says.
void storeVertexValue(const VertexLayout& layout, std::size_t p, std::size_t i, double value,
                      PointCloud& cloud)
{
  const Slot slot = layout.slots[p];
  switch (slot)
  {
  case Slot::X:
  case Slot::Y:
  case Slot::Z:
    cloud.points[3 * i + static_cast<int>(slot) - static_cast<int>(Slot::X)] = value;
    break;
  case Slot::NX:
  case Slot::NY:
  case Slot::NZ:
    cloud.normals[3 * i + static_cast<int>(slot) - static_cast<int>(Slot::NX)] =
        static_cast<float>(value);
    break;
  case Slot::Red:
  case Slot::Green:
  case Slot::Blue:
  case Slot::Alpha:
  {
    const int c = static_cast<int>(slot) - static_cast<int>(Slot::Red);
    if (c < cloud.colorComponents)
    {
      // A NaN colour (float channels) is black: clamping keeps a NaN, and casting it is
      // undefined.
      const double scaled = layout.colorIsFloat ? value * 255.0 + 0.5 : value;
      cloud.colors[cloud.colorComponents * i + c] =
          static_cast<std::uint8_t>(std::isnan(scaled) ? 0.0 : std::clamp(scaled, 0.0, 255.0));
    }
    break;
  }
  case Slot::Attribute:
    cloud.attributes[layout.attributeIndex[p]].values[i] = static_cast<float>(value);
    break;
  case Slot::Skip:
    break;
  }
}

void readVertices(const std::string& path, const PlyElement& element, BodyReader& reader,
                  PointCloud& cloud)
{
  const VertexLayout layout = layOutVertices(path, element, cloud);
  for (std::size_t i = 0; i < element.count; ++i)
    for (std::size_t p = 0; p < element.properties.size(); ++p)
    {
      const PlyProperty& prop = element.properties[p];
      double value = 0;
      if (prop.isList) // read past: a vertex's lists carry nothing we keep
      {
        if (!reader.read(prop.countType, value))
          truncated(path, element, i);
        for (std::size_t k = 0, len = listLength(path, element, i, value, reader); k < len; ++k)
          if (!reader.read(prop.type, value))
            truncated(path, element, i);
        continue;
      }
      if (!reader.read(prop.type, value))
        truncated(path, element, i);
      storeVertexValue(layout, p, i, value, cloud);
    }
  if (layout.colorCount > 0 && layout.colorCount < 3)
    cloud.colorComponents = 0;
}

// A face's vertex index as read: from 0 to below the cloud's vertex count, else an error naming
// the face.
std::int64_t vertexIndex(const std::string& path, std::size_t face, double value,
                         const PointCloud& cloud)
{
  const auto numberOfPoints = static_cast<double>(cloud.numberOfPoints());
  if (!(value >= 0 && value < numberOfPoints)) // NaN included
  {
    const bool whole = support::wholeNumberWithin(value, support::LargestCount);
    throw FileError(
        path, "PLY face " + std::to_string(face) + " uses vertex " +
                  (whole ? std::to_string(static_cast<long long>(value)) : std::to_string(value)) +
                  ", but there are only " + std::to_string(cloud.numberOfPoints()) + " vertices");
  }
  return static_cast<std::int64_t>(value);
}

void readFaces(const std::string& path, const PlyElement& element, BodyReader& reader,
               PointCloud& cloud)
{
  int indexProperty = -1;
  for (std::size_t p = 0; p < element.properties.size(); ++p)
  {
    const auto& name = element.properties[p].name;
    if (element.properties[p].isList && (name == "vertex_indices" || name == "vertex_index"))
      indexProperty = static_cast<int>(p);
  }
  if (indexProperty < 0)
  {
    throw FileError(path, "PLY 'face' element has no 'vertex_indices' list property");
  }
  cloud.faceOffsets.reserve(element.count + 1);
  cloud.faceOffsets.push_back(0);
  cloud.faceConnectivity.reserve(3 * element.count);
  for (std::size_t f = 0; f < element.count; ++f)
  {
    for (std::size_t p = 0; p < element.properties.size(); ++p)
    {
      const PlyProperty& prop = element.properties[p];
      double value = 0;
      if (!prop.isList)
      {
        if (!reader.read(prop.type, value))
          truncated(path, element, f);
        continue;
      }
      if (!reader.read(prop.countType, value))
        truncated(path, element, f);
      const std::size_t length = listLength(path, element, f, value, reader);
      for (std::size_t k = 0; k < length; ++k)
      {
        if (!reader.read(prop.type, value))
          truncated(path, element, f);
        if (static_cast<int>(p) == indexProperty)
          cloud.faceConnectivity.push_back(vertexIndex(path, f, value, cloud));
      }
    }
    cloud.faceOffsets.push_back(static_cast<std::int64_t>(cloud.faceConnectivity.size()));
  }
  if (element.count == 0)
  {
    cloud.faceOffsets.clear();
  }
}

// Binary fast path for the common vertex layout: fixed-size records, no lists.
bool fixedRecordSize(const PlyElement& element, std::size_t& size)
{
  size = 0;
  for (const auto& p : element.properties)
  {
    if (p.isList)
      return false;
    size += sizeOf(p.type);
  }
  return true;
}

// The fewest bytes one element can take: every scalar and every list length present; in ASCII
// at least one digit and one separator per value.
std::size_t minimumBytes(const PlyElement& element, bool binary)
{
  std::size_t bytes = 0;
  for (const auto& p : element.properties)
    bytes += binary ? sizeOf(p.isList ? p.countType : p.type) : 2;
  return bytes;
}

void skipElement(const std::string& path, const PlyElement& element, BodyReader& reader)
{
  if (element.properties.empty())
    return; // nothing to read, however many it declares (a loop of 10^11 empty steps otherwise)
  std::size_t record = 0;
  if (reader.isBinary() && fixedRecordSize(element, record))
  {
    if (reader.remaining() < record * element.count)
      truncated(path, element, reader.remaining() / std::max<std::size_t>(record, 1));
    reader.advance(record * element.count);
    return;
  }
  for (std::size_t i = 0; i < element.count; ++i)
  {
    for (const auto& prop : element.properties)
    {
      double value = 0;
      if (!reader.read(prop.isList ? prop.countType : prop.type, value))
        truncated(path, element, i);
      if (prop.isList)
        for (std::size_t k = 0, len = listLength(path, element, i, value, reader); k < len; ++k)
          if (!reader.read(prop.type, value))
            truncated(path, element, i);
    }
  }
}

} // namespace

PointCloud readPLY(const std::string& path)
{
  const std::string bytes = support::readWholeFile(path);
  const PlyHeader header = support::parsePlyHeader(path, bytes);
  BodyReader reader(path, bytes, header);
  PointCloud cloud;
  bool sawVertex = false, sawFace = false;
  for (const PlyElement& element : header.elements)
  {
    // Check the declared count against the bytes left before allocating anything, so a
    // truncated file, or a header claiming billions of elements, fails at once.
    const std::size_t least = minimumBytes(element, reader.isBinary());
    if (least > 0 && element.count > reader.remaining() / least)
    {
      truncated(path, element, reader.remaining() / least);
    }
    if (element.name == "vertex")
    {
      if (sawVertex) // a second one would overwrite the first's points but not its attributes
        throw FileError(path, "PLY file has more than one 'vertex' element");
      readVertices(path, element, reader, cloud);
      sawVertex = true;
    }
    else if (element.name == "face" && sawVertex)
    {
      if (sawFace) // a second one would restart the face offsets inside the connectivity
        throw FileError(path, "PLY file has more than one 'face' element");
      readFaces(path, element, reader, cloud);
      sawFace = true;
    }
    else
    {
      skipElement(path, element, reader);
    }
  }
  if (!sawVertex)
  {
    throw FileError(path, "PLY file has no 'vertex' element");
  }
  return cloud;
}

} // namespace dp
