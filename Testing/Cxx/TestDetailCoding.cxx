// SPDX-License-Identifier: BSD-3-Clause
// The detail layer's coding: the range coder round-trips any integers exactly, the displacements
// come back within half a step, the .dpz carries the layer (format version 3) while files
// without one keep their versions, a corrupt or cut detail section is refused by name, and the
// layer coded against the data keeps the fine mesh's fit within the growth asked.
#include "FineMeshShapes.h"

#include "dp/compress/ColourStream.h"
#include "dp/compress/DetailCoding.h"
#include "dp/compress/PcaCompression.h"
#include "dp/compress/RangeCoder.h"
#include "dp/detail/DetailCompression.h"
#include "dp/detail/DisplacementFit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

namespace
{

using dp::test::Mesh;

std::vector<std::int64_t> roundTrip(const std::vector<std::int64_t>& values)
{
  dp::compress::IntegerModel model;
  dp::compress::RangeEncoder encoder;
  for (std::int64_t v : values)
    encoder.integer(model, v);
  const std::vector<std::uint8_t> bytes = encoder.finish();
  dp::compress::IntegerModel back;
  dp::compress::RangeDecoder decoder(bytes.data(), bytes.size(), "test");
  std::vector<std::int64_t> out;
  for (std::size_t i = 0; i < values.size(); ++i)
    out.push_back(decoder.integer(back));
  decoder.finish();
  return out;
}

TEST(RangeCoder, RoundTripsRandomAndAdversarialIntegersExactly)
{
  constexpr std::int64_t Largest = std::int64_t{1} << 62;
  std::mt19937_64 random(5);
  std::geometric_distribution<int> small(0.4);
  std::uniform_int_distribution<std::int64_t> any(-Largest, Largest);
  std::vector<std::vector<std::int64_t>> cases(6);
  for (int i = 0; i < 5000; ++i)
  {
    cases[0].push_back(0);                                                 // constant
    cases[1].push_back(i % 2 ? Largest : -Largest);                        // alternating extremes
    cases[2].push_back((i % 2 ? 1 : -1) * small(random));                  // typical residuals
    cases[3].push_back(any(random));                                       // anything
    cases[4].push_back(i % 97 == 0 ? any(random) : 0);                     // rare outliers
    cases[5].push_back(static_cast<std::int64_t>(i) * (i % 3 - 1) * 1000); // growing
  }
  for (const auto& values : cases)
    EXPECT_EQ(roundTrip(values), values);
  EXPECT_EQ(roundTrip({}), std::vector<std::int64_t>{});
  dp::compress::IntegerModel model;
  dp::compress::RangeEncoder encoder;
  EXPECT_THROW(encoder.integer(model, Largest + 1), std::invalid_argument);
  EXPECT_THROW(encoder.integer(model, std::numeric_limits<std::int64_t>::min()),
               std::invalid_argument);
}

TEST(RangeCoder, LearnsWhatIsLikely)
{
  // Mostly zeros cost a small fraction of a byte each; a truncated stream is refused.
  std::vector<std::int64_t> values(20000, 0);
  for (std::size_t i = 0; i < values.size(); i += 50)
    values[i] = 3;
  dp::compress::IntegerModel model;
  dp::compress::RangeEncoder encoder;
  for (std::int64_t v : values)
    encoder.integer(model, v);
  const std::vector<std::uint8_t> bytes = encoder.finish();
  EXPECT_LT(bytes.size(), values.size() / 20);
  dp::compress::IntegerModel back;
  dp::compress::RangeDecoder cut(bytes.data(), bytes.size() / 2, "cut");
  EXPECT_THROW(
      {
        for (std::size_t i = 0; i < values.size(); ++i)
          cut.integer(back);
        cut.finish();
      },
      std::runtime_error);
}

// A base (162 vertices) and smooth displacements of its 2-level fine mesh moving over `frames`
// frames, with a little noise.
struct Take
{
  Mesh base = dp::test::icosphere(2);
  dp::SubdivisionMap map{base.triangles, base.vertices(), 2};
  std::size_t frames;
  std::vector<double> displacements;

