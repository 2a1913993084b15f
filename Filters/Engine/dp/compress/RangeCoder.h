// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file RangeCoder.h
 * @brief Adaptive binary arithmetic coding of integers: what the codec stores where a value is
 *        usually small and its neighbours say how small (the detail layer's residuals).
 *
 * The coder is a binary range coder in the manner of LZMA's: a 32-bit range, probabilities of
 * 11 bits adapted after every bit by 1/32 of the difference, carries propagated through a
 * cached byte. An integer is written as bits, each with its own adaptive probability
 * (BitModel): whether it is 0; its sign; the number of bits of |v| - 1 in unary (Elias-gamma's
 * prefix), then those bits, the top ones adaptive and the rest at even odds. An IntegerModel
 * holds one such set; a caller keeps one per context (the level of the subdivision, the
 * neighbours' magnitudes) so that each kind of value learns its own statistics.
 *
 * The decoder trusts nothing: reading past the end gives zero bytes and is counted, and
 * finish() refuses a stream that ran out more than the coder's own flush allows; a value whose
 * prefix claims more than 62 bits is refused at once (std::runtime_error naming `what`). A
 * corrupt stream thus decodes to wrong but bounded values, which the caller's range checks and
 * the file's checksum catch.
 *
 * Limits: values beyond +-2^62 are refused (std::invalid_argument); about 1-2 % over the
 * adaptive entropy of what it codes, for 16 bytes of state per context.
 */
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace dp::compress
{

/** The probability of a 0 bit, in 1/2048, adapted as bits are coded. */
struct BitModel
{
  std::uint16_t zero = 1024;
};

/** The adaptive models of one kind of integer. */
struct IntegerModel
{
  static constexpr int MaximumBits = 62;
  static constexpr int AdaptiveMantissa = 2; // top bits of the magnitude with their own models
  BitModel isZero, sign;
  BitModel prefix[MaximumBits + 1];
  BitModel mantissa[MaximumBits + 1][AdaptiveMantissa];
};

/** Whether `bytes` of the coder can hold `values` values of one decision or more each: every
 *  decision costs at least 0.022 bits (the likeliest bit's odds), so at most about 360 values a
 *  byte, with slack for a small stream. A decoder asks it of a count read from a file before it
 *  allocates anything for that count. */
inline bool canHold(std::size_t bytes, double values)
{
  return values <= 400.0 * static_cast<double>(bytes) + 1e6;
}

class RangeEncoder
{
public:
  void bit(BitModel& model, int bit);
  void evenBit(int bit);
  /** v through `model` (see the file comment); throws std::invalid_argument beyond +-2^62. */
  void integer(IntegerModel& model, std::int64_t v);
  /** Flushes the coder and returns the bytes (the encoder is then spent). */
  std::vector<std::uint8_t> finish();

private:
  void shiftLow();
  std::uint64_t Low = 0;
  std::uint32_t Range = 0xFFFFFFFFu;
  std::uint8_t Cache = 0;
  std::uint64_t CacheSize = 1;
  std::vector<std::uint8_t> Out;
};

class RangeDecoder
{
public:
  /** Reads `size` bytes at `data` (which must outlive it); `what` names them in errors. */
  RangeDecoder(const std::uint8_t* data, std::size_t size, std::string what);
  int bit(BitModel& model);
  int evenBit();
  std::int64_t integer(IntegerModel& model);
  /** Throws std::runtime_error when the stream ran out before its values did. */
  void finish() const;

private:
  std::uint8_t next();
  [[noreturn]] void fail(const std::string& why) const;
  const std::uint8_t* Data;
  std::size_t Size, Position = 0, Overrun = 0;
  std::uint32_t Range = 0xFFFFFFFFu, Code = 0;
  std::string What;
};

} // namespace dp::compress
