// SPDX-License-Identifier: BSD-3-Clause
#include "MeshFidelity.h"

#include "dp/compress/DetailCoding.h"
#include "dp/geometry/MeshDistortion.h"
#include "dp/geometry/SubdivisionMap.h"
#include "dp/io/PointCloudIO.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

namespace dp::cli
{
namespace
{
// JSON has no infinity: identical surfaces are written as null.
nlohmann::json decibels(double value)
{
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json();
}

// Frame t's decompressed mesh (at its detail layer's fine level when it has one: `fine`) against
// its input mesh `frame`.
MeshDistortion measureFrame(const CompressedSequence& sequence, const SubdivisionMap* fine,
                            std::size_t t, const PointCloud& frame, std::vector<double>& positions)
{
  if (fine)
    detailedFrame(sequence, *fine, t, positions.data());
  else
    sequence.pca.model.frame(t, positions.data());
  const std::vector<std::int64_t>& triangles = fine ? fine->fineTriangles() : sequence.triangles;
  MeshSurface decoded;
  decoded.positions = positions.data();
  decoded.vertices = positions.size() / 3;
  decoded.triangles = triangles.data();
  decoded.triangleCount = triangles.size() / 3;
  return distortionAgainstInput(decoded, frame);
}
} // namespace

MeshDistortion distortionAgainstInput(const MeshSurface& decoded, const PointCloud& input)
{
  const std::vector<std::int64_t> inputTriangles = triangleFans(input);
  // Enough samples that each of the input's triangles is visited about twice.
  const std::size_t samples = std::max<std::size_t>(20000, 2 * inputTriangles.size() / 3);
  return meshDistortion(meshSurfaceOf(input, inputTriangles), decoded, samples);
}

nlohmann::json measureAgainstInputMeshes(const CompressedSequence& sequence,
                                         const std::vector<std::string>& framePaths,
                                         std::size_t fileBytes,
                                         const std::function<void(std::size_t)>& progress)
{
  const std::size_t frames = sequence.pca.model.frames;
  if (frames == 0 || frames != framePaths.size() ||
      readPointCloud(framePaths[0]).numberOfFaces() == 0)
    return nullptr;
  std::unique_ptr<SubdivisionMap> fine;
  if (sequence.detail.levels > 0)
    fine = std::make_unique<SubdivisionMap>(sequence.triangles, sequence.pca.model.vertices,
                                            sequence.detail.levels);
  std::vector<double> positions(3 * (fine ? fine->fineVertices() : sequence.pca.model.vertices));
  nlohmann::json perFrame = nlohmann::json::array();
  double sum1 = 0, sum2 = 0, inputVertices = 0;
  double worst1 = std::numeric_limits<double>::infinity(), worst2 = worst1;
  std::size_t samples = 0;
  for (std::size_t t = 0; t < frames; ++t)
  {
    const PointCloud frame = readPointCloud(framePaths[t]);
    const MeshDistortion d = measureFrame(sequence, fine.get(), t, frame, positions);
    // A frame decoded exactly counts as the finest the doubles resolve.
    const double p1 = std::min(d.d1Psnr(), 300.0), p2 = std::min(d.d2Psnr(), 300.0);
    sum1 += p1;
    sum2 += p2;
    worst1 = std::min(worst1, p1);
    worst2 = std::min(worst2, p2);
    inputVertices += static_cast<double>(frame.numberOfPoints());
    samples = std::max(samples, d.samples);
    perFrame.push_back({{"frame", t},
                        {"inputVertices", frame.numberOfPoints()},
                        {"d1PsnrDb", decibels(d.d1Psnr())},
                        {"d2PsnrDb", decibels(d.d2Psnr())}});
    if (progress)
      progress(t);
  }
  const auto n = static_cast<double>(frames);
  return {{"d1PsnrDb", sum1 / n},
          {"d2PsnrDb", sum2 / n},
          {"worstD1PsnrDb", worst1},
          {"worstD2PsnrDb", worst2},
          {"bitsPerInputVertexFrame", 8.0 * static_cast<double>(fileBytes) / inputVertices},
          {"geometryBitsPerInputVertexFrame",
           8.0 * static_cast<double>(fileBytes - sequence.report.colourBytes) / inputVertices},
          {"detailBitsPerInputVertexFrame",
           8.0 * static_cast<double>(sequence.report.detailBytes) / inputVertices},
          {"inputVertices", inputVertices},
          {"samplesPerSurface", samples},
          {"perFrame", perFrame}};
}

} // namespace dp::cli
