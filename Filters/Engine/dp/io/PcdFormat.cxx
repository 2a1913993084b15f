// SPDX-License-Identifier: BSD-3-Clause
// PCD reader and writer (the Point Cloud Library's format, v0.7: ascii, binary,
// binary_compressed).
#include "dp/io/FileText.h"
#include "dp/io/MemoryBudget.h"
#include "dp/io/PointCloudIO.h"

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>

namespace dp
{
namespace
{

struct PcdField
{
  std::string name;
  int size = 4;
  char type = 'F'; // F float, I signed, U unsigned
  int count = 1;
  std::size_t offset = 0; // byte offset inside a binary record
};

// The value of type T whose bytes start at p (unaligned).
template <typename T>
T load(const char* p)
{
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

double decodeField(const char* p, const PcdField& f)
{
  switch (f.type)
  {
  case 'F':
    if (f.size == 4)
      return load<float>(p);
    else
      return load<double>(p);
  case 'I':
    switch (f.size)
    {
    case 1:
      return static_cast<std::int8_t>(*p);
    case 2:
      return load<std::int16_t>(p);
    case 4:
      return load<std::int32_t>(p);
    default:
      return static_cast<double>(load<std::int64_t>(p));
    }
  default:
    switch (f.size)
    {
    case 1:
      return static_cast<std::uint8_t>(*p);
    case 2:
      return load<std::uint16_t>(p);
    case 4:
      return load<std::uint32_t>(p);
    default:
      return static_cast<double>(load<std::uint64_t>(p));
    }
  }
}

// LZF decompression (the codec PCL uses for binary_compressed); bounds-checked.
bool lzfDecompress(const unsigned char* in, std::size_t inSize, unsigned char* out,
                   std::size_t outSize)
{
  std::size_t ip = 0, op = 0;
  while (ip < inSize)
  {
    unsigned ctrl = in[ip++];
    if (ctrl < 32)
    {
      const std::size_t run = ctrl + 1;
      if (ip + run > inSize || op + run > outSize)
        return false;
      std::memcpy(out + op, in + ip, run);
      ip += run;
      op += run;
    }
    else
    {
      std::size_t length = ctrl >> 5;
      if (length == 7)
      {
        if (ip >= inSize)
          return false;
        length += in[ip++];
      }
      if (ip >= inSize)
        return false;
      const std::size_t back = ((ctrl & 0x1f) << 8) + in[ip++] + 1;
      length += 2;
      if (back > op || op + length > outSize)
        return false;
      for (std::size_t k = 0; k < length; ++k, ++op)
        out[op] = out[op - back];
    }
  }
  return op == outSize;
}

// What the header says.
struct PcdHeader
{
  std::vector<PcdField> fields;
  std::size_t points = 0;
  std::string data; // ascii, binary or binary_compressed (lower case)
};

// A header line's failure, naming the file and the line.
using HeaderFailure = std::function<void(const std::string& why)>;

// SIZE or COUNT: one whole number per field. SIZE is 1 to 8 bytes, COUNT a field's values:
// anything past 2^20 is not a PCD header.
std::vector<int> perFieldNumbers(const std::vector<std::string_view>& values,
                                 std::size_t fieldCount, std::string_view written,
                                 const HeaderFailure& fail)
{
  if (values.size() != fieldCount)
    fail(std::string(written) + " has " + std::to_string(values.size()) + " entries for " +
         std::to_string(fieldCount) + " fields");
  std::vector<int> numbers;
  for (std::string_view value : values)
  {
    double v = 0;
    if (!support::parseNumber(value, v) || v <= 0 || !support::wholeNumberWithin(v, 1 << 20))
      fail("bad " + std::string(written) + " entry '" + std::string(value) + "'");
    numbers.push_back(static_cast<int>(v));
  }
  return numbers;
}

// TYPE: F, I or U per field.
void parseTypes(const std::vector<std::string_view>& values, std::vector<PcdField>& fields,
                const HeaderFailure& fail)
{
  if (values.size() != fields.size())
    fail("TYPE does not match FIELDS");
  for (std::size_t k = 0; k < values.size(); ++k)
  {
    fields[k].type = values[k].empty() ? '?' : values[k][0];
    if (fields[k].type != 'F' && fields[k].type != 'I' && fields[k].type != 'U')
      fail("unknown TYPE '" + std::string(values[k]) + "'");
  }
}

// WIDTH, HEIGHT or POINTS: one whole number, at most LargestCount, so it can be counted and
// multiplied.
std::size_t parseCountValue(const std::vector<std::string_view>& values, std::string_view written,
                            const HeaderFailure& fail)
{
  double v = -1;
  if (values.size() != 1 || !support::parseNumber(values[0], v) || v < 0 ||
      !support::wholeNumberWithin(v, support::LargestCount))
    fail("bad " + std::string(written) + " value '" +
         (values.empty() ? std::string() : std::string(values[0])) + "'");
  return static_cast<std::size_t>(v);
}

// A FIELDS, SIZE, TYPE or COUNT line (its keyword in lower case, as `written`, and its values)
// into `fields`; false for any other keyword.
bool parseFieldLine(const std::string& keyword, const std::vector<std::string_view>& values,
                    std::string_view written, std::vector<PcdField>& fields,
                    const HeaderFailure& fail)
{
  if (keyword == "fields")
  {
    for (auto v : values)
      fields.push_back({std::string(v), 4, 'F', 1, 0});
  }
  else if (keyword == "size")
  {
    const std::vector<int> sizes = perFieldNumbers(values, fields.size(), written, fail);
    for (std::size_t k = 0; k < fields.size(); ++k)
    {
      fields[k].size = sizes[k];
      if (sizes[k] != 1 && sizes[k] != 2 && sizes[k] != 4 && sizes[k] != 8)
        fail("unsupported field size " + std::to_string(sizes[k]));
    }
  }
  else if (keyword == "type")
    parseTypes(values, fields, fail);
  else if (keyword == "count")
  {
    const std::vector<int> counts = perFieldNumbers(values, fields.size(), written, fail);
    for (std::size_t k = 0; k < fields.size(); ++k)
      fields[k].count = counts[k];
  }
  else
    return false;
  return true;
}

// Reads the header lines off the front of `text`, which is left at the data.
PcdHeader parseHeader(const std::string& path, std::string_view& text)
{
  PcdHeader h;
  std::vector<PcdField>& fields = h.fields;
  bool havePoints = false, haveWidth = false;
  std::size_t width = 0, height = 1;
  std::string_view line;
  int lineNumber = 0;
  const HeaderFailure fail = [&](const std::string& why)
  { throw FileError(path, "PCD header line " + std::to_string(lineNumber) + ": " + why); };

  while (h.data.empty())
  {
    if (!support::nextLine(text, line))
    {
      throw FileError(path, "PCD header has no DATA line (not a PCD file, or truncated)");
    }
    ++lineNumber;
    std::string_view rest = line;
    const std::string_view written = support::nextToken(rest);
    const std::string keyword = support::toLower(written);
    if (keyword.empty() || keyword[0] == '#' || keyword == "version" || keyword == "viewpoint")
      continue;
    std::vector<std::string_view> values;
    for (auto t = support::nextToken(rest); !t.empty(); t = support::nextToken(rest))
      values.push_back(t);
    if (parseFieldLine(keyword, values, written, fields, fail))
      continue;
    if (keyword == "width")
      width = parseCountValue(values, written, fail), haveWidth = true;
    else if (keyword == "height")
      height = parseCountValue(values, written, fail);
    else if (keyword == "points")
      h.points = parseCountValue(values, written, fail), havePoints = true;
    else if (keyword == "data")
      h.data = values.empty() ? "?" : support::toLower(values[0]);
    else
      fail("unknown keyword '" + std::string(written) + "'");
  }
  if (!havePoints)
  {
    if (!haveWidth)
      throw FileError(path, "PCD header has neither POINTS nor WIDTH");
    if (height > 0 && width > std::numeric_limits<std::size_t>::max() / height)
      throw FileError(path, "PCD header's WIDTH x HEIGHT is too large to be a point count");
    h.points = width * height;
  }
  if (fields.empty())
    throw FileError(path, "PCD header has no FIELDS");
  return h;
}

// Where each field's values are: in a binary record (offsets, record size), among a point's
// values (firstValue), and which fields are the coordinates, the normal and the colour.
struct PcdLayout
{
  std::size_t recordSize = 0, valuesPerPoint = 0;
  std::vector<std::size_t> firstValue; // per field
  int xyz[3] = {-1, -1, -1}, normal[3] = {-1, -1, -1}, rgb = -1;
  bool hasNormals() const { return normal[0] >= 0 && normal[1] >= 0 && normal[2] >= 0; }
};

PcdLayout layoutOf(const std::string& path, std::vector<PcdField>& fields)
{
  PcdLayout l;
  for (std::size_t k = 0; k < fields.size(); ++k)
  {
    PcdField& f = fields[k];
    if (f.type == 'F' && f.size != 4 && f.size != 8)
      throw FileError(path,
                      "PCD field '" + f.name + "' is a float of size " + std::to_string(f.size));
    f.offset = l.recordSize;
    l.recordSize += static_cast<std::size_t>(f.size) * f.count;
    const std::string& n = f.name;
    const int i = static_cast<int>(k);
    if (n == "x" || n == "y" || n == "z")
      l.xyz[n[0] - 'x'] = i;
    else if (n == "normal_x" || n == "normal_y" || n == "normal_z")
      l.normal[n.back() - 'x'] = i;
    else if (n == "rgb" || n == "rgba")
    {
      if (f.size != 4) // a packed colour is 4 bytes; copying 4 from a smaller field overflows
        throw FileError(path, "PCD field '" + f.name + "' has SIZE " + std::to_string(f.size) +
                                  "; a packed colour takes 4");
      l.rgb = i;
    }
  }
  if (l.xyz[0] < 0 || l.xyz[1] < 0 || l.xyz[2] < 0)
    throw FileError(path, "PCD file lacks one of the fields x, y, z");
  l.firstValue.resize(fields.size());
  for (std::size_t k = 0; k < fields.size(); ++k)
  {
    l.firstValue[k] = l.valuesPerPoint;
    l.valuesPerPoint += fields[k].count;
  }
  return l;
}

// Every value as double in point-major order (value v of field k of point i), and the packed
// colours as stored.
struct PcdValues
{
  std::vector<double> values;
  std::vector<std::uint32_t> packedColor;
};

[[noreturn]] void dataEndsEarly(const std::string& path, std::size_t declared, std::size_t got)
{
  throw FileError(path, "PCD data ends early (truncated file): the header declares " +
                            std::to_string(declared) + " points but the data holds " +
                            std::to_string(got));
}

// PCL writes rgb as the float whose bits are 0x00RRGGBB (or as an integer).
std::uint32_t packedColourOf(const std::string& path, std::size_t point, std::string_view token,
                             double v, const PcdField& f)
{
  const bool packable = f.type == 'F' ? !(std::abs(v) > std::numeric_limits<float>::max()) // NaN
                                      : v >= 0 && v <= 4294967295.0 && v == std::floor(v);
  if (!packable)
    throw FileError(path, "PCD point " + std::to_string(point) + ": rgb value '" +
                              std::string(token) + "' is not a packed colour");
  if (f.type != 'F')
    return static_cast<std::uint32_t>(v);
  const float asFloat = static_cast<float>(v);
  std::uint32_t packed;
  std::memcpy(&packed, &asFloat, 4);
  return packed;
}

void readAscii(const std::string& path, std::string_view cursor, const PcdHeader& h,
               const PcdLayout& l, PcdValues& out)
{
  for (std::size_t i = 0; i < h.points; ++i)
    for (std::size_t k = 0; k < h.fields.size(); ++k)
      for (int c = 0; c < h.fields[k].count; ++c)
      {
        const std::string_view token = support::nextToken(cursor);
        if (token.empty())
          dataEndsEarly(path, h.points, i);
        double v = 0;
        if (!support::parseNumber(token, v))
          throw FileError(path, "PCD point " + std::to_string(i) + ": '" + std::string(token) +
                                    "' is not a number");
        out.values[i * l.valuesPerPoint + l.firstValue[k] + c] = v;
        if (static_cast<int>(k) == l.rgb && c == 0)
          out.packedColor[i] = packedColourOf(path, i, token, v, h.fields[k]);
      }
}

// binary: records one after the other; binary_compressed: two sizes, then an LZF stream of all
// values of field 0, then field 1, ...
void readBinary(const std::string& path, std::string_view body, const PcdHeader& h,
                const PcdLayout& l, PcdValues& out)
{
  std::string decompressed;
  const char* raw = body.data();
  const bool fieldMajor = h.data == "binary_compressed";
  if (!fieldMajor)
  {
    if (body.size() < h.points * l.recordSize)
      dataEndsEarly(path, h.points, l.recordSize ? body.size() / l.recordSize : 0);
  }
  else
  {
    std::uint32_t sizes[2];
    if (body.size() < 8)
      throw FileError(path, "PCD binary_compressed data ends before its size fields");
    std::memcpy(sizes, body.data(), 8);
    if (sizes[1] != h.points * l.recordSize)
      throw FileError(path, "PCD binary_compressed: uncompressed size " + std::to_string(sizes[1]) +
                                " does not match " + std::to_string(h.points) + " points of " +
                                std::to_string(l.recordSize) + " bytes");
    if (body.size() - 8 < sizes[0])
      throw FileError(path, "PCD binary_compressed data ends early (truncated file)");
    decompressed.resize(sizes[1]);
    if (!lzfDecompress(reinterpret_cast<const unsigned char*>(body.data()) + 8, sizes[0],
                       reinterpret_cast<unsigned char*>(decompressed.data()), sizes[1]))
      throw FileError(path, "PCD binary_compressed data is corrupt (LZF stream invalid)");
    raw = decompressed.data();
  }
  std::size_t fieldStart = 0;
  for (std::size_t k = 0; k < h.fields.size(); ++k)
  {
    const PcdField& f = h.fields[k];
    for (std::size_t i = 0; i < h.points; ++i)
    {
      const char* base =
          fieldMajor ? raw + fieldStart + i * f.size * f.count : raw + i * l.recordSize + f.offset;
      for (int c = 0; c < f.count; ++c)
        out.values[i * l.valuesPerPoint + l.firstValue[k] + c] = decodeField(base + c * f.size, f);
      if (static_cast<int>(k) == l.rgb)
        std::memcpy(&out.packedColor[i], base, 4);
    }
    fieldStart += h.points * f.size * f.count;
  }
}

// Every named field other than the coordinates, normals and colour as an attribute of the
// cloud, its values not yet filled.
void declareAttributes(const std::vector<PcdField>& fields, const PcdLayout& l, PointCloud& cloud)
{
  const bool hasNormals = l.hasNormals();
  for (std::size_t k = 0; k < fields.size(); ++k)
  {
    const int i = static_cast<int>(k);
    const bool known = i == l.xyz[0] || i == l.xyz[1] || i == l.xyz[2] || i == l.rgb ||
                       (hasNormals && (i == l.normal[0] || i == l.normal[1] || i == l.normal[2]));
    if (!known && fields[k].name != "_")
      cloud.attributes.push_back({fields[k].name, fields[k].count, {}});
  }
}

// A packed colour (0xAARRGGBB) as `components` (3 or 4) bytes r g b [a].
void unpackColour(std::uint32_t packed, int components, std::uint8_t* out)
{
  out[0] = static_cast<std::uint8_t>((packed >> 16) & 0xff);
  out[1] = static_cast<std::uint8_t>((packed >> 8) & 0xff);
  out[2] = static_cast<std::uint8_t>(packed & 0xff);
  if (components == 4)
    out[3] = static_cast<std::uint8_t>((packed >> 24) & 0xff);
}

// The declared attributes' values, from their fields' values.
void fillAttributes(const PcdHeader& h, const PcdLayout& l, const PcdValues& in, PointCloud& cloud)
{
  const std::size_t points = h.points;
  for (auto& a : cloud.attributes)
  {
    std::size_t k = 0;
    while (h.fields[k].name != a.name)
      ++k;
    a.values.resize(points * a.components);
    for (std::size_t i = 0; i < points; ++i)
      for (int c = 0; c < a.components; ++c)
        a.values[i * a.components + c] =
            static_cast<float>(in.values[i * l.valuesPerPoint + l.firstValue[k] + c]);
  }
}

// The cloud: coordinates, normals, colours, and every other named field as an attribute.
PointCloud assemble(const PcdHeader& h, const PcdLayout& l, const PcdValues& in)
{
  const std::vector<PcdField>& fields = h.fields;
  const std::size_t points = h.points;
  PointCloud cloud;
  cloud.points.resize(3 * points);
  const bool hasNormals = l.hasNormals();
  if (hasNormals)
    cloud.normals.resize(3 * points);
  if (l.rgb >= 0)
  {
    cloud.colorComponents = fields[l.rgb].name == "rgba" ? 4 : 3;
    cloud.colors.resize(cloud.colorComponents * points);
  }
  declareAttributes(fields, l, cloud);
  for (std::size_t i = 0; i < points; ++i)
  {
    const double* v = &in.values[i * l.valuesPerPoint];
    for (int c = 0; c < 3; ++c)
      cloud.points[3 * i + c] = v[l.firstValue[l.xyz[c]]];
    if (hasNormals)
      for (int c = 0; c < 3; ++c)
        cloud.normals[3 * i + c] = static_cast<float>(v[l.firstValue[l.normal[c]]]);
    if (l.rgb >= 0)
      unpackColour(in.packedColor[i], cloud.colorComponents,
                   &cloud.colors[cloud.colorComponents * i]);
  }
  fillAttributes(h, l, in, cloud);
  return cloud;
}

} // namespace

PointCloud readPCD(const std::string& path)
{
  const std::string bytes = support::readWholeFile(path);
  std::string_view text(bytes);
  PcdHeader header = parseHeader(path, text);
  const PcdLayout layout = layoutOf(path, header.fields);
  if (header.data != "ascii" && header.data != "binary" && header.data != "binary_compressed")
    throw FileError(path,
                    "PCD DATA '" + header.data + "' is not ascii, binary or binary_compressed");
  // A header may claim more points than the file can hold: check before allocating. LZF
  // expands at most 264 bytes from a 3-byte back-reference, hence the bound for compressed data.
  const std::size_t leastBytesPerPoint =
      header.data == "ascii" ? 2 * layout.valuesPerPoint : layout.recordSize;
  const std::size_t capacity = header.data == "binary_compressed" ? text.size() * 88 : text.size();
  if (leastBytesPerPoint > 0 && header.points > capacity / leastBytesPerPoint)
  {
    throw FileError(path, "PCD data ends early (truncated file): the header declares " +
                              std::to_string(header.points) +
                              " points but the data holds at most " +
                              std::to_string(text.size() / leastBytesPerPoint));
  }
  // Compressed, a file may still hold 88 times its size: what the points will hold (the data
  // decompressed, their values, the cloud) is asked of the budget first.
  if (header.data == "binary_compressed")
    MemoryAccount(path).claim(
        static_cast<double>(bytes.size()) +
            static_cast<double>(header.points) *
                static_cast<double>(layout.recordSize + 8 * layout.valuesPerPoint + 40),
        std::to_string(header.points) + " points");
  PcdValues values;
  values.values.resize(header.points * layout.valuesPerPoint);
  values.packedColor.resize(layout.rgb >= 0 ? header.points : 0);
  if (header.data == "ascii")
    readAscii(path, text, header, layout, values);
  else
    readBinary(path, text, header, layout, values);
  return assemble(header, layout, values);
}

namespace
{
// The header for the fields the cloud has: x y z, the normal's, and the packed colour, 4-byte
// floats each.
std::string writtenHeader(const PointCloud& cloud, bool binary)
{
  const std::size_t n = cloud.numberOfPoints();
  std::string fieldsLine = "x y z", sizeLine = "4 4 4", typeLine = "F F F", countLine = "1 1 1";
  if (cloud.hasNormals())
  {
    fieldsLine += " normal_x normal_y normal_z";
    sizeLine += " 4 4 4";
    typeLine += " F F F";
    countLine += " 1 1 1";
  }
  if (cloud.hasColors())
  {
    fieldsLine += " rgb";
    sizeLine += " 4";
    typeLine += " F";
    countLine += " 1";
  }
  return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS " + fieldsLine +
         "\nSIZE " + sizeLine + "\nTYPE " + typeLine + "\nCOUNT " + countLine + "\nWIDTH " +
         std::to_string(n) + "\nHEIGHT 1\n" + "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
         std::to_string(n) + "\nDATA " + (binary ? "binary" : "ascii") + "\n";
}

// One value: its 4 bytes in binary, its shortest decimal form and a space in ASCII.
void appendValue(std::string& out, float v, bool binary)
{
  if (binary)
  {
    char b[4];
    std::memcpy(b, &v, 4);
    out.append(b, 4);
  }
  else
  {
    char buffer[32];
    const auto r = std::to_chars(buffer, buffer + sizeof(buffer), v);
    out.append(buffer, r.ptr);
    out += ' ';
  }
}

// An RGB colour as PCL packs it: 0x00RRGGBB in the bytes of a float.
float packedColour(const std::uint8_t* c)
{
  const std::uint32_t packed = (std::uint32_t(c[0]) << 16) | (std::uint32_t(c[1]) << 8) | c[2];
  float asFloat;
  std::memcpy(&asFloat, &packed, 4);
  return asFloat;
}
} // namespace

void writePCD(const std::string& path, const PointCloud& cloud, bool binary)
{
  cloud.validate();
  const std::size_t n = cloud.numberOfPoints();
  std::string out = writtenHeader(cloud, binary);
  for (std::size_t i = 0; i < n; ++i)
  {
    for (int c = 0; c < 3; ++c)
      appendValue(out, static_cast<float>(cloud.points[3 * i + c]), binary);
    if (cloud.hasNormals())
      for (int c = 0; c < 3; ++c)
        appendValue(out, cloud.normals[3 * i + c], binary);
    if (cloud.hasColors())
      appendValue(out, packedColour(&cloud.colors[cloud.colorComponents * i]), binary);
    if (!binary)
      out.back() = '\n';
  }
  support::writeWholeFile(path, out);
}

} // namespace dp
