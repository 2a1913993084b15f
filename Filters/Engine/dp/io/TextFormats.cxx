// SPDX-License-Identifier: BSD-3-Clause
// Plain-text point formats (XYZ, PTS, CSV, TXT) and Wavefront OBJ.
#include "dp/io/FileText.h"
#include "dp/io/PointCloudIO.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace dp
{
namespace
{

bool isCommentLine(std::string_view line)
{
  support::skipSeparators(line);
  return line.empty() || line[0] == '#' || line.substr(0, 2) == "//";
}

// Meaning of a column: a coordinate, a normal component, a colour channel or an attribute.
int columnRole(const std::string& name)
{
  static const char* const roles[] = {"x",     "y",    "z",        "nx",       "ny",
                                      "nz",    "r",    "g",        "b",        "red",
                                      "green", "blue", "normal_x", "normal_y", "normal_z"};
  const int map[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 6, 7, 8, 3, 4, 5};
  for (std::size_t k = 0; k < std::size(roles); ++k)
    if (name == roles[k])
      return map[k];
  return -1;
}

// The rows of numbers of a text file, with the column names of a header line if there is one.
struct TextTable
{
  std::vector<std::string> header; // lower case; empty without a header line
  std::size_t columns = 0;         // 0: no data rows
  std::size_t declaredCount = 0;   // PTS: the count on the first line (0: none)
  std::vector<double> values;      // row-major
  std::size_t rows() const { return columns ? values.size() / columns : 0; }
};

// The line's tokens and, where they are numbers, their values; false when one is not a number.
bool splitRow(std::string_view line, std::vector<double>& row, std::vector<std::string>& tokens)
{
  const bool comma = line.find(',') != std::string_view::npos;
  row.clear();
  tokens.clear();
  std::string_view rest = line;
  bool numeric = true;
  for (auto token = support::nextToken(rest, comma); !token.empty();
       token = support::nextToken(rest, comma))
  {
    double v = 0;
    tokens.emplace_back(token);
    if (support::parseNumber(token, v))
      row.push_back(v);
    else
      numeric = false;
  }
  return numeric;
}

// The first row of numbers sets the column count: at least x y z, and the header's if any.
void setColumns(const std::string& path, std::size_t lineNumber, std::size_t columns, TextTable& t)
{
  t.columns = columns;
  if (t.columns < 3)
    throw FileError(path, "line " + std::to_string(lineNumber) + " has " +
                              std::to_string(t.columns) + " values; at least x y z are needed");
  if (!t.header.empty() && t.header.size() != t.columns)
    throw FileError(path, "the header names " + std::to_string(t.header.size()) +
                              " columns but line " + std::to_string(lineNumber) + " has " +
                              std::to_string(t.columns));
}

TextTable readTable(const std::string& path, std::string_view text, bool isPts)
{
  TextTable t;
  std::string_view line;
  std::size_t lineNumber = 0;
  bool sawData = false;
  std::vector<double> row;
  std::vector<std::string> tokens;
  while (support::nextLine(text, line))
  {
    ++lineNumber;
    if (isCommentLine(line))
      continue;
    const bool numeric = splitRow(line, row, tokens);
    if (!sawData && !numeric && t.header.empty())
    {
      // A header line naming the columns (CSV style).
      for (auto& token : tokens)
        t.header.push_back(support::toLower(token));
      continue;
    }
    if (!numeric)
    {
      throw FileError(path, "line " + std::to_string(lineNumber) + ": '" + std::string(line) +
                                "' is not a row of numbers");
    }
    // A PTS file starts with a line holding only the point count.
    if (!sawData && isPts && row.size() == 1 && t.declaredCount == 0)
    {
      if (!(row[0] >= 0) || !support::wholeNumberWithin(row[0], support::LargestCount))
        throw FileError(path, "line " + std::to_string(lineNumber) + ": the point count '" +
                                  std::string(line) + "' is not a count");
      t.declaredCount = static_cast<std::size_t>(row[0]);
      continue;
    }
    if (!sawData)
    {
      setColumns(path, lineNumber, row.size(), t);
      sawData = true;
    }
    if (row.size() != t.columns)
    {
      throw FileError(path, "line " + std::to_string(lineNumber) + " has " +
                                std::to_string(row.size()) + " values, earlier lines have " +
                                std::to_string(t.columns) + " (truncated or malformed file)");
    }
    t.values.insert(t.values.end(), row.begin(), row.end());
  }
  return t;
}

// What each column is (columnRole's codes; -1 an attribute, named in `names`): from the header
// names, else by the column count.
std::vector<int> rolesOf(const std::string& path, const TextTable& t, bool isPts,
                         std::vector<std::string>& names)
{
  const std::size_t columns = t.columns;
  std::vector<int> role(columns, -1);
  names.resize(columns);
  for (std::size_t c = 0; c < columns; ++c)
    names[c] = c < t.header.size() ? t.header[c] : "Column" + std::to_string(c);
  if (!t.header.empty())
  {
    for (std::size_t c = 0; c < columns; ++c)
      role[c] = columnRole(t.header[c]);
    bool hasXYZ[3] = {false, false, false};
    for (int r : role)
      if (r >= 0 && r < 3)
        hasXYZ[r] = true;
    if (!hasXYZ[0] || !hasXYZ[1] || !hasXYZ[2])
      throw FileError(path, "the header line does not name columns x, y and z");
    return role;
  }
  role[0] = 0, role[1] = 1, role[2] = 2;
  if (isPts && (columns == 4 || columns == 7))
  {
    names[3] = "Intensity"; // Leica PTS: x y z intensity [r g b]
    if (columns == 7)
      role[4] = 6, role[5] = 7, role[6] = 8;
  }
  else if (columns >= 6)
  {
    role[3] = 3, role[4] = 4, role[5] = 5;
  }
  return role;
}

PointCloud cloudOf(const TextTable& t, const std::vector<int>& role,
                   const std::vector<std::string>& names)
{
  const std::size_t n = t.rows(), columns = t.columns;
  PointCloud cloud;
  bool hasNormals = false, hasColors = false;
  for (int r : role)
  {
    hasNormals = hasNormals || (r >= 3 && r < 6);
    hasColors = hasColors || r >= 6;
  }
  cloud.points.resize(3 * n);
  if (hasNormals)
    cloud.normals.resize(3 * n);
  if (hasColors)
  {
    cloud.colorComponents = 3;
    cloud.colors.resize(3 * n);
  }
  std::vector<int> attribute(columns, -1);
  for (std::size_t c = 0; c < columns; ++c)
    if (role[c] < 0)
    {
      attribute[c] = static_cast<int>(cloud.attributes.size());
      cloud.attributes.push_back({names[c], 1, std::vector<float>(n)});
    }
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t c = 0; c < columns; ++c)
    {
      const double v = t.values[i * columns + c];
      const int r = role[c];
      if (r >= 0 && r < 3)
        cloud.points[3 * i + r] = v;
      else if (r >= 3 && r < 6)
        cloud.normals[3 * i + r - 3] = static_cast<float>(v);
      else if (r >= 6)
        cloud.colors[3 * i + r - 6] = static_cast<std::uint8_t>(v < 0 ? 0 : v > 255 ? 255 : v);
      else
        cloud.attributes[attribute[c]].values[i] = static_cast<float>(v);
    }
  return cloud;
}

// Wavefront OBJ read a statement at a time: the vertices (with "v x y z r g b" colours), the
// faces, and the normals, bound to vertices through the faces' v//vn references or listed one
// per vertex in order. Other statements (vt, g, o, s, usemtl, mtllib, l, p, comments) carry
// nothing we keep.
class ObjParser
{
public:
  explicit ObjParser(const std::string& path) : Path(path) {}

  void statement(std::string_view line)
  {
    ++LineNumber;
    std::string_view rest = line;
    const std::string_view keyword = support::nextToken(rest);
    if (keyword == "v" || keyword == "vn")
      coordinates(keyword == "v", rest);
    else if (keyword == "f")
      face(rest);
  }

  PointCloud finish()
  {
    if (Cloud.colorComponents == 3 && Cloud.colors.size() != 3 * Cloud.numberOfPoints())
    {
      Cloud.colors.clear(); // only some vertices had colours
      Cloud.colorComponents = 0;
    }
    const std::size_t n = Cloud.numberOfPoints();
    const bool referenced =
        std::any_of(NormalOfVertex.begin(), NormalOfVertex.end(), [](auto i) { return i >= 0; });
    if (referenced || (n > 0 && NormalList.size() == 3 * n))
    {
      Cloud.normals.assign(3 * n, 0.0f);
      for (std::size_t i = 0; i < n; ++i)
      {
        const std::int64_t k = referenced ? NormalOfVertex[i] : static_cast<std::int64_t>(i);
        if (k >= 0)
          std::memcpy(&Cloud.normals[3 * i], &NormalList[3 * k], 3 * sizeof(float));
      }
    }
    return std::move(Cloud);
  }

private:
  [[noreturn]] void fail(const std::string& why) const
  {
    throw FileError(Path, "OBJ line " + std::to_string(LineNumber) + ": " + why);
  }

  // "v x y z [r g b]" or "vn x y z".
  void coordinates(bool vertex, std::string_view rest)
  {
    double xyz[6];
    int count = 0;
    for (auto t = support::nextToken(rest); !t.empty() && count < 6; t = support::nextToken(rest))
      if (!support::parseNumber(t, xyz[count++]))
        fail("'" + std::string(t) + "' is not a number");
    if (count < 3)
      fail("expected 3 coordinates (truncated file?)");
    if (!vertex)
    {
      for (int c = 0; c < 3; ++c)
        NormalList.push_back(static_cast<float>(xyz[c]));
      return;
    }
    Cloud.points.insert(Cloud.points.end(), xyz, xyz + 3);
    if (count == 6) // colours in [0,1]; kept only if the first vertex has them
    {
      if (Cloud.colors.empty() && Cloud.numberOfPoints() == 1)
        Cloud.colorComponents = 3;
      if (Cloud.colorComponents == 3 && Cloud.colors.size() == 3 * (Cloud.numberOfPoints() - 1))
        for (int c = 3; c < 6; ++c)
          Cloud.colors.push_back(
              static_cast<std::uint8_t>(std::min(255.0, std::max(0.0, xyz[c] * 255.0 + 0.5))));
    }
    NormalOfVertex.push_back(-1);
  }

  // "f" and three or more of v, v/vt, v//vn or v/vt/vn; negative indices count back from the end.
  void face(std::string_view rest)
  {
    Face.clear();
    for (auto t = support::nextToken(rest); !t.empty(); t = support::nextToken(rest))
      Face.push_back(faceVertex(t));
    if (Face.size() < 3)
      fail("a face needs at least 3 vertices");
    Cloud.addFace(Face.data(), Face.size());
  }

  // One corner of a face: its vertex index; a normal it references is bound to the vertex.
  std::int64_t faceVertex(std::string_view t)
  {
    const auto nv = static_cast<std::int64_t>(Cloud.numberOfPoints());
    const std::size_t slash = t.find('/');
    double v = 0;
    if (!support::parseNumber(t.substr(0, slash), v) || v == 0 ||
        !support::wholeNumberWithin(v, support::LargestCount))
      fail("bad face vertex '" + std::string(t) + "'");
    auto index = static_cast<std::int64_t>(v);
    index = index > 0 ? index - 1 : nv + index;
    if (std::abs(v) > static_cast<double>(nv) || index < 0 || index >= nv)
      fail("face uses vertex " + std::string(t) + " but only " + std::to_string(nv) +
           " vertices are defined so far");
    const std::size_t lastSlash = t.rfind('/');
    if (slash == std::string_view::npos || lastSlash <= slash)
      return index; // v or v/vt
    const auto nn = static_cast<std::int64_t>(NormalList.size() / 3);
    double vn = 0;
    if (support::parseNumber(t.substr(lastSlash + 1), vn) && vn != 0 &&
        support::wholeNumberWithin(vn, static_cast<double>(nn)))
    {
      auto n = static_cast<std::int64_t>(vn);
      n = n > 0 ? n - 1 : nn + n;
      if (n >= 0 && n < nn)
        NormalOfVertex[index] = n;
    }
    return index;
  }

  const std::string& Path;
  std::size_t LineNumber = 0;
  PointCloud Cloud;
  std::vector<float> NormalList;            // vn entries, as listed
  std::vector<std::int64_t> NormalOfVertex; // vn index used by each vertex (-1: none)
  std::vector<std::int64_t> Face;
};

} // namespace

