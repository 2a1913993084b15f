// SPDX-License-Identifier: BSD-3-Clause
#include "dp/io/PointCloudIO.h"

#include "dp/io/FileText.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

namespace dp
{
namespace support
{

std::string readWholeFile(const std::string& path)
{
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
  {
    throw FileError(path, "is a folder, not a file");
  }
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"),
                                                       &std::fclose);
  if (!file)
  {
    throw FileError(path, std::string("cannot open file (") + std::strerror(errno) + ")");
  }
  std::string bytes;
  char buffer[1 << 16];
  // Size first so a large file is read into one allocation.
  if (std::fseek(file.get(), 0, SEEK_END) == 0)
  {
    const long size = std::ftell(file.get());
    if (size > 0)
    {
      bytes.reserve(static_cast<std::size_t>(size));
    }
    std::rewind(file.get());
  }
  std::size_t got = 0;
  while ((got = std::fread(buffer, 1, sizeof(buffer), file.get())) > 0)
  {
    bytes.append(buffer, got);
  }
  if (std::ferror(file.get()))
  {
    throw FileError(path, std::string("read error (") + std::strerror(errno) +
                              ") - is it a directory or an unreadable file?");
  }
  return bytes;
}

void writeWholeFile(const std::string& path, const std::string& bytes)
{
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "wb"),
                                                       &std::fclose);
  if (!file)
  {
    throw FileError(path, std::string("cannot create file (") + std::strerror(errno) + ")");
  }
  if (std::fwrite(bytes.data(), 1, bytes.size(), file.get()) != bytes.size() ||
      std::fflush(file.get()) != 0)
  {
    throw FileError(path, std::string("write error (") + std::strerror(errno) + ")");
  }
}

void moveIntoPlace(const std::string& partial, const std::string& path)
{
  if (std::rename(partial.c_str(), path.c_str()) != 0)
  {
    const std::string reason = std::strerror(errno);
    std::remove(partial.c_str());
    throw FileError(path, "cannot put the written file in place (" + reason + ")");
  }
}

void writeBesideAndMove(const std::string& path,
                        const std::function<void(const std::string& partial)>& write)
{
  const std::string partial = path + ".partial";
  try
  {
    write(partial);
  }
  catch (...)
  {
    std::remove(partial.c_str());
    throw;
  }
  moveIntoPlace(partial, path);
}

std::string toLower(std::string_view s)
{
  std::string out(s);
  for (char& c : out)
  {
    if (c >= 'A' && c <= 'Z')
    {
      c = static_cast<char>(c - 'A' + 'a');
    }
  }
  return out;
}

} // namespace support

PointFileFormat formatFromFileName(const std::string& path)
{
  const std::size_t dot = path.find_last_of('.');
  const std::size_t slash = path.find_last_of("/\\");
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash))
  {
    return PointFileFormat::Unknown;
  }
  const std::string ext = support::toLower(std::string_view(path).substr(dot + 1));
  if (ext == "ply")
    return PointFileFormat::PLY;
  if (ext == "pcd")
    return PointFileFormat::PCD;
  if (ext == "xyz" || ext == "pts" || ext == "csv" || ext == "txt")
    return PointFileFormat::Text;
  if (ext == "obj")
    return PointFileFormat::OBJ;
  if (ext == "drc")
    return PointFileFormat::Draco;
  if (ext == "vtp")
    return PointFileFormat::VTKXMLPolyData;
  if (ext == "vtu")
    return PointFileFormat::VTKXMLUnstructuredGrid;
  if (ext == "vtk")
    return PointFileFormat::VTKLegacy;
  return PointFileFormat::Unknown;
}

bool isEngineFormat(PointFileFormat format)
{
  return format == PointFileFormat::PLY || format == PointFileFormat::PCD ||
         format == PointFileFormat::Text || format == PointFileFormat::OBJ ||
         format == PointFileFormat::Draco;
}

const char* readableExtensions()
{
  return ".ply .pcd .xyz .pts .csv .txt .obj .drc .vtp .vtu .vtk";
}

PointCloud readPointCloud(const std::string& path, ReadReport* report)
{
  PointCloud cloud;
  switch (formatFromFileName(path))
  {
  case PointFileFormat::PLY:
    cloud = readPLY(path);
    break;
  case PointFileFormat::PCD:
    cloud = readPCD(path);
    break;
  case PointFileFormat::Text:
    cloud = readTextPoints(path);
    break;
  case PointFileFormat::OBJ:
    cloud = readOBJ(path);
    break;
  case PointFileFormat::Draco:
    cloud = readDRC(path);
    break;
  case PointFileFormat::Unknown:
    throw FileError(path,
                    std::string("unknown file extension; expected one of ") + readableExtensions());
  default:
    throw FileError(path, "VTK formats are read by the VTK layer, not by the engine");
  }
  // Every reader checks its own; this keeps a slip in one from reaching the renumbering below.
  try
  {
    cloud.validate();
  }
  catch (const std::logic_error& e)
  {
    throw FileError(path, e.what());
  }
  const std::size_t dropped = dropNonFinitePoints(cloud);
  if (report)
  {
    report->droppedNonFinite = dropped;
  }
  return cloud;
}

void writePointCloud(const std::string& path, const PointCloud& cloud)
{
  switch (formatFromFileName(path))
  {
  case PointFileFormat::PLY:
    return writePLY(path, cloud);
  case PointFileFormat::PCD:
    return writePCD(path, cloud);
  case PointFileFormat::Text:
    return writeTextPoints(path, cloud);
  case PointFileFormat::OBJ:
    return writeOBJ(path, cloud);
  case PointFileFormat::Draco:
    return writeDRC(path, cloud);
  default:
    throw FileError(path, "cannot write this extension; use .ply .pcd .xyz .csv .txt .obj or .drc");
  }
}

} // namespace dp
