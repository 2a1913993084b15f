// SPDX-License-Identifier: BSD-3-Clause
#include "dp/compress/IntegerCodec.h"

#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace dp::compress
{
namespace
{

void putVarint(std::vector<std::uint8_t>& out, std::uint64_t v)
{
  while (v >= 0x80)
  {
    out.push_back(static_cast<std::uint8_t>(v | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<std::uint8_t>(v));
}

std::uint64_t zigzag(std::int64_t v)
{
  return (static_cast<std::uint64_t>(v) << 1) ^ static_cast<std::uint64_t>(v >> 63);
}
std::int64_t unzigzag(std::uint64_t v)
{
  return static_cast<std::int64_t>(v >> 1) ^ -static_cast<std::int64_t>(v & 1);
}

// Prediction orders: 0 none, 1 the value one stride back, 2 linear from two strides back,
// 3 (per-vertex sequences only) the rounded mean of the same coordinate at the vertex's
// earlier mesh neighbours, falling back to order 1 for a vertex without any.
constexpr int MeshOrder = 3;

// Two's-complement sum and difference without overflow (a corrupt file may hold any integers; its
// values are refused later by their range checks). Equal to + and - whenever those do not
// overflow, so valid files decode bit for bit as before.
std::int64_t wrappingSum(std::int64_t a, std::int64_t b)
{
  return static_cast<std::int64_t>(static_cast<std::uint64_t>(a) + static_cast<std::uint64_t>(b));
}

std::int64_t wrappingDifference(std::int64_t a, std::int64_t b)
{
  return static_cast<std::int64_t>(static_cast<std::uint64_t>(a) - static_cast<std::uint64_t>(b));
}

std::int64_t predicted(const std::int64_t* v, std::size_t i, std::size_t stride, int order,
                       const EarlierNeighbours* mesh)
{
  if (order == MeshOrder)
  {
    const std::size_t vertex = i / stride, c = i % stride;
    const std::size_t first = mesh->start[vertex], last = mesh->start[vertex + 1];
    if (last > first)
    {
      std::int64_t sum = 0;
      for (std::size_t n = first; n < last; ++n)
        sum = wrappingSum(sum, v[mesh->index[n] * stride + c]);
      return std::llround(static_cast<double>(sum) / static_cast<double>(last - first));
    }
    order = 1;
  }
  if (order == 0 || i < stride)
    return 0;
  if (order == 1 || i < 2 * stride)
    return v[i - stride];
  return wrappingDifference(wrappingSum(v[i - stride], v[i - stride]), v[i - 2 * stride]);
}

} // namespace

EarlierNeighbours::EarlierNeighbours(const std::vector<std::int64_t>& triangles,
                                     std::size_t vertices)
{
  std::vector<std::pair<std::size_t, std::size_t>> edges; // (later, earlier)
  edges.reserve(triangles.size());
  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3)
    for (int e = 0; e < 3; ++e)
    {
      const auto a = static_cast<std::size_t>(triangles[t + e]);
      const auto b = static_cast<std::size_t>(triangles[t + (e + 1) % 3]);
      if (a != b)
        edges.emplace_back(std::max(a, b), std::min(a, b));
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  start.assign(vertices + 1, 0);
  for (const auto& e : edges)
    ++start[e.first + 1];
  for (std::size_t v = 0; v < vertices; ++v)
    start[v + 1] += start[v];
  index.reserve(edges.size());
  for (const auto& e : edges)
    index.push_back(e.second);
}

void putSequence(std::vector<std::uint8_t>& out, const std::int64_t* v, std::size_t count,
                 std::size_t stride)
{
  int best = 0;
  double bestCost = std::numeric_limits<double>::infinity();
  for (int order = 0; order <= 2; ++order)
  {
    double cost = 0;
    for (std::size_t i = 0; i < count; ++i)
      cost += std::log2(
          1.0 + static_cast<double>(zigzag(v[i] - predicted(v, i, stride, order, nullptr))));
    if (cost < bestCost)
    {
      bestCost = cost;
      best = order;
    }
  }
  out.push_back(static_cast<std::uint8_t>(best));
  for (std::size_t i = 0; i < count; ++i)
    putVarint(out, zigzag(v[i] - predicted(v, i, stride, best, nullptr)));
}

ByteReader::ByteReader(const std::uint8_t* data, std::size_t size, std::string what)
    : Data(data), Size(size), What(std::move(what))
{
}

void ByteReader::fail(const std::string& why) const
{
  throw std::runtime_error(What + ": " + why);
}

std::uint8_t ByteReader::byte()
{
  if (Position >= Size)
    fail("truncated");
  return Data[Position++];
}

std::uint64_t ByteReader::varint()
{
  std::uint64_t v = 0;
  for (int shift = 0; shift < 64; shift += 7)
  {
    const std::uint8_t b = byte();
    v |= static_cast<std::uint64_t>(b & 0x7f) << shift;
    if (!(b & 0x80))
      return v;
  }
  fail("malformed number");
}

void ByteReader::sequence(std::int64_t* v, std::size_t count, std::size_t stride,
                          const EarlierNeighbours* mesh)
{
  const int order = byte();
  if (order > (mesh ? MeshOrder : 2))
    fail("unknown prediction order " + std::to_string(order));
  for (std::size_t i = 0; i < count; ++i)
    v[i] = wrappingSum(unzigzag(varint()), predicted(v, i, stride, order, mesh));
}

int storedLevel(std::size_t bytes)
{
  return bytes < (8u << 20) ? 19 : 9;
}

std::vector<std::uint8_t> zstdCompress(const std::vector<std::uint8_t>& raw, int level)
{
  std::vector<std::uint8_t> out(ZSTD_compressBound(raw.size()));
  if (level == 0)
    level = storedLevel(raw.size());
  const std::size_t n = ZSTD_compress(out.data(), out.size(), raw.data(), raw.size(), level);
  if (ZSTD_isError(n))
    throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
  out.resize(n);
  return out;
}

double fixedWidthBits(const std::int64_t* v, std::size_t count)
{
  if (count == 0)
    return 0;
  const auto [lo, hi] = std::minmax_element(v, v + count);
  const double range = static_cast<double>(*hi - *lo) + 1;
  return std::ceil(std::log2(range)) * static_cast<double>(count) + 64; // + offset
}

} // namespace dp::compress
