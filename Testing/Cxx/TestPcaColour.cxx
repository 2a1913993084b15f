// SPDX-License-Identifier: BSD-3-Clause
// The .dpz colour stream: exact round trips through memory and a file, version-1 files (no
// colour) still read, a corrupt or truncated colour stream and colours of the wrong count
// refused (by the .glb writer too).
#include "dp/compress/ColourStream.h"
#include "dp/compress/PcaCompression.h"
#include "dp/export/GltfExport.h"
#include "dp/io/AnimatedMesh.h"

#include "TestUtilities.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <unistd.h>

namespace
{

// The bending tube's first `frames` frames, compressed with the default options.
dp::CompressedSequence tube(std::size_t frames)
{
  return dp::test::compressedTube(frames);
}

// Colour as a tracker gives it: each vertex its own colour, a few steps of noise from frame to
// frame, and values at 0 and 255 that step across the byte's ends (differences wrap mod 256).
std::vector<std::uint8_t> colours(std::size_t vertices, std::size_t frames)
{
  std::mt19937 random(7);
  std::uniform_int_distribution<int> base(0, 255), noise(-2, 2);
  std::vector<std::uint8_t> first(3 * vertices);
  for (std::size_t i = 0; i < first.size(); ++i)
    first[i] = static_cast<std::uint8_t>(i % 7 == 0 ? 0 : i % 7 == 1 ? 255 : base(random));
  std::vector<std::uint8_t> out;
  for (std::size_t t = 0; t < frames; ++t)
    for (std::uint8_t c : first)
      out.push_back(static_cast<std::uint8_t>(std::clamp(c + noise(random), 0, 255)));
  return out;
}

std::uint32_t versionOf(const std::vector<std::uint8_t>& bytes)
{
  std::uint32_t v = 0;
  std::memcpy(&v, bytes.data() + 8, 4);
  return v;
}

std::string temporaryPath(const std::string& name)
{
  return (std::filesystem::temp_directory_path() /
          ("dp_colour_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

// `a` with its colour section replaced by `b`'s (their geometry sections differ in nothing the
// colour reader looks at).
std::vector<std::uint8_t> withColourSectionOf(const dp::CompressedSequence& a,
                                              const dp::CompressedSequence& b)
{
  const std::vector<std::uint8_t> x = dp::encodeCompressedSequence(a);
  const std::vector<std::uint8_t> y = dp::encodeCompressedSequence(b);
  std::vector<std::uint8_t> out(x.begin(), x.end() - static_cast<long>(a.report.colourBytes));
  out.insert(out.end(), y.end() - static_cast<long>(b.report.colourBytes), y.end());
  return out;
}

} // namespace

TEST(PcaColour, RoundTripIsExactThroughMemoryAndAFile)
{
  dp::CompressedSequence s = tube(12);
  const dp::PcaModel& m = s.pca.model;
  const std::vector<std::uint8_t> plain = dp::encodeCompressedSequence(s);
  dp::setColours(s, colours(m.vertices, m.frames));
  ASSERT_EQ(s.colours.size(), 3 * m.vertices * m.frames);
  const std::vector<std::uint8_t> bytes = dp::encodeCompressedSequence(s);
  EXPECT_EQ(versionOf(plain), 5u);
  EXPECT_EQ(versionOf(bytes), 5u);
  // The report says what the colour takes in the file: the file grows by exactly that.
  EXPECT_GT(s.report.colourBytes, 0u);
  EXPECT_EQ(bytes.size(), plain.size() + s.report.colourBytes);
  // Noise of a few steps costs far less than the colours as they are.
  EXPECT_LT(s.report.colourBytes, s.colours.size() / 2);

  const dp::CompressedSequence r = dp::decodeCompressedSequence(bytes.data(), bytes.size(), "c");
  EXPECT_EQ(r.colours, s.colours);
  EXPECT_EQ(r.report.colourBytes, s.report.colourBytes);
  EXPECT_EQ(r.pca.model.reconstruct(), s.pca.model.reconstruct()); // the geometry untouched
  const std::string path = temporaryPath("roundtrip.dpz");
  dp::writeCompressedSequence(path, s);
  const dp::CompressedSequence f = dp::readCompressedSequence(path);
  std::filesystem::remove(path);
  EXPECT_EQ(f.colours, s.colours);
  EXPECT_EQ(f.triangles, s.triangles);
  EXPECT_EQ(f.pca.model.reconstruct(), s.pca.model.reconstruct());
}

// With a tolerance the stored colours keep their value while the given ones stay within it:
// every byte within the tolerance, the flicker gone (the noise of +-2 is held), a jump of 60
// levels passed exactly in its frame, a third of the bytes or fewer, and the file gives back
// what was stored. setColours' default (tolerance 0) is lossless; a tolerance outside
// [0, MaximumColourTolerance] is refused.
TEST(PcaColour, AToleranceHoldsEachColourWithinItAndShrinksTheStream)
{
  dp::CompressedSequence exact = tube(12);
  const dp::PcaModel& m = exact.pca.model;
  std::vector<std::uint8_t> given = colours(m.vertices, m.frames);
  const std::size_t frameBytes = 3 * m.vertices, jumpFrame = 7;
  for (std::size_t t = jumpFrame; t < m.frames; ++t) // vertex 1's red turns 60 levels darker
    given[t * frameBytes + 3 * 1] = static_cast<std::uint8_t>(given[3 * 1] > 128 ? 40 : 200);
  dp::CompressedSequence held = exact;
  dp::setColours(exact, given);
  dp::setColours(held, given, 4);
  EXPECT_EQ(exact.colours, given);
  EXPECT_EQ(exact.report.colourTolerance, 0);
  EXPECT_EQ(held.report.colourTolerance, 4);
  std::size_t repeats = 0;
  for (std::size_t i = 0; i < given.size(); ++i)
  {
    ASSERT_LE(std::abs(int(held.colours[i]) - int(given[i])), 4) << "byte " << i;
    repeats += i >= frameBytes && held.colours[i] == held.colours[i - frameBytes];
  }
  EXPECT_EQ(repeats, given.size() - frameBytes - 1); // the jump is the one change
  EXPECT_EQ(held.colours[jumpFrame * frameBytes + 3], given[jumpFrame * frameBytes + 3]);
  EXPECT_LT(3 * held.report.colourBytes, exact.report.colourBytes);
  const std::vector<std::uint8_t> bytes = dp::encodeCompressedSequence(held);
  EXPECT_EQ(dp::decodeCompressedSequence(bytes.data(), bytes.size(), "held").colours, held.colours);
  for (int tolerance : {-1, dp::MaximumColourTolerance + 1})
    EXPECT_THROW(dp::setColours(held, given, tolerance), std::invalid_argument);
}

// Files of the earlier versions (the .dpz fuzzer's seeds: version 1 without colour, 2 with
// colour, 3 with a detail layer and colour, 4 the same with the geometry range-coded) still
// read, and written again (as version 5, the connectivity range-coded too) they give back the
// same sequence.
TEST(PcaColour, EarlierVersionsStillRead)
{
  for (const char* name :
       {"tracked.dpz", "tracked_colour.dpz", "detailed_colour.dpz", "coded_detailed_colour.dpz"})
  {
    const std::string path = std::string(DP_DPZ_SEEDS) + "/" + name;
    std::ifstream in(path, std::ios::binary);
    const std::vector<std::uint8_t> file((std::istreambuf_iterator<char>(in)),
                                         std::istreambuf_iterator<char>());
    const dp::CompressedSequence old = dp::readCompressedSequence(path);
    EXPECT_LT(versionOf(file), 5u) << name;
    EXPECT_EQ(old.colours.empty(), std::string(name) == "tracked.dpz") << name;
    const std::vector<std::uint8_t> bytes = dp::encodeCompressedSequence(old);
    EXPECT_EQ(versionOf(bytes), 5u);
    const dp::CompressedSequence r = dp::decodeCompressedSequence(bytes.data(), bytes.size(), name);
    EXPECT_EQ(r.pca.meanIntegers, old.pca.meanIntegers) << name;
    EXPECT_EQ(r.pca.basisIntegers, old.pca.basisIntegers) << name;
    EXPECT_EQ(r.pca.weightIntegers, old.pca.weightIntegers) << name;
    EXPECT_EQ(r.pca.model.reconstruct(), old.pca.model.reconstruct()) << name;
    EXPECT_EQ(r.colours, old.colours) << name;
    EXPECT_EQ(r.detail.displacements, old.detail.displacements) << name;
    EXPECT_EQ(r.triangles, old.triangles) << name;
  }
  const dp::CompressedSequence old =
      dp::readCompressedSequence(std::string(DP_DPZ_SEEDS) + "/tracked.dpz");
  EXPECT_EQ(old.pca.model.vertices, 300u);
  EXPECT_EQ(old.pca.model.frames, 5u);
  EXPECT_EQ(old.report.colourBytes, 0u);
}

TEST(PcaColour, ACorruptOrTruncatedColourStreamIsRefusedByName)
{
  dp::CompressedSequence s = tube(5);
  dp::setColours(s, colours(s.pca.model.vertices, 5));
  const std::vector<std::uint8_t> bytes = dp::encodeCompressedSequence(s);
  // Every byte of the section's sizes and checksum, and a couple of hundred of its packed bytes.
  const std::size_t start = bytes.size() - s.report.colourBytes;
  const std::size_t stride = std::max<std::size_t>(1, s.report.colourBytes / 200);
  const auto next = [&](std::size_t i) { return i < start + 20 ? i + 1 : i + stride; };
  for (std::size_t n = start; n < bytes.size(); n = next(n))
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
  for (std::size_t i = start; i < bytes.size(); i = next(i))
  {
    std::vector<std::uint8_t> bad = bytes;
    bad[i] ^= 0x5a;
    EXPECT_THROW(dp::decodeCompressedSequence(bad.data(), bad.size(), "bad.dpz"),
                 std::runtime_error)
        << "byte " << i;
  }
  // Read as an earlier version (the connectivity as a zstd section): refused, not misread.
  std::vector<std::uint8_t> relabelled = bytes;
  for (std::uint8_t earlier : {1, 2, 3, 4})
  {
    relabelled[8] = earlier;
    EXPECT_THROW(dp::decodeCompressedSequence(relabelled.data(), relabelled.size(), "x"),
                 std::runtime_error);
  }
  // A version this reader does not know.
  relabelled[8] = 6;
  try
  {
    dp::decodeCompressedSequence(relabelled.data(), relabelled.size(), "new.dpz");
    ADD_FAILURE();
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("new.dpz: format version 6"), std::string::npos)
        << e.what();
  }
}

TEST(PcaColour, AColourStreamOfTheWrongCountIsRefused)
{
  dp::CompressedSequence s = tube(6);
  const std::size_t nv = s.pca.model.vertices;
  // Colours for one frame too few or too many, or with a byte too few: refused with the counts.
  for (std::size_t count : {3 * nv * 5, 3 * nv * 7, 3 * nv * 6 - 1, 4 * nv * 6})
  {
    try
    {
      dp::setColours(s, std::vector<std::uint8_t>(count, 9));
      ADD_FAILURE() << count;
    }
    catch (const std::invalid_argument& e)
    {
      EXPECT_NE(std::string(e.what()).find(std::to_string(3 * nv * 6)), std::string::npos)
          << e.what();
    }
    EXPECT_TRUE(s.colours.empty());
  }
  s.colours.assign(3 * nv * 6 + 3, 1);
  EXPECT_THROW(dp::encodeCompressedSequence(s), std::invalid_argument);
  EXPECT_THROW(dp::writeGlb(temporaryPath("count.glb"), s), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(temporaryPath("count.glb")));
  s.colours.clear();
  // A file whose colour stream holds five or seven frames for six: refused, by name.
  dp::setColours(s, colours(nv, 6));
  for (std::size_t frames : {5, 7})
  {
    dp::CompressedSequence other = tube(frames);
    dp::setColours(other, colours(nv, frames));
    const std::vector<std::uint8_t> bad = withColourSectionOf(s, other);
    try
    {
      dp::decodeCompressedSequence(bad.data(), bad.size(), "count.dpz");
      ADD_FAILURE() << frames;
    }
    catch (const std::runtime_error& e)
    {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("count.dpz: colour stream", 0), 0u) << what;
    }
  }
}
