// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file PointCloud.h
 * @brief The engine's in-memory point cloud: one frame of a point sequence.
 *
 * A plain, VTK-free container. Positions are stored as doubles (3 per point, interleaved),
 * so geo-referenced scans keep their precision; optional per-point normals, colours and
 * further named attributes ride along, and polygons are kept when the file had them
 * (a PLY/OBJ mesh used as a template, for instance).
 *
 * Limits: everything is in memory; one PointCloud is one frame, never a whole sequence.
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace dp
{

/** A named per-point array of float values with a fixed number of components. */
struct PointAttribute
{
  std::string name;
  int components = 1;
  std::vector<float> values; // components per point, interleaved
};

/** One frame of points (see file comment). */
struct PointCloud
{
  std::vector<double> points;       // x y z per point
  std::vector<float> normals;       // empty, or nx ny nz per point
  std::vector<std::uint8_t> colors; // empty, or colorComponents per point (0..255)
  int colorComponents = 0;          // 0, 3 (RGB) or 4 (RGBA)
  std::vector<PointAttribute> attributes;
  // Polygons in CSR form: face f uses faceConnectivity[faceOffsets[f] .. faceOffsets[f+1]).
  // Either both are empty or faceOffsets has numberOfFaces()+1 entries.
  std::vector<std::int64_t> faceOffsets;
  std::vector<std::int64_t> faceConnectivity;

  std::size_t numberOfPoints() const { return points.size() / 3; }
  std::size_t numberOfFaces() const { return faceOffsets.empty() ? 0 : faceOffsets.size() - 1; }
  bool hasNormals() const { return !normals.empty(); }
  bool hasColors() const { return !colors.empty(); }

  /** Appends a polygon given by point indices. */
  void addFace(const std::int64_t* ids, std::size_t count);

  /** Checks sizes of every array against numberOfPoints() and face indices against the
   *  point range; throws std::logic_error naming the first inconsistency. */
  void validate() const;
};

/**
 * Removes points whose coordinates are NaN or infinite, together with their attributes.
 * Faces that use a removed point are removed too; the remaining face indices are renumbered.
 * @return the number of points removed.
 */
std::size_t dropNonFinitePoints(PointCloud& cloud);

/** Error raised by the readers and writers: the message always starts with the file name. */
class FileError : public std::runtime_error
{
public:
  FileError(const std::string& path, const std::string& what)
      : std::runtime_error(path + ": " + what), Path(path)
  {
  }
  const std::string& path() const { return Path; }

private:
  std::string Path;
};

} // namespace dp
