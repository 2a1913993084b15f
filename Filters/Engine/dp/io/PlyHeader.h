// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file PlyHeader.h
 * @brief The header of a PLY file (Turk's format) as the reader sees it: the encoding of the
 *        body, its elements with their counts and properties, and where the body starts.
 *
 * Internal to dp/io: PlyReader.cxx reads the body the header describes; PlyWriter.cxx writes
 * its own fixed header and needs none of this.
 */
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace dp::support
{

/** A property's value type, under either of its names (char or int8, float or float32...). */
enum class PlyType
{
  Int8,
  UInt8,
  Int16,
  UInt16,
  Int32,
  UInt32,
  Float32,
  Float64
};

/** The bytes one value of type `t` takes in a binary body. */
inline std::size_t sizeOf(PlyType t)
{
  switch (t)
  {
  case PlyType::Int8:
  case PlyType::UInt8:
    return 1;
  case PlyType::Int16:
  case PlyType::UInt16:
    return 2;
  case PlyType::Int32:
  case PlyType::UInt32:
  case PlyType::Float32:
    return 4;
  case PlyType::Float64:
    return 8;
  }
  return 0;
}

struct PlyProperty
{
  std::string name;
  PlyType type = PlyType::Float32;
  bool isList = false;
  PlyType countType = PlyType::UInt8;
};

struct PlyElement
{
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> properties;
};

/** How the body is written ("format ascii", "binary_little_endian", "binary_big_endian"). */
enum class PlyBodyEncoding
{
  Ascii,
  Little,
  Big
};

struct PlyHeader
{
  PlyBodyEncoding encoding = PlyBodyEncoding::Ascii;
  std::vector<PlyElement> elements;
  std::size_t bodyOffset = 0; // the body's first byte in the file
};

/** Parses the header at the start of `bytes`, the whole file `path`; throws FileError naming
 *  the file and the header line at fault (unknown keyword, type or format, a malformed element
 *  line, a property before any element, no format line, no end_header). */
PlyHeader parsePlyHeader(const std::string& path, const std::string& bytes);

} // namespace dp::support
