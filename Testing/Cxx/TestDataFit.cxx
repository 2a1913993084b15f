// SPDX-License-Identifier: BSD-3-Clause
// A take's fit to its data (measureDataFit), compression judged by it (compressAgainstData,
// PcaErrorMeasure::RmsDeviation), and the slide along the surface (slideAlongSurface): how far it
// moves a vertex, and where the truth is known, that it moves it toward the truth.
#include "dp/compress/DataFitCompression.h"
#include "dp/compress/PcaCompression.h"
#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/DataFit.h"
#include "dp/geometry/FrameSamples.h"
#include "dp/geometry/SurfaceLocator.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
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

// Each sample's squared distance to frame t's mesh, by brute force over every triangle.
std::vector<double> bruteForceDistances(const Take& take, std::size_t t)
{
  const auto& tri = take.mesh.triangles();
  const double* x = take.positions.data() + 3 * take.mesh.numberOfVertices() * t;
  const dp::FrameSamples& s = take.samples[t];
  std::vector<double> d2(s.size(), HUGE_VAL);
  for (std::size_t i = 0; i < s.size(); ++i)
    for (std::size_t f = 0; f < tri.size(); f += 3)
    {
      double w[3], c[3];
      d2[i] =
          std::min(d2[i], dp::closestPointOnTriangle(&s.points[3 * i], x + 3 * tri[f],
                                                     x + 3 * tri[f + 1], x + 3 * tri[f + 2], w, c));
    }
  return d2;
}

TEST(DataFit, MatchesBruteForceAndMarksTheSamplesItCounted)
{
  // Noisy samples, a few moved far off: the RMS over those within reach, the count of the others
  // and the flags of `within` are brute force's. Measured again with those flags on a moved take,
  // only the flagged samples count, whatever their distance.
  Take take(0.004, 3);
  for (std::size_t i = 0; i < take.samples[1].size(); i += 97)
    take.samples[1].points[3 * i + 2] += 0.3 * take.diagonal;
  const double reach = 0.01 * take.diagonal;
  std::vector<std::vector<bool>> within;
  const dp::DataFit fit =
      dp::measureDataFit(take.mesh, take.positions.data(), take.views(), reach, &within);
  ASSERT_EQ(within.size(), take.samples.size());
  double sum = 0;
  std::size_t inside = 0, outside = 0;
  std::vector<std::vector<double>> distances;
  for (std::size_t t = 0; t < take.samples.size(); ++t)
  {
    distances.push_back(bruteForceDistances(take, t));
    ASSERT_EQ(within[t].size(), take.samples[t].size());
    for (std::size_t i = 0; i < distances[t].size(); ++i)
    {
      const bool near = distances[t][i] < reach * reach;
      EXPECT_EQ(within[t][i], near) << "frame " << t << ", sample " << i;
      (near ? inside : outside) += 1;
      sum += near ? distances[t][i] : 0.0;
    }
  }
  EXPECT_GT(outside, take.samples[1].size() / 97); // the moved samples and the noise's tail
  EXPECT_EQ(fit.samples, inside);
  EXPECT_EQ(fit.beyondReach, outside);
  EXPECT_NEAR(fit.rms, std::sqrt(sum / static_cast<double>(inside)), 1e-12 * take.diagonal);

  // The take moved by more than the reach: with the flags given, no sample is beyond it.
  for (std::size_t i = 0; i < take.positions.size(); i += 3)
    take.positions[i] += 0.02 * take.diagonal;
  const dp::DataFit flagged =
      dp::measureDataFit(take.mesh, take.positions.data(), take.views(), reach, &within);
  EXPECT_EQ(flagged.samples, inside);
  EXPECT_EQ(flagged.beyondReach, 0u);
  sum = 0;
  std::size_t farButFlagged = 0;
  for (std::size_t t = 0; t < take.samples.size(); ++t)
  {
    const std::vector<double> d2 = bruteForceDistances(take, t);
    for (std::size_t i = 0; i < d2.size(); ++i)
      if (within[t][i])
      {
        sum += d2[i];
        farButFlagged += d2[i] > reach * reach;
      }
  }
  EXPECT_NEAR(flagged.rms, std::sqrt(sum / static_cast<double>(inside)), 1e-12 * take.diagonal);
  EXPECT_GT(farButFlagged, inside / 10);
}

