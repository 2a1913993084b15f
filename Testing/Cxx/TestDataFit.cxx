// SPDX-License-Identifier: BSD-3-Clause
// A take's fit to its data (measureDataFit) and compression judged by it (compressAgainstData,
// PcaErrorMeasure::RmsDeviation).
#include "dp/compress/PcaCompression.h"
#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/track/DataFit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace
{

// The bending tube's frames (frame-major) and, per frame, samples of its surface with noise.
struct Take
{
  dp::BendingTube tube;
  dp::TriangleMesh mesh;
  std::vector<double> positions;
  std::vector<dp::FrameSamples> samples;
  double diagonal = 0;

  Take(double noise, std::size_t frames = 30)
      : tube(options(frames)), mesh(tube.triangles(), tube.numberOfVertices())
  {
    diagonal = dp::boundingBoxDiagonal(tube.positions(0));
    dp::SamplerOptions o;
    o.pointsPerFrame = 3000;
    o.noiseStdDev = noise * diagonal;
    for (std::size_t t = 0; t < frames; ++t)
    {
      const std::vector<double> x = tube.positions(t);
      positions.insert(positions.end(), x.begin(), x.end());
      const dp::PointCloud c = dp::sampleSurface(x, tube.triangles(), o, t);
      samples.push_back({c.points, c.normals, 0.01 * diagonal});
    }
  }
  static dp::BendingTube::Options options(std::size_t frames)
  {
    dp::BendingTube::Options o;
    o.frames = frames;
    return o;
  }
  std::vector<const dp::FrameSamples*> views() const
  {
    std::vector<const dp::FrameSamples*> all;
    for (const dp::FrameSamples& s : samples)
      all.push_back(&s);
    return all;
  }
};

TEST(DataFit, MeasuresTheSamplesDistanceToTheMeshAndCountsFarOnesApart)
{
  Take take(0.0, 4);
  // Samples on the mesh itself: no distance.
  const dp::DataFit exact =
      dp::measureDataFit(take.mesh, take.positions.data(), take.views(), 0.05 * take.diagonal);
  EXPECT_LT(exact.rms, 1e-9 * take.diagonal);
  EXPECT_EQ(exact.samples, 4 * take.samples[0].size());
  // One frame's samples pushed 1 % of the diagonal along x: that frame's share of the RMS; a
  // sample moved beyond reach is counted apart, out of the RMS.
  for (std::size_t i = 0; i < take.samples[1].points.size(); i += 3)
    take.samples[1].points[i] += 0.001 * take.diagonal;
  take.samples[2].points[0] += take.diagonal;
  const dp::DataFit moved =
      dp::measureDataFit(take.mesh, take.positions.data(), take.views(), 0.05 * take.diagonal);
  EXPECT_EQ(moved.beyondReach, 1u);
  EXPECT_EQ(moved.samples, exact.samples - 1);
  EXPECT_GT(moved.rms, 0.1 * 0.001 * take.diagonal);
  EXPECT_LT(moved.rms, 0.001 * take.diagonal);
  // A frame without samples (an empty frame) counts nothing.
  std::vector<const dp::FrameSamples*> views = take.views();
  views[1] = nullptr;
  EXPECT_EQ(
      dp::measureDataFit(take.mesh, take.positions.data(), views, 0.05 * take.diagonal).samples,
      exact.samples - take.samples[1].size() - 1);
}

TEST(DataFit, TheRmsDeviationTargetIsMetAndReported)
{
  const Take take(0.0);
  const std::size_t nv = take.mesh.numberOfVertices(), frames = take.samples.size();
  std::size_t components = 0;
  for (double fraction : {0.001, 0.004})
  {
    dp::PcaOptions o;
    o.measure = dp::PcaErrorMeasure::RmsDeviation;
    o.target = fraction * take.diagonal;
    const dp::CompressedSequence c =
        dp::compressSequence(take.positions.data(), nv, frames, o, take.mesh.triangles());
    const Eigen::Map<const Eigen::MatrixXd> A(take.positions.data(),
                                              static_cast<Eigen::Index>(3 * nv),
                                              static_cast<Eigen::Index>(frames));
    const double rms = (A - c.pca.model.reconstruct()).norm() / std::sqrt(double(nv * frames));
    EXPECT_LE(rms, o.target);
    EXPECT_GT(rms, 0.2 * o.target); // not far tighter than asked
    EXPECT_NEAR(c.report.rmsError, rms, 1e-9 * take.diagonal);
    if (components > 0)
    {
      EXPECT_LT(c.report.components, components); // a looser target keeps fewer
    }
    components = c.report.components;
  }
}

TEST(DataFit, CompressionAgainstTheDataKeepsTheFitWithinTheGrowthAllowed)
{
  // Noisy samples (0.3 % of the diagonal): their distance to the mesh is the noise's, and a
  // deviation well below it barely adds to it, so the data's target is looser than KG 0.2 %.
  const Take take(0.003);
  const std::size_t nv = take.mesh.numberOfVertices(), frames = take.samples.size();
  const double reach = 0.05 * take.diagonal;
  for (double growth : {0.05, 0.1})
  {
    const dp::DataFitCompression c = dp::compressAgainstData(
        take.mesh, take.positions.data(), frames, take.views(), reach, growth, {});
    EXPECT_LE(c.decompressed.rms, (1 + growth) * c.tracked.rms);
    EXPECT_NEAR(c.growth, c.decompressed.rms / c.tracked.rms - 1, 1e-12);
    EXPECT_GT(c.growth, 0.3 * growth); // the search uses what it is allowed
    EXPECT_GE(c.rounds, 1);
    dp::PcaOptions kg;
    const dp::CompressedSequence strict =
        dp::compressSequence(take.positions.data(), nv, frames, kg, take.mesh.triangles());
    EXPECT_LT(c.sequence.report.bitsPerVertexFrame, strict.report.bitsPerVertexFrame);
  }
  EXPECT_THROW(dp::compressAgainstData(take.mesh, take.positions.data(), frames, take.views(),
                                       reach, 0.0, {}),
               std::invalid_argument);
  // No data at all: the codec's default target.
  const std::vector<const dp::FrameSamples*> none(frames, nullptr);
  const dp::DataFitCompression blind =
      dp::compressAgainstData(take.mesh, take.positions.data(), frames, none, reach, 0.1, {});
  EXPECT_LE(blind.sequence.report.kgError, 0.2);
}

// RMS distance between two takes' vertices.
double rmsBetween(const std::vector<double>& a, const std::vector<double>& b)
{
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    sum += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(sum / static_cast<double>(a.size() / 3));
}

// The take with each vertex moved along its surface (across its normal) by a random step of
// about `share` of the mesh's mean edge length, anew every frame: a tracker's sliding.
std::vector<double> wandering(const Take& take, double share)
{
  const std::size_t nv = take.mesh.numberOfVertices();
  double edge = 0;
  std::size_t edges = 0;
  for (std::size_t v = 0; v < nv; ++v)
    for (std::int64_t w : take.mesh.neighbours(v))
    {
      double d2 = 0;
      for (int c = 0; c < 3; ++c)
        d2 += std::pow(take.positions[3 * v + c] - take.positions[3 * w + c], 2);
      edge += std::sqrt(d2);
      ++edges;
    }
  edge /= static_cast<double>(edges);
  std::mt19937 random(7);
  std::normal_distribution<double> step(0.0, share * edge);
  std::vector<double> out = take.positions, normals(3 * nv);
  for (std::size_t t = 0; t < take.samples.size(); ++t)
  {
    double* x = &out[3 * nv * t];
    take.mesh.vertexNormals(x, normals.data());
    for (std::size_t v = 0; v < nv; ++v)
    {
      double move[3] = {step(random), step(random), step(random)}, across = 0;
      for (int c = 0; c < 3; ++c)
        across += move[c] * normals[3 * v + c];
      for (int c = 0; c < 3; ++c)
        x[3 * v + c] += move[c] - across * normals[3 * v + c];
    }
  }
  return out;
}

TEST(DataFit, SlidingAlongTheSurfaceRemovesAWanderTheDataDoNotSee)
{
  const Take take(0.003);
  const std::size_t frames = take.samples.size();
  const std::vector<double> wander = wandering(take, 0.2);
  const double before = rmsBetween(wander, take.positions);
  const std::vector<double> slid =
      dp::slideAlongSurface(take.mesh, wander.data(), frames, 6, dp::PcaLayout::Trajectories);
  // The vertices come back toward where the motion puts them ...
  EXPECT_LT(rmsBetween(slid, take.positions), 0.6 * before);
  // ... and the surface stays where the data are.
  const double reach = 0.05 * take.diagonal;
  std::vector<std::vector<bool>> within;
  const dp::DataFit wanderFit =
      dp::measureDataFit(take.mesh, wander.data(), take.views(), reach, &within);
  const dp::DataFit slidFit =
      dp::measureDataFit(take.mesh, slid.data(), take.views(), reach, &within);
  EXPECT_LT(slidFit.rms, 1.05 * wanderFit.rms);

  // The codec codes the take slid too and keeps it: fewer bits, the fit within the growth.
  const dp::DataFitCompression plain = dp::compressAgainstData(take.mesh, wander.data(), frames,
                                                               take.views(), reach, 0.1, {}, false);
  const dp::DataFitCompression sliding =
      dp::compressAgainstData(take.mesh, wander.data(), frames, take.views(), reach, 0.1, {}, true);
  EXPECT_FALSE(plain.slid);
  EXPECT_TRUE(sliding.slid);
  EXPECT_LT(sliding.sequence.report.bitsPerVertexFrame,
            0.8 * plain.sequence.report.bitsPerVertexFrame);
  EXPECT_LE(sliding.decompressed.rms, 1.1 * sliding.tracked.rms);
  EXPECT_EQ(sliding.tracked.rms, plain.tracked.rms); // judged against the take as given
  std::vector<double> decoded(wander.size());
  const std::size_t nv = take.mesh.numberOfVertices();
  for (std::size_t t = 0; t < frames; ++t)
    sliding.sequence.pca.model.frame(t, &decoded[3 * nv * t]);
  EXPECT_NEAR(sliding.sequence.report.rmsError, rmsBetween(decoded, wander),
              1e-9 * rmsBetween(decoded, wander)); // its error too, not the slid take's
}

} // namespace
