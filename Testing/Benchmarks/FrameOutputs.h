// SPDX-License-Identifier: BSD-3-Clause
// BenchmarkTracker's per-frame outputs: --csv rows and --dump meshes (the tracked frame coloured
// by its error, its truth and its points as PLY).
#pragma once

#include "TakeMeasures.h"

#include "dp/io/PointCloudIO.h"
#include "dp/track/Tracker.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

namespace dp::bench
{

// --csv: one row a frame.
inline void writeCsvRow(std::ostream& csv, const std::string& label, std::size_t f,
                        const dp::FrameResult& r, const FrameFigures& figures, double vertices)
{
  csv << label << ',' << f << ',' << 1e3 * std::sqrt(figures.vertexSquaredSum / vertices) << ','
      << 1e3 * figures.largestVertexError << ','
      << 1e3 * std::sqrt(figures.surfaceSquaredSum / vertices) << ',' << 100 * figures.uncovered
      << ',' << r.iterations << ',' << 1e3 * r.seconds << '\n';
}

inline void dumpFrame(const std::string& folder, std::size_t frame,
                      const std::vector<double>& positions, const std::vector<double>& truth,
                      const std::vector<std::int64_t>& triangles, const dp::PointCloud& data)
{
  std::filesystem::create_directories(folder);
  dp::PointCloud mesh;
  mesh.points = positions;
  for (std::size_t t = 0; t < triangles.size(); t += 3)
    mesh.addFace(&triangles[t], 3);
  // Each vertex's error against the truth, for colouring.
  dp::PointAttribute error{"error", 1, {}};
  for (std::size_t i = 0; i < positions.size(); i += 3)
    error.values.push_back(static_cast<float>(
        std::sqrt((positions[i] - truth[i]) * (positions[i] - truth[i]) +
                  (positions[i + 1] - truth[i + 1]) * (positions[i + 1] - truth[i + 1]) +
                  (positions[i + 2] - truth[i + 2]) * (positions[i + 2] - truth[i + 2]))));
  mesh.attributes.push_back(error);
  // ... and as colours: grey at 0, red at 5 cm and beyond.
  mesh.colorComponents = 3;
  for (float e : error.values)
  {
    const double u = std::min(1.0, e / 0.05);
    const auto c = [&](double from, double to)
    { return static_cast<std::uint8_t>(from + u * (to - from)); };
    mesh.colors.insert(mesh.colors.end(), {c(200, 230), c(200, 20), c(200, 20)});
  }
  char name[64];
  std::snprintf(name, sizeof name, "/tracked_%04zu.ply", frame);
  dp::writePLY(folder + name, mesh);
  mesh.points = truth;
  std::snprintf(name, sizeof name, "/truth_%04zu.ply", frame);
  dp::writePLY(folder + name, mesh);
  std::snprintf(name, sizeof name, "/points_%04zu.ply", frame);
  // The frame's data as the tracker was given it (with --per-frame-mesh, the mesh's faces too).
  dp::PointCloud input;
  input.points = data.points;
  input.faceOffsets = data.faceOffsets;
  input.faceConnectivity = data.faceConnectivity;
  dp::writePLY(folder + name, input);
}

} // namespace dp::bench
