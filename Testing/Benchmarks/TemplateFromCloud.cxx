// SPDX-License-Identifier: BSD-3-Clause
// The template the product makes from one frame's points, written as a PLY mesh, for
// BenchmarkTemplate.py to measure beside a peer's:
//   TemplateFromCloud CLOUD OUTPUT.ply [VERTICES]
// prints "template: V vertices, T triangles in S s (reconstruction)".
#include "dp/field/TemplateMesh.h"
#include "dp/io/PointCloudIO.h"

#include <chrono>
#include <cstdio>
#include <exception>
#include <string>

int main(int argc, char** argv)
{
  if (argc < 3)
  {
    std::fprintf(stderr, "usage: TemplateFromCloud CLOUD OUTPUT.ply [VERTICES]\n");
    return 2;
  }
  try
  {
    const dp::PointCloud cloud = dp::readPointCloud(argv[1]);
    dp::TemplateOptions options;
    options.source = dp::TemplateSource::Points;
    if (argc > 3)
      options.targetVertices = std::stoul(argv[3]);
    const auto start = std::chrono::steady_clock::now();
    const dp::TemplateMesh t =
        dp::makeTemplate(cloud.points.data(), cloud.numberOfPoints(),
                         cloud.hasNormals() ? cloud.normals.data() : nullptr, {}, options, argv[1]);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    dp::PointCloud mesh;
    mesh.points = t.positions;
    for (std::size_t i = 0; i + 2 < t.triangles.size(); i += 3)
      mesh.addFace(&t.triangles[i], 3);
    dp::writePLY(argv[2], mesh);
    std::printf("template: %zu vertices, %zu triangles in %.2f s (%s)\n", t.positions.size() / 3,
                t.triangles.size() / 3, seconds, t.report.summary().c_str());
    return 0;
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "TemplateFromCloud: %s\n", e.what());
    return 1;
  }
}
