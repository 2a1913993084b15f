// SPDX-License-Identifier: BSD-3-Clause
// Decoded per-frame meshes against reference meshes, measured as the main job's report measures
// its own (dp::cli::distortionAgainstInput: D1 and D2 PSNR, peak = each reference frame's
// diagonal), so that a per-frame codec (Draco) and the main job are on one metric, and a take's
// .dpz can be held against the true surface it was sampled from.
//
//   BenchmarkMeshFidelity DECODED REFERENCE_FOLDER [PATTERN] [--base]
//
// DECODED: a folder of one mesh file per frame, matched with the reference's by sorted name
// (PATTERN, default *.ply), or a .dpz (its detail layer's fine mesh; --base: the tracked mesh
// under it). Prints one line: frames, mean and worst D1 / D2 PSNR in dB, and the mean RMS
// distance (the square root of the mean D1 over the frames).
#include "MeshFidelity.h"

#include "dp/compress/DetailCoding.h"
#include "dp/compress/PcaCompression.h"
#include "dp/geometry/SubdivisionMap.h"

#include "dp/geometry/MeshSurfaceSamples.h"
#include "dp/io/FrameSequence.h"
#include "dp/io/PointCloudIO.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <string>
#include <vector>

namespace
{
// The decoded frames: mesh files, or a .dpz's frames at its fine or its base level.
class Decoded
{
public:
  Decoded(const std::string& path, const std::string& pattern, bool base)
  {
    if (path.size() > 4 && path.substr(path.size() - 4) == ".dpz")
    {
      Sequence = std::make_unique<dp::CompressedSequence>(dp::readCompressedSequence(path));
      if (!base && Sequence->detail.levels > 0)
        Map = std::make_unique<dp::SubdivisionMap>(
            Sequence->triangles, Sequence->pca.model.vertices, Sequence->detail.levels);
    }
    else
      Files = dp::FrameSequence::fromDirectory(path, pattern);
  }
  std::size_t size() const { return Sequence ? Sequence->pca.model.frames : Files.size(); }
  dp::PointCloud frame(std::size_t t) const
  {
    if (!Sequence)
      return dp::readPointCloud(Files[t].path);
    dp::PointCloud c;
    const std::vector<std::int64_t>& triangles = Map ? Map->fineTriangles() : Sequence->triangles;
    c.points.resize(3 * (Map ? Map->fineVertices() : Sequence->pca.model.vertices));
    if (Map)
      dp::detailedFrame(*Sequence, *Map, t, c.points.data());
    else
      Sequence->pca.model.frame(t, c.points.data());
    for (std::size_t i = 0; i < triangles.size(); i += 3)
      c.addFace(&triangles[i], 3);
    return c;
  }

private:
  dp::FrameSequence Files;
  std::unique_ptr<dp::CompressedSequence> Sequence;
  std::unique_ptr<dp::SubdivisionMap> Map;
};
} // namespace

int main(int argc, char** argv)
{
  std::vector<std::string> args(argv + 1, argv + argc);
  const bool base = std::find(args.begin(), args.end(), "--base") != args.end();
  args.erase(std::remove(args.begin(), args.end(), "--base"), args.end());
  if (args.size() < 2)
  {
    std::fprintf(stderr,
                 "usage: BenchmarkMeshFidelity DECODED REFERENCE_FOLDER [PATTERN] [--base]\n");
    return 2;
  }
  try
  {
    const std::string pattern = args.size() > 2 ? args[2] : "*.ply";
    const Decoded decoded(args[0], pattern, base);
    const dp::FrameSequence inputs = dp::FrameSequence::fromDirectory(args[1], pattern);
    if (decoded.size() == 0 || decoded.size() != inputs.size())
    {
      std::fprintf(stderr, "error: %zu decoded frames for %zu reference frames\n", decoded.size(),
                   inputs.size());
      return 1;
    }
    double sum1 = 0, sum2 = 0, worst1 = HUGE_VAL, worst2 = HUGE_VAL, mse = 0;
    for (std::size_t t = 0; t < inputs.size(); ++t)
    {
      const dp::PointCloud frame = decoded.frame(t);
      const std::vector<std::int64_t> triangles = dp::triangleFans(frame);
      const dp::MeshDistortion d = dp::cli::distortionAgainstInput(
          dp::meshSurfaceOf(frame, triangles), dp::readPointCloud(inputs[t].path));
      mse += d.d1;
      const double p1 = std::min(d.d1Psnr(), 300.0), p2 = std::min(d.d2Psnr(), 300.0);
      sum1 += p1;
      sum2 += p2;
      worst1 = std::min(worst1, p1);
      worst2 = std::min(worst2, p2);
    }
    const auto n = static_cast<double>(inputs.size());
    std::printf("frames %zu D1 PSNR %.3f dB (worst %.3f) D2 PSNR %.3f dB (worst %.3f) RMS %.6g\n",
                inputs.size(), sum1 / n, worst1, sum2 / n, worst2, std::sqrt(mse / n));
    return 0;
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
