// SPDX-License-Identifier: BSD-3-Clause
// PCA compression: error targets, the paper's counts, the codec, the file and its failures.
#include "dp/compress/PcaCompression.h"
#include "dp/export/GltfExport.h"
#include "dp/io/AnimatedMesh.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace
{

struct Animation
{
  std::vector<double> positions; // frame-major
  std::vector<std::int64_t> triangles;
  std::size_t vertices = 0, frames = 0;
};

Animation bendingTube(std::size_t frames = 30)
{
  dp::BendingTube::Options o;
  o.frames = frames;
  const dp::BendingTube tube(o);
  Animation a;
  a.vertices = tube.numberOfVertices();
  a.frames = frames;
  a.triangles = tube.triangles();
  for (std::size_t t = 0; t < frames; ++t)
  {
    const std::vector<double> p = tube.positions(t);
    a.positions.insert(a.positions.end(), p.begin(), p.end());
  }
  return a;
}

Eigen::Map<const Eigen::MatrixXd> matrix(const Animation& a)
{
  return {a.positions.data(), static_cast<Eigen::Index>(3 * a.vertices),
          static_cast<Eigen::Index>(a.frames)};
}

std::string temporaryPath(const std::string& name)
{
  return (std::filesystem::temp_directory_path() /
          ("dp_pca_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

} // namespace

std::string
pcaTargetName(const ::testing::TestParamInfo<std::tuple<dp::PcaLayout, bool, double>>& info)
{
  const dp::PcaLayout layout = std::get<0>(info.param);
  return std::string(layout == dp::PcaLayout::Shapes ? "Shapes" : "Trajectories") +
         (std::get<1>(info.param) ? "Codec" : "Float") + "KG" +
         std::to_string(static_cast<int>(std::lround(std::get<2>(info.param) * 100)));
}

class PcaTargets : public ::testing::TestWithParam<std::tuple<dp::PcaLayout, bool, double>>
{
};

TEST_P(PcaTargets, MeetsTheKarniGotsmanTarget)
{
  const auto [layout, quantise, target] = GetParam();
  const Animation a = bendingTube();
  dp::PcaOptions o;
  o.layout = layout;
  o.quantise = quantise;
  o.target = target;
  const dp::CompressedSequence s =
      dp::compressSequence(a.positions.data(), a.vertices, a.frames, o, a.triangles);
  const Eigen::MatrixXd approx = s.pca.model.reconstruct();
  const double kg = dp::karniGotsmanError(matrix(a), approx);
  EXPECT_LE(kg, target);
  EXPECT_NEAR(kg, s.report.kgError, 1e-9);
  // Not lossless either: the codec spends the budget it is given.
  EXPECT_GT(kg, 0.2 * target);
  EXPECT_GT(s.report.components, 0u);
  if (quantise)
  {
    EXPECT_LT(s.report.bitsPerVertexFrame, s.report.quantisedPlainBits);
  }
}

INSTANTIATE_TEST_SUITE_P(LayoutsAndTargets, PcaTargets,
                         ::testing::Combine(::testing::Values(dp::PcaLayout::Shapes,
                                                              dp::PcaLayout::Trajectories),
                                            ::testing::Bool(), ::testing::Values(0.5, 0.2, 0.1)),
                         pcaTargetName);

TEST(PcaCompression, MeetsAMaximumVertexErrorTarget)
{
  const Animation a = bendingTube();
  for (dp::PcaLayout layout : {dp::PcaLayout::Shapes, dp::PcaLayout::Trajectories})
  {
    dp::PcaOptions o;
    o.layout = layout;
    o.measure = dp::PcaErrorMeasure::MaxVertexError;
    o.target = 0.002;
    const dp::CompressedSequence s =
        dp::compressSequence(a.positions.data(), a.vertices, a.frames, o);
    const double worst = dp::maxVertexError(matrix(a), s.pca.model.reconstruct());
    EXPECT_LE(worst, o.target * s.report.diagonal);
    EXPECT_GT(worst, 0.1 * o.target * s.report.diagonal);
  }
}

TEST(PcaCompression, ThePapersCountsAndAnExactLowRankSequence)
{
  // mean + two shapes with independent weights: rank 2 exactly, so float PCA needs 2 components
  // in the shape layout and reproduces the sequence to rounding.
  const std::size_t nv = 50, nt = 20;
  std::mt19937 random(7);
  std::normal_distribution<double> normal;
  std::vector<double> mean(3 * nv), s1(3 * nv), s2(3 * nv), positions;
  for (std::size_t i = 0; i < 3 * nv; ++i)
  {
    mean[i] = normal(random);
    s1[i] = normal(random);
    s2[i] = normal(random);
  }
  for (std::size_t t = 0; t < nt; ++t)
    for (std::size_t i = 0; i < 3 * nv; ++i)
      positions.push_back(mean[i] + std::sin(0.3 * t) * s1[i] + 0.5 * std::cos(0.7 * t) * s2[i]);
  dp::PcaOptions o;
  o.quantise = false;
  o.target = 1e-4;
  const dp::CompressedSequence s = dp::compressSequence(positions.data(), nv, nt, o);
  EXPECT_EQ(s.report.components, 2u);
  EXPECT_LT(s.report.kgError, 1e-8);
  EXPECT_DOUBLE_EQ(s.report.paperD0, 3.0 * nt * nv);
  EXPECT_DOUBLE_EQ(s.report.paperD1, 3.0 * nt * 2 + nv * 2.0);
  EXPECT_DOUBLE_EQ(s.report.paperRatio, (3.0 * nt * nv) / (3.0 * nt * 2 + nv * 2.0));
  // Float PCA stores 32-bit numbers: the mean, the basis and the weights.
  EXPECT_DOUBLE_EQ(s.report.bitsPerVertexFrame,
                   32.0 * (3 * nv + 2 * 3 * nv + 2 * nt) / static_cast<double>(nv * nt));
}

TEST(PcaCompression, AGivenComponentCountIsKept)
{
  const Animation a = bendingTube();
  dp::PcaOptions o;
  o.components = 3;
  o.target = 0.01; // out of reach with 3: the quantisation then adds almost nothing
  const dp::CompressedSequence s =
      dp::compressSequence(a.positions.data(), a.vertices, a.frames, o);
  EXPECT_EQ(s.pca.model.components(), 3u);
  o.quantise = false;
  const dp::CompressedSequence plain =
      dp::compressSequence(a.positions.data(), a.vertices, a.frames, o);
  EXPECT_GT(plain.report.kgError, 0.01);
  EXPECT_LE(s.report.kgError, 1.011 * plain.report.kgError);
}

TEST(PcaCompression, TheSameBytesForAnyThreadCount)
{
  // The candidate component counts are coded side by side; the fewest bits win whatever order
  // they finish in. On one thread the progress is reported once per candidate. A shaking tube:
  // its spectrum falls slowly, so several counts are worth coding.
  Animation a = bendingTube(40);
  std::mt19937 random(7);
  std::normal_distribution<double> shake(0.0, 1e-3);
  for (double& x : a.positions)
    x += shake(random);
  dp::PcaOptions o;
  o.target = 0.5;
  std::vector<double> fractions;
  auto record = [&](double f)
  {
    fractions.push_back(f);
    return true;
  };
  dp::CompressedSequence serial;
  {
    const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    serial =
        dp::compressSequence(a.positions.data(), a.vertices, a.frames, o, a.triangles, {}, record);
  }
  const auto coded = std::count_if(fractions.begin(), fractions.end(),
                                   [](double f) { return f > 0.3 && f < 0.96; });
  ASSERT_GE(coded, 3) << "too few candidates to compare";
  const dp::CompressedSequence parallel =
      dp::compressSequence(a.positions.data(), a.vertices, a.frames, o, a.triangles);
  EXPECT_EQ(dp::encodeCompressedSequence(parallel), dp::encodeCompressedSequence(serial));
  EXPECT_EQ(parallel.report.components, serial.report.components);
  // Aborted while the candidates are coded: the caller gets the abort, not a partial result.
  EXPECT_THROW(dp::compressSequence(a.positions.data(), a.vertices, a.frames, o, a.triangles, {},
                                    [](double f) { return f <= 0.3; }),
               std::runtime_error);
}

TEST(PcaCompression, RoundTripThroughTheFileIsExact)
{
  const Animation a = bendingTube();
  for (dp::PcaLayout layout : {dp::PcaLayout::Shapes, dp::PcaLayout::Trajectories})
  {
    dp::PcaOptions o;
    o.layout = layout;
    std::vector<double> times;
    for (std::size_t t = 0; t < a.frames; ++t)
      times.push_back(0.04 * t);
    const dp::CompressedSequence s =
        dp::compressSequence(a.positions.data(), a.vertices, a.frames, o, a.triangles, times);
    const std::string path = temporaryPath("roundtrip.dpz");
    dp::writeCompressedSequence(path, s);
    const dp::CompressedSequence r = dp::readCompressedSequence(path);
    std::filesystem::remove(path);
    EXPECT_EQ(r.triangles, a.triangles);
    EXPECT_EQ(r.times, times);
    EXPECT_EQ(r.pca.model.layout, layout);
    EXPECT_EQ(r.pca.model.reconstruct(), s.pca.model.reconstruct()); // bit for bit
    std::vector<double> frame(3 * a.vertices);
    r.pca.model.frame(7, frame.data());
    EXPECT_EQ(Eigen::Map<const Eigen::VectorXd>(frame.data(), frame.size()),
              s.pca.model.reconstruct().col(7));
  }
}

// The frame times come back exactly whichever way the header writes them: evenly spaced ones
// (first + t step, as the readers number frames) as two numbers, 8 bytes a frame fewer; times
// summed up in steps of 0.1, which first + t step does not give exactly, and uneven ones as
// their list.
TEST(PcaCompression, TheFrameTimesComeBackExactlyEvenlySpacedOrNot)
{
  const Animation a = bendingTube();
  std::vector<double> even, summed, uneven;
  for (std::size_t t = 0; t < a.frames; ++t)
  {
    even.push_back(2.5 + 0.5 * static_cast<double>(t));
    summed.push_back(t == 0 ? 0.0 : summed.back() + 0.1);
    uneven.push_back(static_cast<double>(t * t) / 7.0);
  }
  std::vector<std::size_t> sizes;
  for (const std::vector<double>* times : {&even, &summed, &uneven})
  {
    const dp::CompressedSequence s = dp::compressSequence(a.positions.data(), a.vertices, a.frames,
                                                          dp::PcaOptions{}, a.triangles, *times);
    const std::vector<std::uint8_t> bytes = dp::encodeCompressedSequence(s);
    EXPECT_EQ(dp::decodeCompressedSequence(bytes.data(), bytes.size(), "t").times, *times);
    sizes.push_back(bytes.size());
  }
  EXPECT_EQ(sizes[0] + 8 * a.frames - 16, sizes[1]);
  EXPECT_EQ(sizes[1], sizes[2]);
}

// A name that cannot take the file (a folder is in the way): an error naming it, and neither a
// half file under the name nor the one written beside it left behind.
TEST(PcaCompression, AFileThatCannotBePutInPlaceIsNamedAndLeavesNothing)
{
  const Animation a = bendingTube();
  const dp::CompressedSequence s =
      dp::compressSequence(a.positions.data(), a.vertices, a.frames, dp::PcaOptions(), a.triangles);
  const std::filesystem::path folder = temporaryPath("in-the-way");
  for (const char* name : {"tracked.dpz", "tracked.glb"})
  {
    const std::filesystem::path path = folder / name;
    std::filesystem::create_directories(path / "occupied");
    try
    {
      if (path.extension() == ".glb")
        dp::writeGlb(path.string(), s);
      else
        dp::writeCompressedSequence(path.string(), s);
      ADD_FAILURE() << "no error for " << path;
    }
    catch (const std::exception& e)
    {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    }
    EXPECT_TRUE(std::filesystem::is_directory(path / "occupied"));
    EXPECT_FALSE(std::filesystem::exists(path.string() + ".partial"));
  }
  std::filesystem::remove_all(folder);
}

// Per-vertex numbers are predicted from mesh neighbours, so a vertex order with no spatial sense
// costs little when the triangles are given; the file still decodes bit for bit.
TEST(PcaCompression, MeshNeighboursPredictPerVertexNumbers)
{
  const Animation tube = bendingTube();
  std::vector<std::size_t> order(tube.vertices); // new index -> old index
  for (std::size_t v = 0; v < order.size(); ++v)
    order[v] = v;
  std::shuffle(order.begin(), order.end(), std::mt19937(7));
  std::vector<std::int64_t> newIndex(tube.vertices);
  for (std::size_t v = 0; v < order.size(); ++v)
    newIndex[order[v]] = static_cast<std::int64_t>(v);
  Animation a = tube;
  for (std::size_t t = 0; t < a.frames; ++t)
    for (std::size_t v = 0; v < a.vertices; ++v)
      for (int c = 0; c < 3; ++c)
        a.positions[3 * (t * a.vertices + v) + c] =
            tube.positions[3 * (t * a.vertices + order[v]) + c];
  for (std::int64_t& index : a.triangles)
    index = newIndex[static_cast<std::size_t>(index)];
  for (dp::PcaLayout layout : {dp::PcaLayout::Shapes, dp::PcaLayout::Trajectories})
  {
    dp::PcaOptions o;
    o.layout = layout;
    o.components = 6; // the same model both ways; only the coding differs
    const dp::CompressedSequence withMesh =
        dp::compressSequence(a.positions.data(), a.vertices, a.frames, o, a.triangles);
    const dp::CompressedSequence without =
        dp::compressSequence(a.positions.data(), a.vertices, a.frames, o, {});
    EXPECT_LT(withMesh.report.payloadBytes, 0.8 * without.report.payloadBytes)
        << (layout == dp::PcaLayout::Shapes ? "shapes" : "trajectories");
    const std::vector<std::uint8_t> bytes = dp::encodeCompressedSequence(withMesh);
    const dp::CompressedSequence r = dp::decodeCompressedSequence(bytes.data(), bytes.size(), "x");
    EXPECT_EQ(r.pca.model.reconstruct(), withMesh.pca.model.reconstruct());
  }
}

TEST(PcaCompression, CorruptOrTruncatedFilesAreRefusedByName)
{
  const Animation a = bendingTube(12);
  const dp::CompressedSequence s =
      dp::compressSequence(a.positions.data(), a.vertices, a.frames, dp::PcaOptions{}, a.triangles);
  const std::vector<std::uint8_t> bytes = dp::encodeCompressedSequence(s);
  // Every truncation.
  for (std::size_t n = 0; n < bytes.size(); ++n)
  {
    try
    {
      dp::decodeCompressedSequence(bytes.data(), n, "cut.dpz");
      ADD_FAILURE() << "a file cut at " << n << " of " << bytes.size() << " bytes was read";
    }
    catch (const std::runtime_error& e)
    {
      ASSERT_EQ(std::string(e.what()).rfind("cut.dpz", 0), 0u) << e.what();
    }
  }
  // Every single-byte change: refused, or (in bytes no checksum covers: none) the same result.
  for (std::size_t i = 0; i < bytes.size(); ++i)
  {
    std::vector<std::uint8_t> bad = bytes;
    bad[i] ^= 0x5a;
    EXPECT_THROW(dp::decodeCompressedSequence(bad.data(), bad.size(), "bad.dpz"),
                 std::runtime_error)
        << "byte " << i;
  }
  std::vector<std::uint8_t> longer = bytes;
  longer.push_back(0);
  EXPECT_THROW(dp::decodeCompressedSequence(longer.data(), longer.size(), "x"), std::runtime_error);
  try
  {
    dp::readCompressedSequence("/nonexistent/sequence.dpz");
    ADD_FAILURE();
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/sequence.dpz"), std::string::npos);
  }
}

// A header whose evenly spaced times would let it claim any number of frames in 16 bytes (a fuzz
// finding: 2^38 frames of times allocated): refused when the file cannot hold them, its CRC right.
TEST(PcaCompression, AHeaderClaimingMoreFramesThanTheFileHoldsIsRefused)
{
  const Animation a = bendingTube(6);
  const dp::CompressedSequence s =
      dp::compressSequence(a.positions.data(), a.vertices, a.frames, dp::PcaOptions{}, a.triangles);
  std::vector<std::uint8_t> bytes = dp::encodeCompressedSequence(s);
  std::uint64_t headerSize = 0;
  std::memcpy(&headerSize, bytes.data() + 12, 8);
  const std::uint64_t frames = std::uint64_t{1} << 30; // vertices x frames still below 2^40
  std::memcpy(bytes.data() + 20 + 1 + 8, &frames, 8);  // after the layout and the vertex count
  const auto crc = static_cast<std::uint32_t>(crc32(0L, bytes.data() + 20, headerSize));
  std::memcpy(bytes.data() + 20 + headerSize, &crc, 4);
  // Under the default memory budget the take is refused for its size; with a budget large enough
  // to let it through, for the bytes its frames would need.
  for (const bool budget : {true, false})
  {
    if (!budget)
      ::setenv("DP_MEMORY_BUDGET", "1000T", 1);
    try
    {
      dp::decodeCompressedSequence(bytes.data(), bytes.size(), "many.dpz");
      ADD_FAILURE();
    }
    catch (const std::runtime_error& e)
    {
      EXPECT_NE(std::string(e.what()).find(budget ? "more than the memory budget"
                                                  : "claims more frames (1073741824)"),
                std::string::npos)
          << e.what();
    }
    ::unsetenv("DP_MEMORY_BUDGET");
  }
}

TEST(PcaCompression, BadInputIsRefusedClearly)
{
  const Animation a = bendingTube(5);
  std::vector<double> p = a.positions;
  p[3 * 17 + 1] = std::nan("");
  EXPECT_THROW(dp::compressSequence(p.data(), a.vertices, a.frames, dp::PcaOptions{}),
               std::invalid_argument);
  EXPECT_THROW(dp::compressSequence(p.data(), 0, a.frames, dp::PcaOptions{}),
               std::invalid_argument);
  for (double target : {0.0, -1.0, 100.0, std::nan("")})
  {
    dp::PcaOptions o;
    o.target = target;
    EXPECT_THROW(dp::compressSequence(a.positions.data(), a.vertices, a.frames, o),
                 std::invalid_argument)
        << target;
  }
  EXPECT_THROW(dp::compressSequence(a.positions.data(), a.vertices, a.frames, dp::PcaOptions{},
                                    {0, 1, static_cast<std::int64_t>(a.vertices)}),
               std::invalid_argument);
  // Aborting through the progress callback.
  EXPECT_THROW(dp::compressSequence(a.positions.data(), a.vertices, a.frames, dp::PcaOptions{}, {},
                                    {}, [](double) { return false; }),
               std::runtime_error);
}

TEST(PcaCompression, AStillSequenceCompressesToItsMean)
{
  const Animation a = bendingTube(1);
  std::vector<double> still;
  for (int t = 0; t < 6; ++t)
    still.insert(still.end(), a.positions.begin(), a.positions.end());
  const dp::CompressedSequence s =
      dp::compressSequence(still.data(), a.vertices, 6, dp::PcaOptions{}, a.triangles);
  EXPECT_EQ(s.pca.model.components(), 0u);
  const std::vector<std::uint8_t> bytes = dp::encodeCompressedSequence(s);
  const dp::CompressedSequence r =
      dp::decodeCompressedSequence(bytes.data(), bytes.size(), "still");
  const Eigen::Map<const Eigen::MatrixXd> original(still.data(), 3 * a.vertices, 6);
  EXPECT_LT(dp::maxVertexError(original, r.pca.model.reconstruct()), 1e-3);
}
