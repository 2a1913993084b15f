// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file PointCloudIO.h
 * @brief Readers and writers for the point-cloud formats the engine parses itself.
 *
 * Formats: PLY (ASCII, binary little and big endian; vertices with any scalar properties,
 * normals nx/ny/nz, colours red/green/blue[/alpha], faces), PCD (ASCII and binary as PCL
 * writes it, with packed `rgb`/`rgba`), plain text (XYZ, PTS, CSV, TXT: x y z [nx ny nz],
 * optional header line naming the columns), OBJ (v, vn, f; point-only files too) and Draco
 * (.drc meshes and point clouds, through Google's library: DracoFormat.cxx).
 * VTK's own formats (.vtp, .vtu, .vtk) are read by the VTK layer with VTK's readers.
 *
 * Every reader reads the whole file with one system call, checks it against its header
 * (a truncated binary body, a short ASCII body, an index out of range are errors) and throws
 * dp::FileError whose message starts with the file name. Non-finite coordinates are not
 * errors: readPointCloud() drops them and counts them in the report.
 *
 * Memory: a header's counts are checked against what the bytes after it can hold before
 * anything is allocated, so a file costs at most, resident, per byte of it (its densest records;
 * TestMemoryBudget holds these): binary PLY 12, ASCII PLY 10, binary PCD 18, ASCII PCD 10, text
 * 12, OBJ 10; a .series file (FrameSequence) 16. Compressed PCD may hold 88 times its size: what
 * its points will take is asked of the memory budget first (MemoryBudget.h), as is what a
 * Draco file's counts make its decoder and the decoded frame hold.
 */
#pragma once

#include "dp/io/PointCloud.h"

#include <string>

namespace dp
{

enum class PointFileFormat
{
  Unknown,
  PLY,
  PCD,
  Text, // .xyz .pts .csv .txt
  OBJ,
  Draco,                  // .drc
  VTKXMLPolyData,         // .vtp
  VTKXMLUnstructuredGrid, // .vtu
  VTKLegacy               // .vtk
};

/** The format implied by the file name's extension (case-insensitive). */
PointFileFormat formatFromFileName(const std::string& path);

/** True for the formats readPointCloud() parses (not the VTK formats, not Unknown). */
bool isEngineFormat(PointFileFormat format);

/** Every extension a point sequence may have, for messages: ".ply .pcd ... .vtk". */
const char* readableExtensions();

struct ReadReport
{
  std::size_t droppedNonFinite = 0; // points removed because a coordinate was NaN or Inf
};

/** Reads any engine format (by extension); drops non-finite points (counted in report). */
PointCloud readPointCloud(const std::string& path, ReadReport* report = nullptr);

PointCloud readPLY(const std::string& path);
PointCloud readPCD(const std::string& path);
PointCloud readTextPoints(const std::string& path);
PointCloud readOBJ(const std::string& path);
PointCloud readDRC(const std::string& path);

enum class PlyEncoding
{
  Ascii,
  BinaryLittleEndian,
  BinaryBigEndian
};

/** Writes float32 vertices (+ normals, colours, attributes) and int32 faces. */
void writePLY(const std::string& path, const PointCloud& cloud,
              PlyEncoding encoding = PlyEncoding::BinaryLittleEndian);

/** Writes PCD v0.7 fields x y z [normal_x normal_y normal_z] [rgb], ASCII or binary. */
void writePCD(const std::string& path, const PointCloud& cloud, bool binary = true);

/** Writes "x y z [nx ny nz]" lines (space separated; comma separated for a .csv name). */
void writeTextPoints(const std::string& path, const PointCloud& cloud);

/** Writes v [vn] and f lines. */
void writeOBJ(const std::string& path, const PointCloud& cloud);

/** Writes a Draco mesh (edgebreaker) when every face is a triangle, else a Draco point cloud;
 *  positions quantised to 14 bits of the bounding box, normals 10, colours lossless. */
void writeDRC(const std::string& path, const PointCloud& cloud);

/** Writes in the format the extension names (binary PLY, binary PCD, text, OBJ, Draco). */
void writePointCloud(const std::string& path, const PointCloud& cloud);

} // namespace dp