  explicit Take(std::size_t f) : frames(f)
  {
    std::vector<double> fine(3 * map.fineVertices());
    map.apply(base.positions.data(), fine.data());
    std::mt19937 random(9);
    std::normal_distribution<double> noise(0.0, 0.001);
    for (std::size_t t = 0; t < frames; ++t)
      for (std::size_t i = 0; i < map.fineVertices(); ++i)
      {
        const double* x = &fine[3 * i];
        displacements.push_back(0.03 * std::sin(4 * x[0] + 0.2 * static_cast<double>(t)) *
                                    std::cos(3 * x[1]) +
                                noise(random));
      }
  }
};

TEST(DetailCoding, DisplacementsComeBackWithinHalfAStep)
{
  const Take take(6);
  double previousBytes = std::numeric_limits<double>::infinity();
  for (const double step : {0.0005, 0.002, 0.008})
  {
    std::vector<double> decoded;
    const std::vector<std::uint8_t> bytes =
        dp::encodeDetail(take.map, take.displacements.data(), take.frames, step, &decoded);
    EXPECT_EQ(decoded, dp::quantiseDetail(take.map, take.displacements.data(), take.frames, step));
    EXPECT_EQ(dp::decodeDetail(take.map, take.frames, step, bytes.data(), bytes.size(), "t"),
              decoded);
    double worst = 0, sum = 0;
    for (std::size_t i = 0; i < decoded.size(); ++i)
    {
      const double e = decoded[i] - take.displacements[i];
      worst = std::max(worst, std::abs(e));
      sum += e * e;
    }
    EXPECT_LE(worst, 0.5 * step * (1 + 1e-9));
    EXPECT_NEAR(std::sqrt(sum / static_cast<double>(decoded.size())), step / std::sqrt(12.0),
                0.25 * step / std::sqrt(12.0));
    EXPECT_LT(static_cast<double>(bytes.size()), previousBytes); // a coarser step costs less
    previousBytes = static_cast<double>(bytes.size());
  }
  EXPECT_THROW(dp::encodeDetail(take.map, take.displacements.data(), take.frames, 0.0),
               std::invalid_argument);
  std::vector<double> bad = take.displacements;
  bad[17] = std::nan("");
  EXPECT_THROW(dp::encodeDetail(take.map, bad.data(), take.frames, 0.001), std::invalid_argument);
}

// A compressed sequence of the take's base (still) with its detail layer.
dp::CompressedSequence detailed(const Take& take, double step)
{
  std::vector<double> positions;
  for (std::size_t t = 0; t < take.frames; ++t)
    positions.insert(positions.end(), take.base.positions.begin(), take.base.positions.end());
  dp::PcaOptions o;
  o.components = 1;
  dp::CompressedSequence s = dp::compressSequence(positions.data(), take.base.vertices(),
                                                  take.frames, o, take.base.triangles);
  dp::setDetail(s, 2, take.displacements, step);
  return s;
}

std::uint32_t versionOf(const std::vector<std::uint8_t>& bytes)
{
  std::uint32_t v = 0;
  std::memcpy(&v, bytes.data() + 8, 4);
  return v;
}

TEST(DetailCoding, TheFileCarriesTheLayer)
{
  const Take take(5);
  dp::CompressedSequence s = detailed(take, 0.001);
  const std::vector<std::uint8_t> bytes = dp::encodeCompressedSequence(s);
  EXPECT_EQ(versionOf(bytes), 5u);
  const dp::CompressedSequence back = dp::decodeCompressedSequence(bytes.data(), bytes.size(), "d");
  EXPECT_EQ(back.detail.levels, 2);
  EXPECT_EQ(back.detail.step, s.detail.step);
  EXPECT_EQ(back.detail.displacements, s.detail.displacements);
  EXPECT_EQ(back.report.detailBytes, s.report.detailBytes);
  // The same fine mesh, frame by frame.
  std::vector<double> a(3 * take.map.fineVertices()), b(a.size());
  for (std::size_t t = 0; t < take.frames; ++t)
  {
    dp::detailedFrame(s, take.map, t, a.data());
    dp::detailedFrame(back, take.map, t, b.data());
    EXPECT_EQ(a, b);
  }
  // With colour too: both sections back.
  std::vector<std::uint8_t> colours(3 * take.base.vertices() * take.frames);
  for (std::size_t i = 0; i < colours.size(); ++i)
    colours[i] = static_cast<std::uint8_t>(i * 7);
  dp::setColours(s, colours);
  const std::vector<std::uint8_t> both = dp::encodeCompressedSequence(s);
  const dp::CompressedSequence again = dp::decodeCompressedSequence(both.data(), both.size(), "c");
  EXPECT_EQ(again.colours, colours);
  EXPECT_EQ(again.detail.displacements, s.detail.displacements);
  // Without the layer the file ends after the colour.
  s.detail = dp::DetailLayer{};
  const std::vector<std::uint8_t> plain = dp::encodeCompressedSequence(s);
  EXPECT_EQ(plain.size(), both.size() - s.report.detailBytes);
  EXPECT_TRUE(
      dp::decodeCompressedSequence(plain.data(), plain.size(), "p").detail.displacements.empty());
}

TEST(DetailCoding, ACutOrCorruptDetailSectionIsRefusedByName)
{
  const Take take(4);
  const dp::CompressedSequence s = detailed(take, 0.001);
  const std::vector<std::uint8_t> bytes = dp::encodeCompressedSequence(s);
  const std::size_t start = bytes.size() - s.report.detailBytes;
  const std::size_t stride = std::max<std::size_t>(1, s.report.detailBytes / 150);
  for (std::size_t n = start; n < bytes.size(); n += n < start + 30 ? 1 : stride)
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
  for (std::size_t i = start; i < bytes.size(); i += i < start + 30 ? 1 : stride)
  {
    std::vector<std::uint8_t> bad = bytes;
    bad[i] ^= 0x5a;
    EXPECT_THROW(dp::decodeCompressedSequence(bad.data(), bad.size(), "bad.dpz"),
                 std::runtime_error)
        << "byte " << i;
  }
}

TEST(DetailCoding, SetDetailRefusesLevelsAndCountsThatDoNotFit)
{
  const Take take(3);
  dp::CompressedSequence s = detailed(take, 0.001);
  EXPECT_THROW(dp::setDetail(s, 0, take.displacements, 0.001), std::invalid_argument);
  EXPECT_THROW(dp::setDetail(s, 3, take.displacements, 0.001), std::invalid_argument);
  EXPECT_THROW(dp::setDetail(s, 2, {1.0, 2.0}, 0.001), std::invalid_argument);
  s.detail.payload.clear();
  EXPECT_THROW(dp::encodeCompressedSequence(s), std::invalid_argument);
}

} // namespace

