// SPDX-License-Identifier: BSD-3-Clause
#include "dp/compress/ConnectivityCoding.h"

#include "dp/compress/IntegerCodec.h"
#include "dp/compress/RangeCoder.h"

#include <zstd.h>

#include <algorithm>
#include <stdexcept>
#include <unordered_map>

namespace dp::compress
{
namespace
{

// The candidate list's length at most, and how many of the latest triangles' vertices it keeps
// (on tracked templates more of either gained nothing; 16 recent cost 1 % more).
constexpr std::size_t ListSize = 32;
constexpr std::size_t RecentSize = 32;
// A vertex's neighbours kept at most: a list of ListSize seldom reaches further (only past
// neighbours already listed), and the cap keeps a vertex shared by every triangle (a fan; a
// hostile file) linear, not quadratic.
constexpr std::size_t RingSize = 2 * ListSize;
// The first byte of the bytes: which coding follows.
constexpr std::uint8_t PackedVarints = 0, CodedCorners = 1;

// What encoder and decoder both know after the same triangles: the edges so far, the latest
// vertices, the largest index; and each corner kind's models.
class CornerCoding
{
public:
  struct Models
  {
    BitModel isNext, inList;
    IntegerModel position, escape;
  };
  Models models[3];
  std::int64_t largest = -1;

  // The candidates for corner `k` of a triangle whose earlier corners are tri[0..k).
  const std::vector<std::int64_t>& candidates(const std::int64_t* tri, int k)
  {
    List.clear();
    if (k == 2)
      add(neighbours(tri[1]), tri, k);
    if (k >= 1)
      add(neighbours(tri[0]), tri, k);
    add(Recent, tri, k);
    return List;
  }

  // The triangle decoded: its edges and vertices join what later corners are predicted from.
  void learn(const std::int64_t* tri)
  {
    for (int c = 0; c < 3; ++c)
    {
      link(tri[c], tri[(c + 1) % 3]);
      largest = std::max(largest, tri[c]);
    }
    for (int c = 0; c < 3; ++c)
    {
      Recent.erase(std::remove(Recent.begin(), Recent.end(), tri[c]), Recent.end());
      Recent.insert(Recent.begin(), tri[c]);
    }
    if (Recent.size() > RecentSize)
      Recent.resize(RecentSize);
  }

private:
  const std::vector<std::int64_t>& neighbours(std::int64_t v)
  {
    static const std::vector<std::int64_t> none;
    const auto it = Adjacency.find(v);
    return it == Adjacency.end() ? none : it->second;
  }

  void link(std::int64_t a, std::int64_t b)
  {
    for (auto [from, to] : {std::pair{a, b}, std::pair{b, a}})
    {
      std::vector<std::int64_t>& ring = Adjacency[from];
      if (ring.size() < RingSize && std::find(ring.begin(), ring.end(), to) == ring.end())
        ring.push_back(to);
    }
  }

  // Appends `from`'s vertices not yet listed nor among the triangle's earlier corners.
  void add(const std::vector<std::int64_t>& from, const std::int64_t* tri, int k)
  {
    for (std::int64_t v : from)
    {
      if (List.size() == ListSize)
        return;
      if (std::find(tri, tri + k, v) == tri + k &&
          std::find(List.begin(), List.end(), v) == List.end())
        List.push_back(v);
    }
  }