PointCloud readTextPoints(const std::string& path)
{
  const std::string bytes = support::readWholeFile(path);
  const bool isPts =
      support::toLower(path.substr(path.size() >= 4 ? path.size() - 4 : 0)) == ".pts";
  const TextTable table = readTable(path, bytes, isPts);
  if (table.columns == 0)
    return {}; // an empty frame; the caller decides whether that is an error
  if (table.declaredCount != 0 && table.declaredCount != table.rows())
    throw FileError(path, "the PTS header declares " + std::to_string(table.declaredCount) +
                              " points but the file holds " + std::to_string(table.rows()) +
                              " (truncated file?)");
  std::vector<std::string> names;
  const std::vector<int> role = rolesOf(path, table, isPts, names);
  return cloudOf(table, role, names);
}

void writeTextPoints(const std::string& path, const PointCloud& cloud)
{
  cloud.validate();
  const bool csv = support::toLower(path.substr(path.size() >= 4 ? path.size() - 4 : 0)) == ".csv";
  const char separator = csv ? ',' : ' ';
  std::string out;
  if (csv)
    out = cloud.hasNormals() ? "x,y,z,nx,ny,nz\n" : "x,y,z\n";
  char buffer[32];
  for (std::size_t i = 0; i < cloud.numberOfPoints(); ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      out.append(buffer, std::to_chars(buffer, buffer + 32, cloud.points[3 * i + c]).ptr);
      out += separator;
    }
    if (cloud.hasNormals())
      for (int c = 0; c < 3; ++c)
      {
        out.append(buffer, std::to_chars(buffer, buffer + 32, cloud.normals[3 * i + c]).ptr);
        out += separator;
      }
    out.back() = '\n';
  }
  support::writeWholeFile(path, out);
}

