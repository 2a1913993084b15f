// SPDX-License-Identifier: BSD-3-Clause
// BenchmarkTracker --scaling: the paper's Fig. 4, time per frame against the vertex count.
#pragma once

#include "BenchmarkUtilities.h"

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/track/Tracker.h"

#include <cmath>
#include <cstdio>
#include <vector>

namespace dp::bench
{

// The paper's Fig. 4: time per frame against the vertex count, on the procedural bending tube
// at resolutions from 500 to 50k vertices (same shape, same 20k points per frame).
inline std::vector<std::size_t> ScalingSizes = {500, 1000, 2000, 5000, 10000, 20000, 50000};

inline void scalingTable(const dp::TrackerOptions& options, std::size_t frames, std::size_t points,
                         bool givenNormals)
{
  std::printf("\n== scaling (bending tube, %zu frames after the first, %zu points per frame)\n",
              frames, points);
  std::printf("%10s %12s %14s %12s %14s %12s %12s %28s\n", "vertices", "ms/frame", "ms/1k vertices",
              "iterations", "vertex RMS %", "resident MiB", "KiB/vertex",
              "data/coarse/fine/other ms");
  for (std::size_t target : ScalingSizes)
  {
    dp::BendingTube::Options shape;
    shape.segments = static_cast<std::size_t>(std::lround(std::sqrt(target / 1.67)));
    shape.rings = (target + shape.segments - 1) / shape.segments;
    const dp::BendingTube tube(shape);
    // What the tracker holds while it works: resident memory from before it is made to after its
    // last frame (its mesh, energies, graph and solvers, and the last frame's data).
    const double residentBefore = dp::bench::residentMiB();
    dp::Tracker tracker(dp::TriangleMesh(tube.triangles(), tube.numberOfVertices()),
                        tube.positions(0), options);
    dp::SamplerOptions sampling;
    sampling.pointsPerFrame = points;
    sampling.normals = givenNormals;
    std::vector<double> ms, dataMs, coarseMs, fineMs, otherMs;
    double iterations = 0, sum = 0;
    const double diagonal = dp::boundingBoxDiagonal(tube.positions(0));
    for (std::size_t f = 0; f <= frames; ++f)
    {
      const dp::PointCloud cloud =
          dp::sampleSurface(tube.positions(f), tube.triangles(), sampling, f);
      const dp::FrameResult r = tracker.track(cloud.points.data(), cloud.numberOfPoints(),
                                              cloud.hasNormals() ? cloud.normals.data() : nullptr);
      if (f == 0)
        continue; // the first frame starts at the data
      ms.push_back(1e3 * r.seconds);
      dataMs.push_back(1e3 * r.timings.data);
      coarseMs.push_back(1e3 * r.timings.coarse);
      fineMs.push_back(1e3 * r.timings.fine);
      otherMs.push_back(1e3 * (r.seconds - r.timings.data - r.timings.coarse - r.timings.fine));
      iterations += r.iterations;
      const std::vector<double> truth = tube.positions(f);
      double e = 0;
      for (std::size_t i = 0; i < truth.size(); ++i)
        e += (truth[i] - r.positions[i]) * (truth[i] - r.positions[i]);
      sum += e / static_cast<double>(truth.size() / 3);
    }
    const double median = dp::bench::median(ms);
    const double resident = dp::bench::residentMiB() - residentBefore;
    std::printf("%10zu %12.1f %14.2f %12.1f %13.3f%% %12.1f %12.2f %8.0f/%.0f/%.0f/%.0f\n",
                tube.numberOfVertices(), median,
                1e3 * median / static_cast<double>(tube.numberOfVertices()),
                iterations / static_cast<double>(frames),
                100 * std::sqrt(sum / static_cast<double>(frames)) / diagonal, resident,
                1024 * resident / static_cast<double>(tube.numberOfVertices()),
                dp::bench::median(dataMs), dp::bench::median(coarseMs), dp::bench::median(fineMs),
                dp::bench::median(otherMs));
    std::fflush(stdout);
  }
}

} // namespace dp::bench
