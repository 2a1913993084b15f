// SPDX-License-Identifier: BSD-3-Clause
// PLY writer: float32 vertices (+ normals, colours, attributes) and int32 faces, in ASCII or
// binary of either byte order.
#include "dp/io/FileText.h"
#include "dp/io/PointCloudIO.h"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <type_traits>

namespace dp
{
namespace
{

template <typename T>
void appendValue(std::string& out, T value, PlyEncoding encoding)
{
  if (encoding == PlyEncoding::Ascii)
  {
    if constexpr (std::is_floating_point_v<T>)
    {
      char buffer[32];
      const auto r = std::to_chars(buffer, buffer + sizeof(buffer), value);
      out.append(buffer, r.ptr);
    }
    else
    {
      out += std::to_string(value);
    }
    out += ' ';
    return;
  }
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (encoding == PlyEncoding::BinaryBigEndian)
  {
    std::reverse(bytes, bytes + sizeof(T));
  }
  out.append(bytes, sizeof(T));
}

// The header: the vertex element with what the cloud has, then the face element if any.
std::string headerText(const PointCloud& cloud, PlyEncoding encoding)
{
  const std::size_t n = cloud.numberOfPoints();
  std::string out = "ply\nformat ";
  out += encoding == PlyEncoding::Ascii             ? "ascii"
         : encoding == PlyEncoding::BinaryBigEndian ? "binary_big_endian"
                                                    : "binary_little_endian";
  out += " 1.0\ncomment written by DynamicPoints\n";
  out += "element vertex " + std::to_string(n) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  if (cloud.hasNormals())
    out += "property float nx\nproperty float ny\nproperty float nz\n";
  if (cloud.hasColors())
  {
    out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    if (cloud.colorComponents == 4)
      out += "property uchar alpha\n";
  }
  for (const auto& a : cloud.attributes)
  {
    for (int c = 0; c < a.components; ++c)
    {
      out += "property float " + a.name + (a.components > 1 ? "_" + std::to_string(c) : "") + "\n";
    }
  }
  if (cloud.numberOfFaces() > 0)
  {
    out += "element face " + std::to_string(cloud.numberOfFaces()) + "\n";
    out += "property list uchar int vertex_indices\n";
  }
  out += "end_header\n";
  return out;
}

// Vertex i's values in the header's order (one line in ASCII).
void appendVertex(std::string& out, const PointCloud& cloud, std::size_t i, PlyEncoding encoding)
{
  for (int k = 0; k < 3; ++k)
    appendValue(out, static_cast<float>(cloud.points[3 * i + k]), encoding);
  if (cloud.hasNormals())
    for (int k = 0; k < 3; ++k)
      appendValue(out, cloud.normals[3 * i + k], encoding);
  if (cloud.hasColors())
    for (int k = 0; k < cloud.colorComponents; ++k)
    {
      const std::uint8_t c = cloud.colors[cloud.colorComponents * i + k];
      if (encoding == PlyEncoding::Ascii)
        appendValue(out, static_cast<int>(c), encoding);
      else
        out += static_cast<char>(c);
    }
  for (const auto& a : cloud.attributes)
    for (int c = 0; c < a.components; ++c)
      appendValue(out, a.values[a.components * i + c], encoding);
  if (encoding == PlyEncoding::Ascii)
    out.back() = '\n';
}

// Face f: its vertex count (a uchar: more than 255 vertices cannot be written) and indices.
void appendFace(std::string& out, const std::string& path, const PointCloud& cloud, std::size_t f,
                PlyEncoding encoding)
{
  const auto begin = cloud.faceOffsets[f];
  const auto count = cloud.faceOffsets[f + 1] - begin;
  if (count > 255)
  {
    throw FileError(path, "cannot write a PLY face with more than 255 vertices");
  }
  if (encoding == PlyEncoding::Ascii)
    appendValue(out, static_cast<int>(count), encoding);
  else
    out += static_cast<char>(count);
  for (std::int64_t k = 0; k < count; ++k)
    appendValue(out, static_cast<std::int32_t>(cloud.faceConnectivity[begin + k]), encoding);
  if (encoding == PlyEncoding::Ascii)
    out.back() = '\n';
}

} // namespace

void writePLY(const std::string& path, const PointCloud& cloud, PlyEncoding encoding)
{
  cloud.validate();
  const std::size_t n = cloud.numberOfPoints();
  std::string out = headerText(cloud, encoding);
  out.reserve(out.size() + n * 40 + cloud.faceConnectivity.size() * 5);
  for (std::size_t i = 0; i < n; ++i)
    appendVertex(out, cloud, i, encoding);
  for (std::size_t f = 0; f < cloud.numberOfFaces(); ++f)
    appendFace(out, path, cloud, f, encoding);
  support::writeWholeFile(path, out);
}

} // namespace dp