namespace
{

// A bumpy sphere moving over `frames` frames, tracked by a coarse sphere (its base compressed),
// the detail fitted to each frame: what dp::compressDetailAgainstData codes.
struct MovingTake
{
  Mesh base = dp::test::icosphere(2);
  dp::SubdivisionMap map{base.triangles, base.vertices(), 2};
  std::size_t frames = 8;
  std::vector<double> basePositions, displacements;
  std::vector<dp::FrameSamples> samples;
  dp::CompressedSequence sequence;

  MovingTake()
  {
    const Mesh data =
        dp::test::icosphere(5, [](const double* u) { return dp::test::bumpyRadius(u, 0.03); });
    const dp::DisplacementFitter fitter(map);
    dp::DisplacementFitOptions options;
    options.reach = 0.2;
    const std::size_t n = map.fineVertices();
    std::vector<double> fine(3 * n), normals(3 * n);
    for (std::size_t t = 0; t < frames; ++t)
    {
      const double shift = 0.05 * static_cast<double>(t);
      std::vector<double> b = base.positions, d = data.positions;
      for (std::size_t i = 0; i < b.size(); i += 3)
        b[i] += shift;
      for (std::size_t i = 0; i < d.size(); i += 3)
        d[i] += shift;
      basePositions.insert(basePositions.end(), b.begin(), b.end());
      Mesh moved = data;
      moved.positions = d;
      map.subdivide(b.data(), fine.data(), normals.data());
      const dp::DisplacementFit fit = fitter.fit(
          fine.data(), normals.data(), dp::FrameSurface::ofMesh(moved.surface()), options);
      displacements.insert(displacements.end(), fit.displacement.begin(), fit.displacement.end());
      dp::FrameSamples s;
      s.points = dp::sampleMeshSurface(moved.surface(), 3000).points;
      samples.push_back(std::move(s));
    }
    dp::PcaOptions o;
    o.target = 0.5;
    sequence =
        dp::compressSequence(basePositions.data(), base.vertices(), frames, o, base.triangles);
  }
  std::vector<const dp::FrameSamples*> views() const
  {
    std::vector<const dp::FrameSamples*> v;
    for (const dp::FrameSamples& s : samples)
      v.push_back(&s);
    return v;
  }
};

TEST(DetailCompression, KeepsTheFineMeshsFitWithinTheAllowedGrowth)
{
  const MovingTake take;
  const dp::FittedDetail fitted{take.map, take.basePositions.data(), take.displacements.data(),
                                take.frames};
  std::size_t previousBytes = std::numeric_limits<std::size_t>::max();
  for (const double growth : {0.05, 0.2, 1.0})
  {
    dp::CompressedSequence s = take.sequence;
    const dp::DetailCompression c =
        dp::compressDetailAgainstData(s, fitted, take.views(), 0.2, growth);
    EXPECT_GT(c.fitted.samples, 0u);
    EXPECT_LE(c.decompressed.rms, (1 + growth) * c.fitted.rms * (1 + 1e-12)) << growth;
    EXPECT_GT(c.growth, 0.3 * growth) << growth; // the budget was used
    EXPECT_EQ(s.detail.levels, 2);
    EXPECT_LT(s.report.detailBytes, previousBytes); // more growth, fewer bytes
    previousBytes = s.report.detailBytes;
    // The fine mesh the file gives lies on the data within the growth: the displacements were
    // carried over to the decoded base, whose own error is undone along the normals.
    const std::vector<std::uint8_t> bytes = dp::encodeCompressedSequence(s);
    const dp::CompressedSequence back =
        dp::decodeCompressedSequence(bytes.data(), bytes.size(), "d");
    EXPECT_EQ(back.detail.displacements, s.detail.displacements);
  }
  dp::CompressedSequence s = take.sequence;
  EXPECT_THROW(dp::compressDetailAgainstData(s, fitted, take.views(), 0.2, 0.0),
               std::invalid_argument);
  EXPECT_THROW(dp::compressDetailAgainstData(s, fitted, {}, 0.2, 0.1), std::invalid_argument);
}

} // namespace