TEST(FrameSamples, AViewSeesTheSamplesWhereTheyAre)
{
  // A held copy's view reads its own arrays; a view through an index reads the points it names.
  dp::FrameSamples held;
  held.points = {0, 0, 0, 1, 2, 3, 4, 5, 6};
  held.normals = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  held.voxel = 0.5;
  EXPECT_EQ(held.size(), 3u);
  EXPECT_FALSE(held.empty());
  EXPECT_TRUE(dp::FrameSamples{}.empty());
  const dp::SampleView all = held.view();
  EXPECT_EQ(all.count, 3u);
  EXPECT_EQ(all.voxel, 0.5);
  for (std::size_t i = 0; i < 3; ++i)
  {
    EXPECT_EQ(all.point(i), &held.points[3 * i]);
    EXPECT_EQ(all.normal(i), &held.normals[3 * i]);
  }
  const std::uint32_t index[2] = {2, 0};
  const dp::SampleView some{held.points.data(), held.normals.data(), index, 2, 0.5};
  EXPECT_EQ(some.point(0), &held.points[6]);
  EXPECT_EQ(some.normal(0)[2], 1.0f);
  EXPECT_EQ(some.point(1), &held.points[0]);
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

// A surface known everywhere: a height field over [0, 1] x [0, 0.6] carrying a travelling wave
// (two components in time), meshed as a grid. A vertex put at (x, y, height(x, y)) lies on it
// exactly, so both a wander along the surface and the truth it wanders from are known.
struct WaveTake
{
  static constexpr std::size_t Columns = 31, Rows = 19, Vertices = Columns * Rows, Frames = 30;
  static constexpr double Width = 1.0, Depth = 0.6;
  static constexpr double Spacing = Width / (Columns - 1);
  dp::TriangleMesh mesh{triangles(), Vertices};
  std::vector<double> truth = wandering(0.0, 0);

  static double height(double x, double y, std::size_t t)
  {
    const double s = 2 * M_PI * static_cast<double>(t) / Frames;
    return 0.1 * x * std::sin(2 * M_PI * x / 0.8 - s) +
           0.03 * std::sin(M_PI * y / Depth) * std::sin(s);
  }
  static std::vector<std::int64_t> triangles()
  {
    std::vector<std::int64_t> out;
    const auto nx = static_cast<std::int64_t>(Columns);
    for (std::int64_t r = 0; r + 1 < static_cast<std::int64_t>(Rows); ++r)
      for (std::int64_t c = 0; c + 1 < nx; ++c)
      {
        const std::int64_t a = r * nx + c, b = a + 1, d = a + nx, e = d + 1;
        out.insert(out.end(), {a, b, e, a, e, d});
      }
    return out;
  }
  // Every frame, each vertex moved from its place on the grid by a random step in x and y (a
  // normal law of `share` of the grid's spacing), then put on the surface: a tracker's sliding.
  static std::vector<double> wandering(double share, unsigned seed)
  {
    std::mt19937 random(seed);
    std::normal_distribution<double> unit(0.0, 1.0);
    std::vector<double> out;
    for (std::size_t t = 0; t < Frames; ++t)
      for (std::size_t r = 0; r < Rows; ++r)
        for (std::size_t c = 0; c < Columns; ++c)
        {
          const double x = (static_cast<double>(c) + share * unit(random)) * Spacing;
          const double y = (static_cast<double>(r) + share * unit(random)) * Spacing;
          out.insert(out.end(), {x, y, height(x, y, t)});
        }
    return out;
  }
  // The RMS vertical distance of a take's vertices from the surface (at least the distance).
  static double offSurface(const std::vector<double>& take)
  {
    double sum = 0;
    for (std::size_t i = 0; i < take.size(); i += 3)
      sum += std::pow(take[i + 2] - height(take[i], take[i + 1], i / (3 * Vertices)), 2);
    return std::sqrt(sum / static_cast<double>(take.size() / 3));
  }
};

// How far `slid` moved each vertex from `given`, in that vertex's mean edge length in the given
// take's first frame (the unit the slide's steps are limited in): RMS and largest.
struct Moved
{
  double rms = 0, max = 0;
};
Moved movedEdges(const dp::TriangleMesh& mesh, const std::vector<double>& given,
                 const std::vector<double>& slid)
{
  const std::size_t nv = mesh.numberOfVertices();
  std::vector<double> edge(nv, 0.0);
  for (std::size_t v = 0; v < nv; ++v)
  {
    for (std::int64_t w : mesh.neighbours(v))
    {
      double d2 = 0;
      for (int c = 0; c < 3; ++c)
        d2 += std::pow(given[3 * v + c] - given[3 * w + c], 2);
      edge[v] += std::sqrt(d2);
    }
    edge[v] /= static_cast<double>(mesh.neighbours(v).size());
  }
  Moved m;
  for (std::size_t i = 0; i < given.size(); i += 3)
  {
    double d2 = 0;
    for (int c = 0; c < 3; ++c)
      d2 += std::pow(slid[i + c] - given[i + c], 2);
    const double d = std::sqrt(d2) / edge[(i / 3) % nv];
    m.rms += d * d;
    m.max = std::max(m.max, d);
  }
  m.rms = std::sqrt(m.rms / static_cast<double>(given.size() / 3));
  return m;
}

// What the slide does where the truth is known: a quarter of the grid's spacing of wander (a
// normal law, in x and in y) on the wave, slid toward 0.55 of the components the codec kept on it
// (90 in the trajectory layout, 29 in the shape layout), as compressAgainstData does. Measured:
// the truth itself moves 1e-13 of an edge at most; the wandered take moves 0.135 / 0.192 edges
// RMS, 0.664 / 0.640 at most (trajectories / shapes), its RMS distance from the truth falls to
// 0.815 / 0.747 of what it was, and it leaves the surface by 0.0039 / 0.0050 of the spacing RMS.
// The bounds are those a few percent up: a slide that moved farther, or less toward the truth,
// or off the surface, fails here.
TEST(DataFit, TheSlideMovesVerticesLessThanAnEdgeAndTowardTheirTruth)
{
  const WaveTake wave;
  struct Case
  {
    dp::PcaLayout layout;
    std::size_t components;
    double rms, max, towardTruth, offSurface; // bounds: edges, edges, of before, of the spacing
  };
  const std::vector<double> given = WaveTake::wandering(0.25, 5);
  for (const Case& c : {Case{dp::PcaLayout::Trajectories, 50, 0.14, 0.69, 0.84, 0.0040},
                        Case{dp::PcaLayout::Shapes, 16, 0.20, 0.67, 0.77, 0.0052}})
  {
    const int layout = static_cast<int>(c.layout);
    // The truth is 4 components (trajectories) or 2 (shapes): nothing to slide.
    const std::vector<double> still = dp::slideAlongSurface(
        wave.mesh, wave.truth.data(), WaveTake::Frames, c.components, c.layout);
    EXPECT_LT(movedEdges(wave.mesh, wave.truth, still).max, 1e-6) << layout;

    const std::vector<double> slid =
        dp::slideAlongSurface(wave.mesh, given.data(), WaveTake::Frames, c.components, c.layout);
    const Moved moved = movedEdges(wave.mesh, given, slid);
    const double before = rmsBetween(given, wave.truth), after = rmsBetween(slid, wave.truth);
    const double off = WaveTake::offSurface(slid) / WaveTake::Spacing;
    std::printf("layout %d: moved %.4f edges RMS, %.4f at most; from the truth %.4f -> %.4f of "
                "the spacing (x%.3f); off the surface %.5f of the spacing\n",
                layout, moved.rms, moved.max, before / WaveTake::Spacing, after / WaveTake::Spacing,
                after / before, off);
    EXPECT_LT(moved.rms, c.rms) << layout;
    EXPECT_LT(moved.max, c.max) << layout;
    EXPECT_LT(after, c.towardTruth * before) << layout;
    EXPECT_LT(off, c.offSurface) << layout;
  }
  // Twice the wander: each vertex stops at the slide's reach, six steps of 0.15 of its edge.
  const std::vector<double> far = WaveTake::wandering(0.5, 5);
  const Moved capped = movedEdges(
      wave.mesh, far,
      dp::slideAlongSurface(wave.mesh, far.data(), WaveTake::Frames, 16, dp::PcaLayout::Shapes));
  EXPECT_LE(capped.max, 0.9 * (1 + 1e-9));
  EXPECT_GT(capped.max, 0.89);
}

// Samples of the wave's surface in each frame (uniform over the sheet, with its normals).
std::vector<dp::FrameSamples> waveSamples(std::size_t perFrame)
{
  std::mt19937 random(9);
  std::uniform_real_distribution<double> ux(0, WaveTake::Width), uy(0, WaveTake::Depth);
  std::vector<dp::FrameSamples> samples(WaveTake::Frames);
  for (std::size_t t = 0; t < WaveTake::Frames; ++t)
  {
    samples[t].voxel = WaveTake::Spacing / 2;
    for (std::size_t i = 0; i < perFrame; ++i)
    {
      const double x = ux(random), y = uy(random), h = 1e-6;
      const double gx = (WaveTake::height(x + h, y, t) - WaveTake::height(x - h, y, t)) / (2 * h);
      const double gy = (WaveTake::height(x, y + h, t) - WaveTake::height(x, y - h, t)) / (2 * h);
      const double n = std::sqrt(1 + gx * gx + gy * gy);
      samples[t].points.insert(samples[t].points.end(), {x, y, WaveTake::height(x, y, t)});
      samples[t].normals.insert(
          samples[t].normals.end(),
          {static_cast<float>(-gx / n), static_cast<float>(-gy / n), static_cast<float>(1 / n)});
    }
  }
  return samples;
}

std::vector<const dp::FrameSamples*> viewsOf(const std::vector<dp::FrameSamples>& samples)
{
  std::vector<const dp::FrameSamples*> views;
  for (const dp::FrameSamples& s : samples)
    views.push_back(&s);
  return views;
}

// The slide as the codec runs it (the data's target, the shape layout the main job's automatic
// choice keeps on this take) on the wandered wave: the take kept is the slid one, and as the
// reader gives it back it is closer to the truth than the take given (measured: 0.748 of its RMS
// distance), each vertex moved 0.194 edges RMS and 0.639 at most (the slide and the coding
// together); the bounds are a few percent up.
TEST(DataFit, TheCompressedTakeSlidIsCloserToTheTruthThanTheTakeGiven)
{
  const WaveTake wave;
  const std::vector<dp::FrameSamples> samples = waveSamples(1000);
  const std::vector<double> given = WaveTake::wandering(0.25, 5);
  dp::PcaOptions o;
  o.layout = dp::PcaLayout::Shapes;
  const dp::DataFitCompression c = dp::compressAgainstData(
      wave.mesh, given.data(), WaveTake::Frames, viewsOf(samples), 0.5, 0.1, o);
  const std::size_t nv = wave.mesh.numberOfVertices();
  std::vector<double> decoded(given.size());
  for (std::size_t t = 0; t < WaveTake::Frames; ++t)
    c.sequence.pca.model.frame(t, &decoded[3 * nv * t]);
  const Moved moved = movedEdges(wave.mesh, given, decoded);
  const double before = rmsBetween(given, wave.truth), after = rmsBetween(decoded, wave.truth);
  std::printf("kept %zu components, slid %d: moved %.4f edges RMS, %.4f at most; from the truth "
              "x%.3f\n",
              c.sequence.report.components, static_cast<int>(c.slid), moved.rms, moved.max,
              after / before);
  EXPECT_TRUE(c.slid);
  EXPECT_LE(c.decompressed.rms, 1.1 * c.tracked.rms);
  EXPECT_LT(after, 0.78 * before);
  EXPECT_LT(moved.rms, 0.20);
  EXPECT_LT(moved.max, 0.67);
}

// The same wave with almost no wander (a thousandth of the spacing) keeps 2 shape components; a
// slide toward 1 of them would move the motion itself, its take far from the data: it is left
// out (it once escaped as the quantiser's "cannot meet the error target" and lost the whole
// compression), and the take is coded as tracked, its fit kept.
TEST(DataFit, ALowRankTakeWithLittleWanderIsStillCompressed)
{
  const WaveTake wave;
  const std::vector<dp::FrameSamples> samples = waveSamples(3000);
  const std::vector<double> given = WaveTake::wandering(0.001, 5);
  dp::PcaOptions o;
  o.layout = dp::PcaLayout::Automatic;
  dp::DataFitCompression c;
  ASSERT_NO_THROW(c = dp::compressAgainstData(wave.mesh, given.data(), WaveTake::Frames,
                                              viewsOf(samples), 0.5, 0.1, o));
  EXPECT_LE(c.decompressed.rms, 1.1 * c.tracked.rms);
}

} // namespace
