// SPDX-License-Identifier: BSD-3-Clause
// The .dpz layout's shared parts (dp/compress/DpzFormat.h): its checksums are zlib's CRC-32 (the
// standard check value), the detail section's covers its fields and its bytes, and the fine
// vertex count a detail section must hold is Loop subdivision's, level by level.
#include "dp/compress/DpzFormat.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace
{

namespace dpz = dp::compress::dpz;

std::uint32_t crcOf(const std::string& text)
{
  return dpz::crc(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

// A tetrahedron as the base of a sequence (the detail count reads only its connectivity).
dp::CompressedSequence tetrahedron()
{
  dp::CompressedSequence s;
  s.triangles = {0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3};
  s.pca.model.vertices = 4;
  return s;
}

} // namespace

TEST(DpzFormat, TheChecksumIsTheStandardCrc32)
{
  EXPECT_EQ(crcOf("123456789"), 0xCBF43926u); // CRC-32's published check value
  EXPECT_EQ(crcOf(""), 0u);
  EXPECT_NE(crcOf("123456789"), crcOf("123456788"));
}

TEST(DpzFormat, TheDetailChecksumCoversItsFieldsThenItsBytes)
{
  std::vector<std::uint8_t> fields(dpz::DetailFieldsBytes), payload = {9, 8, 7, 6, 5};
  for (std::size_t i = 0; i < fields.size(); ++i)
    fields[i] = static_cast<std::uint8_t>(3 * i + 1);
  std::vector<std::uint8_t> whole = fields;
  whole.insert(whole.end(), payload.begin(), payload.end());
  const std::uint32_t sum = dpz::detailChecksum(fields.data(), payload.data(), payload.size());
  EXPECT_EQ(sum, dpz::crc(whole.data(), whole.size()));
  payload[4] ^= 1;
  EXPECT_NE(sum, dpz::detailChecksum(fields.data(), payload.data(), payload.size()));
}

TEST(DpzFormat, TheFineVertexCountIsLoopSubdivisionsLevelByLevel)
{
  // A closed mesh's level L + 1 has V + E vertices, 2E + 3F edges and 4F faces of level L's.
  const dp::CompressedSequence s = tetrahedron();
  std::size_t v = 4, e = 6, f = 4;
  for (int level = 0; level <= 3; ++level)
  {
    EXPECT_EQ(dpz::fineVerticesOf(s, level), v) << "level " << level;
    const std::size_t nextV = v + e, nextE = 2 * e + 3 * f, nextF = 4 * f;
    v = nextV, e = nextE, f = nextF;
  }
  dp::CompressedSequence corrupt = tetrahedron();
  corrupt.triangles[5] = 4; // a vertex the base does not have
  EXPECT_THROW(dpz::fineVerticesOf(corrupt, 1), std::invalid_argument);
}