PointCloud readOBJ(const std::string& path)
{
  const std::string bytes = support::readWholeFile(path);
  std::string_view text(bytes);
  std::string_view line;
  ObjParser parser(path);
  while (support::nextLine(text, line))
    parser.statement(line);
  return parser.finish();
}

void writeOBJ(const std::string& path, const PointCloud& cloud)
{
  cloud.validate();
  std::string out = "# written by DynamicPoints\n";
  char buffer[32];
  auto triple = [&](const char* key, auto* v)
  {
    out += key;
    for (int c = 0; c < 3; ++c)
    {
      out += ' ';
      out.append(buffer, std::to_chars(buffer, buffer + 32, v[c]).ptr);
    }
    out += '\n';
  };
  for (std::size_t i = 0; i < cloud.numberOfPoints(); ++i)
    triple("v", &cloud.points[3 * i]);
  if (cloud.hasNormals())
    for (std::size_t i = 0; i < cloud.numberOfPoints(); ++i)
      triple("vn", &cloud.normals[3 * i]);
  for (std::size_t f = 0; f < cloud.numberOfFaces(); ++f)
  {
    out += 'f';
    for (auto k = cloud.faceOffsets[f]; k < cloud.faceOffsets[f + 1]; ++k)
    {
      const std::string id = std::to_string(cloud.faceConnectivity[k] + 1);
      out += ' ' + id + (cloud.hasNormals() ? "//" + id : "");
    }
    out += '\n';
  }
  support::writeWholeFile(path, out);
}

} // namespace dp
