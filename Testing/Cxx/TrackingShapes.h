// SPDX-License-Identifier: BSD-3-Clause
// What the tests of the tracker and its parts share: a tube template, the frame data of its
// samples, and a sampled bending-tube sequence with its truth.
#pragma once

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/track/ClothEnergy.h"
#include "dp/track/FrameData.h"
#include "dp/track/TrackerOptions.h"

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

namespace dp::test
{

struct Shape
{
  std::vector<std::int64_t> triangles;
  std::vector<double> positions;
};

inline Shape tube(std::size_t rings = 10, std::size_t segments = 12, std::size_t frame = 0)
{
  dp::BendingTube::Options o;
  o.rings = rings;
  o.segments = segments;
  dp::BendingTube t(o);
  return {t.triangles(), t.positions(frame)};
}

// The frame data of a tube's samples (with their true normals), voxel = diagonal / 60.
struct Frame
{
  Shape shape;
  dp::TriangleMesh mesh{shape.triangles, shape.positions.size() / 3};
  double voxel = dp::boundingBoxDiagonal(shape.positions) / 60;
  std::unique_ptr<dp::FrameData> data;
  std::vector<double> mass;
  double L = 0;
  // `truth`: the frame's vertex positions on `base`'s connectivity (the template).
  explicit Frame(const std::vector<double>& truth, bool estimateNormals = false,
                 Shape base = tube())
      : shape(std::move(base))
  {
    dp::SamplerOptions o;
    o.pointsPerFrame = 3000;
    const dp::PointCloud c = dp::sampleSurface(truth, shape.triangles, o, 0);
    dp::FrameDataOptions fo;
    fo.voxelSize = voxel;
    fo.surfaceArea = mesh.totalArea(shape.positions.data());
    fo.spreadCount = 600;
    data = std::make_unique<dp::FrameData>(c.points.data(), c.numberOfPoints(),
                                           estimateNormals ? nullptr : c.normals.data(), fo);
    const dp::ClothEnergy cloth(mesh, shape.positions.data(), dp::ClothParameters{});
    mass = cloth.vertexMass();
    L = cloth.lengthScale();
  }
};

// A generated sequence: the tube's frames sampled with noise; the template is frame 0's mesh.
struct Sequence
{
  dp::BendingTube animation;
  std::vector<dp::PointCloud> frames;
  double diagonal;
};

// The tube bends but does not twist: a twist of a round tube leaves its surface unchanged,
// so no tracker could see it in the points. Of 30 frames, the first `frames` are sampled
// (per-frame motion of the tip: about 10% of the diagonal).
// The bending tube's truth compresses the inside of the bend: not an isometry, so its triangles
// change shape. The corner-angle (shear) terms, off by default because real motion (the horse
// sequences) tracks better without them, hold those triangles here.
inline dp::TrackerOptions tubeOptions()
{
  dp::TrackerOptions o;
  o.cloth.shear = 0.05;
  return o;
}

inline Sequence makeSequence(std::size_t frames, double noise, std::size_t holes,
                             std::size_t points)
{
  dp::BendingTube::Options o;
  o.frames = 30;
  o.rings = 16;
  o.segments = 12;
  o.maxBendRadians = 1.0;
  o.maxTwistRadians = 0.0;
  Sequence s{dp::BendingTube(o), {}, 0};
  s.diagonal = dp::boundingBoxDiagonal(s.animation.positions(0));
  dp::SamplerOptions sampling;
  sampling.pointsPerFrame = points;
  sampling.noiseStdDev = noise * s.diagonal;
  sampling.holes = holes;
  sampling.holeRadius = 0.08 * s.diagonal;
  for (std::size_t f = 0; f < frames; ++f)
    s.frames.push_back(
        dp::sampleSurface(s.animation.positions(f), s.animation.triangles(), sampling, f));
  return s;
}

inline double vertexRms(const std::vector<double>& a, const std::vector<double>& b)
{
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    sum += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(sum / static_cast<double>(a.size() / 3));
}
} // namespace dp::test