  std::unordered_map<std::int64_t, std::vector<std::int64_t>> Adjacency;
  std::vector<std::int64_t> Recent, List;
};

// The corners through the range coder (the file comment), after the form byte.
void encodeCorners(const std::vector<std::int64_t>& triangles, std::size_t vertices,
                   std::vector<std::uint8_t>& out)
{
  CornerCoding state;
  RangeEncoder e;
  for (std::size_t t = 0; t < triangles.size(); t += 3)
  {
    const std::int64_t* tri = &triangles[t];
    for (int k = 0; k < 3; ++k)
    {
      const std::int64_t v = tri[k];
      if (v < 0 || static_cast<std::size_t>(v) >= vertices)
        throw std::invalid_argument("connectivity: vertex index " + std::to_string(v) +
                                    " out of range");
      CornerCoding::Models& m = state.models[k];
      const bool next = v == state.largest + 1;
      e.bit(m.isNext, next);
      if (next)
        continue;
      const std::vector<std::int64_t>& list = state.candidates(tri, k);
      const auto at = std::find(list.begin(), list.end(), v);
      e.bit(m.inList, at != list.end());
      if (at != list.end())
        e.integer(m.position, at - list.begin());
      else
        e.integer(m.escape, v - state.largest);
    }
    state.learn(tri);
  }
  const std::vector<std::uint8_t> coded = e.finish();
  out.insert(out.end(), coded.begin(), coded.end());
}

void decodeCorners(const std::uint8_t* bytes, std::size_t size, const std::string& what,
                   std::size_t vertices, std::vector<std::int64_t>& triangles)
{
  const auto fail = [&](const std::string& why) { throw std::runtime_error(what + ": " + why); };
  CornerCoding state;
  RangeDecoder d(bytes, size, what);
  for (std::size_t t = 0; t < triangles.size(); t += 3)
  {
    std::int64_t* tri = &triangles[t];
    for (int k = 0; k < 3; ++k)
    {
      CornerCoding::Models& m = state.models[k];
      std::int64_t v = state.largest + 1;
      if (!d.bit(m.isNext))
      {
        if (d.bit(m.inList))
        {
          const std::vector<std::int64_t>& list = state.candidates(tri, k);
          const std::int64_t at = d.integer(m.position);
          if (at < 0 || static_cast<std::size_t>(at) >= list.size())
            fail("a corner's position " + std::to_string(at) + " is beyond its list");
          v = list[static_cast<std::size_t>(at)];
        }
        else
          v = state.largest + d.integer(m.escape);
      }
      if (v < 0 || static_cast<std::size_t>(v) >= vertices)
        fail("triangle index " + std::to_string(v) + " out of range");
      tri[k] = v;
    }
    state.learn(tri);
  }
  d.finish();
}

// The varints through zstd of versions 1 to 4 (IntegerCodec.h), after the form byte: the
// unpacked size, then zstd's frame.
void encodePacked(const std::vector<std::int64_t>& triangles, std::vector<std::uint8_t>& out)
{
  std::vector<std::uint8_t> raw;
  putSequence(raw, triangles.data(), triangles.size(), 3);
  const std::vector<std::uint8_t> packed = zstdCompress(raw);
  putRaw<std::uint64_t>(out, raw.size());
  out.insert(out.end(), packed.begin(), packed.end());
}

std::vector<std::int64_t> decodePacked(const std::uint8_t* bytes, std::size_t size,
                                       const std::string& what, std::size_t triangleCount,
                                       std::size_t vertices)
{
  ByteReader in(bytes, size, what);
  const auto rawSize = in.raw<std::uint64_t>();
  // Each index takes 1 to 10 bytes, the sequence one more for its order; zstd expands a byte to
  // at most 32768 (plus a block): checked before anything is allocated.
  const std::uint64_t indices = 3 * static_cast<std::uint64_t>(triangleCount);
  if (rawSize < indices || rawSize > 10 * indices + 1 || rawSize > 32768 * in.remaining() + 131072)
    in.fail("claims " + std::to_string(rawSize) + " bytes for " + std::to_string(indices) +
            " indices");
  std::vector<std::uint8_t> raw(rawSize);
  const std::size_t n =
      ZSTD_decompress(raw.data(), raw.size(), bytes + in.position(), in.remaining());
  if (ZSTD_isError(n) || n != rawSize)
    in.fail("cannot be decompressed");
  return unpackTriangles(raw, what, triangleCount, vertices);
}

} // namespace

std::vector<std::int64_t> unpackTriangles(const std::vector<std::uint8_t>& raw,
                                          const std::string& what, std::size_t triangleCount,
                                          std::size_t vertices)
{
  ByteReader c(raw.data(), raw.size(), what);
  if (raw.size() < 3 * triangleCount) // every index takes at least a byte
    c.fail("holds " + std::to_string(raw.size()) + " bytes for " +
           std::to_string(3 * triangleCount) + " indices");
  std::vector<std::int64_t> triangles(3 * triangleCount);
  c.sequence(triangles.data(), triangles.size(), 3);
  if (c.remaining() != 0)
    c.fail("unexpected bytes after the triangles");
  for (std::int64_t v : triangles)
    if (v < 0 || static_cast<std::uint64_t>(v) >= vertices)
      c.fail("triangle index " + std::to_string(v) + " out of range");
  return triangles;
}

std::vector<std::uint8_t> encodeConnectivity(const std::vector<std::int64_t>& triangles,
                                             std::size_t vertices)
{
  if (triangles.size() % 3 != 0)
    throw std::invalid_argument("connectivity: not whole triangles");
  std::vector<std::uint8_t> corners{CodedCorners}, packed{PackedVarints};
  encodeCorners(triangles, vertices, corners);
  encodePacked(triangles, packed);
  return corners.size() <= packed.size() ? corners : packed;
}

std::vector<std::int64_t> decodeConnectivity(const std::uint8_t* bytes, std::size_t size,
                                             const std::string& what, std::size_t triangleCount,
                                             std::size_t vertices)
{
  if (size == 0)
    throw std::runtime_error(what + ": empty");
  if (bytes[0] != PackedVarints && bytes[0] != CodedCorners)
    throw std::runtime_error(what + ": unknown coding " + std::to_string(bytes[0]));
  if (triangleCount > (std::size_t{1} << 40))
    throw std::runtime_error(what + ": implausible triangle count");
  if (bytes[0] == PackedVarints)
    return decodePacked(bytes + 1, size - 1, what, triangleCount, vertices);
  // Each corner is at least one decision of the coder: more corners than the bytes can hold are
  // refused before anything is allocated.
  if (!canHold(size, 3.0 * static_cast<double>(triangleCount)))
    throw std::runtime_error(what + ": claims more triangles than its " + std::to_string(size) +
                             " bytes can hold");
  std::vector<std::int64_t> triangles(3 * triangleCount);
  decodeCorners(bytes + 1, size - 1, what, vertices, triangles);
  return triangles;
}

} // namespace dp::compress
