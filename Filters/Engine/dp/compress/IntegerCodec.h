// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file IntegerCodec.h
 * @brief Predicted varints: the .dpz file's connectivity in format versions 1 to 4, and from
 *        version 5 on where zstd packs them smaller than the range coder's corners
 *        (ConnectivityCoding.h); the reading of its geometry in versions 1 to 3 (range-coded
 *        since version 4, ModelCoding.h). Each sequence is predicted (order 0 none, 1 the value
 *        one stride back, 2 linear from two strides back, 3 for per-vertex sequences the rounded
 *        mean of the same coordinate at the vertex's earlier mesh neighbours), the order with the
 *        smallest estimated cost is kept, and the residuals are written as zigzag varints; whole
 *        sections are then packed by zstd.
 *
 * Internal to the compression; not installed API. Limits: a reader trusts nothing: ByteReader
 * throws std::runtime_error naming the file on truncation or malformed numbers, and sums wrap
 * instead of overflowing, so corrupt input is refused by the caller's range checks.
 */
#pragma once

#include "dp/compress/PcaCompression.h"

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace dp::compress
{

/** For each vertex, its mesh neighbours with a smaller index: the values a decoder going through
 *  the vertices in order already has, so a per-vertex sequence can be predicted from them. */
struct EarlierNeighbours
{
  EarlierNeighbours(const std::vector<std::int64_t>& triangles, std::size_t vertices);
  std::vector<std::size_t> start; // neighbours of v: index[start[v] .. start[v + 1])
  std::vector<std::size_t> index;
};

/** Writes v[0..count) predicted along `stride` (the connectivity; the geometry of versions 1 to 3
 *  was written so too, with per-vertex sequences predicted from earlier mesh neighbours). */
void putSequence(std::vector<std::uint8_t>& out, const std::int64_t* v, std::size_t count,
                 std::size_t stride);

template <typename T>
void putRaw(std::vector<std::uint8_t>& out, T v)
{
  const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
  out.insert(out.end(), p, p + sizeof(T));
}

/** Reads what putSequence and putRaw wrote, refusing malformed bytes with `what` in the error. */
class ByteReader
{
public:
  ByteReader(const std::uint8_t* data, std::size_t size, std::string what);
  [[noreturn]] void fail(const std::string& why) const;
  std::uint8_t byte();
  std::uint64_t varint();
  template <typename T>
  T raw()
  {
    if (Size - Position < sizeof(T))
      fail("truncated");
    T v;
    std::memcpy(&v, Data + Position, sizeof(T));
    Position += sizeof(T);
    return v;
  }
  void sequence(std::int64_t* v, std::size_t count, std::size_t stride,
                const EarlierNeighbours* mesh = nullptr);
  std::size_t position() const { return Position; }
  std::size_t remaining() const { return Size - Position; }

private:
  const std::uint8_t* Data;
  std::size_t Size, Position = 0;
  std::string What;
};

// Strides of the prediction, the same in both layouts: x y z interleaved in the mean and the
// basis (3: the same coordinate one frame or one vertex back), one value per row in the weights.
constexpr std::size_t MeanStride = 3, BasisStride = 3, WeightStride = 1;

/** zstd level of what is stored (19; 9 for big inputs, where 19 gets slow). */
int storedLevel(std::size_t bytes);

/** zstd at `level` (0: storedLevel). Throws std::runtime_error on a zstd error. */
std::vector<std::uint8_t> zstdCompress(const std::vector<std::uint8_t>& raw, int level = 0);

/** Fixed-width bits of a sequence of integers: what quantised plain PCA would store. */
double fixedWidthBits(const std::int64_t* v, std::size_t count);

} // namespace dp::compress
