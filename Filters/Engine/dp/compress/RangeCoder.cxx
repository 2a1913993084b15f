// SPDX-License-Identifier: BSD-3-Clause
#include "dp/compress/RangeCoder.h"

#include <stdexcept>
#include <utility>

namespace dp::compress
{
namespace
{

constexpr int ProbabilityBits = 11;
constexpr std::uint32_t ProbabilityOne = 1u << ProbabilityBits;
constexpr int Adaptation = 5;
constexpr std::uint32_t Top = 1u << 24;
// The decoder starts by reading this many bytes; the encoder's flush writes as many.
constexpr int StartBytes = 5;

void adapt(BitModel& m, int bit)
{
  if (bit)
    m.zero = static_cast<std::uint16_t>(m.zero - (m.zero >> Adaptation));
  else
    m.zero = static_cast<std::uint16_t>(m.zero + ((ProbabilityOne - m.zero) >> Adaptation));
}

// The bits of n >= 1 below its top one: n's bit count minus one.
int prefixOf(std::uint64_t n)
{
  int k = 0;
  while (n >> (k + 1))
    ++k;
  return k;
}

} // namespace

void RangeEncoder::shiftLow()
{
  if (static_cast<std::uint32_t>(Low) < 0xFF000000u || (Low >> 32) != 0)
  {
    const auto carry = static_cast<std::uint8_t>(Low >> 32);
    std::uint8_t pending = Cache;
    do
    {
      Out.push_back(static_cast<std::uint8_t>(pending + carry));
      pending = 0xFF;
    } while (--CacheSize != 0);
    Cache = static_cast<std::uint8_t>(Low >> 24);
  }
  ++CacheSize;
  Low = (Low & 0x00FFFFFFu) << 8;
}

void RangeEncoder::bit(BitModel& model, int bit)
{
  const std::uint32_t bound = (Range >> ProbabilityBits) * model.zero;
  if (bit)
  {
    Low += bound;
    Range -= bound;
  }
  else
    Range = bound;
  adapt(model, bit);
  while (Range < Top)
  {
    Range <<= 8;
    shiftLow();
  }
}

void RangeEncoder::evenBit(int bit)
{
  Range >>= 1;
  if (bit)
    Low += Range;
  while (Range < Top)
  {
    Range <<= 8;
    shiftLow();
  }
}

void RangeEncoder::integer(IntegerModel& model, std::int64_t v)
{
  constexpr std::int64_t Limit = std::int64_t{1} << IntegerModel::MaximumBits;
  if (v > Limit || v < -Limit)
    throw std::invalid_argument("range coder: " + std::to_string(v) + " is beyond +-2^62");
  bit(model.isZero, v == 0 ? 1 : 0);
  if (v == 0)
    return;
  bit(model.sign, v < 0 ? 1 : 0);
  const auto n = static_cast<std::uint64_t>(v < 0 ? -v : v);
  const int k = prefixOf(n);
  for (int j = 0; j < k; ++j)
    bit(model.prefix[j], 1);
  if (k < IntegerModel::MaximumBits)
    bit(model.prefix[k], 0);
  for (int j = k - 1; j >= 0; --j)
  {
    const int b = static_cast<int>((n >> j) & 1u);
    const int adaptive = k - 1 - j;
    if (adaptive < IntegerModel::AdaptiveMantissa)
      bit(model.mantissa[k][adaptive], b);
    else
      evenBit(b);
  }
}

std::vector<std::uint8_t> RangeEncoder::finish()
{
  for (int i = 0; i < StartBytes; ++i)
    shiftLow();
  return std::move(Out);
}

RangeDecoder::RangeDecoder(const std::uint8_t* data, std::size_t size, std::string what)
    : Data(data), Size(size), What(std::move(what))
{
  for (int i = 0; i < StartBytes; ++i)
    Code = (Code << 8) | next();
}

std::uint8_t RangeDecoder::next()
{
  if (Position < Size)
    return Data[Position++];
  ++Overrun;
  return 0;
}

void RangeDecoder::fail(const std::string& why) const
{
  throw std::runtime_error(What + ": " + why);
}

int RangeDecoder::bit(BitModel& model)
{
  const std::uint32_t bound = (Range >> ProbabilityBits) * model.zero;
  int bit;
  if (Code < bound)
  {
    Range = bound;
    bit = 0;
  }
  else
  {
    Code -= bound;
    Range -= bound;
    bit = 1;
  }
  adapt(model, bit);
  while (Range < Top)
  {
    Range <<= 8;
    Code = (Code << 8) | next();
  }
  return bit;
}

int RangeDecoder::evenBit()
{
  Range >>= 1;
  int bit = 0;
  if (Code >= Range)
  {
    Code -= Range;
    bit = 1;
  }
  while (Range < Top)
  {
    Range <<= 8;
    Code = (Code << 8) | next();
  }
  return bit;
}

std::int64_t RangeDecoder::integer(IntegerModel& model)
{
  if (bit(model.isZero))
    return 0;
  const bool negative = bit(model.sign) != 0;
  int k = 0;
  while (k < IntegerModel::MaximumBits && bit(model.prefix[k]))
    ++k;
  if (Overrun > StartBytes)
    fail("the coded values are truncated");
  std::uint64_t n = 1;
  for (int j = k - 1; j >= 0; --j)
  {
    const int adaptive = k - 1 - j;
    const int b =
        adaptive < IntegerModel::AdaptiveMantissa ? bit(model.mantissa[k][adaptive]) : evenBit();
    n = (n << 1) | static_cast<std::uint64_t>(b);
  }
  const auto magnitude = static_cast<std::int64_t>(n);
  return negative ? -magnitude : magnitude;
}

void RangeDecoder::finish() const
{
  if (Overrun > StartBytes)
    fail("the coded values are truncated");
}

} // namespace dp::compress
