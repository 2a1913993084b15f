// SPDX-License-Identifier: BSD-3-Clause
// libFuzzer target: a template mesh (PLY or OBJ, DP_FUZZ_EXTENSION) on arbitrary bytes, taken the
// way the tracker takes a template: read, polygons split into triangles, the topology built, a
// Tracker made with the default options (cloth rest state, deformation graph). Built with
// DP_FUZZ_TRACK, one frame is tracked as well (the template's own vertices, moved) when the mesh
// has at most 200 vertices: about 15x fewer executions a second, so it is a target of its own.
// An exception is the expected answer to a bad template; a crash, a hang, a leak or undefined
// behaviour is a finding.
#include "FuzzInputFile.h"

#include "dp/io/AnimatedMesh.h"
#include "dp/io/PointCloudIO.h"
#include "dp/track/Tracker.h"

#include <cstdint>
#include <exception>
#include <vector>

namespace
{
// Larger templates are built but not tracked: a frame costs milliseconds there, and the
// mutations that matter (indices, counts, numbers) show on small meshes as well.
#ifdef DP_FUZZ_TRACK
constexpr std::size_t LargestTrackedTemplate = 200;
#else
constexpr std::size_t LargestTrackedTemplate = 0;
#endif
} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  const std::string path = dp::fuzz::writeInput(data, size, DP_FUZZ_EXTENSION);
  if (path.empty())
    return 0;
  try
  {
    const dp::PointCloud cloud = dp::readPointCloud(path);
    const std::size_t n = cloud.numberOfPoints();
    dp::Tracker tracker(dp::TriangleMesh(dp::triangulateFaces(cloud), n), cloud.points,
                        dp::TrackerOptions());
    if (n > LargestTrackedTemplate)
      return 0;
    std::vector<double> frame = cloud.points;
    for (std::size_t i = 0; i < frame.size(); i += 3)
      frame[i] += 0.01 * (1.0 + frame[i + 1]);
    (void)tracker.track(frame.data(), n, nullptr).positions.size();
  }
  catch (const std::exception&)
  {
    // A refused template or frame: what bad input should get.
  }
  return 0;
}
