// SPDX-License-Identifier: BSD-3-Clause
// The .dpz file's writing (its layout: DpzFormat.h; its reading: DpzReader.cxx): the header, then
// each section with its sizes and CRC-32.
#include "dp/compress/DpzFormat.h"

#include "dp/compress/ColourStream.h"
#include "dp/compress/ConnectivityCoding.h"
#include "dp/compress/DetailCoding.h"
#include "dp/compress/IntegerCodec.h"
#include "dp/compress/ModelCoding.h"
#include "dp/io/FileText.h"

#include <zlib.h>

#include <algorithm>
#include <fstream>
#include <stdexcept>

namespace dp
{

using compress::checkColourCount;
using compress::colourResiduals;
using compress::putRaw;
using namespace compress::dpz;

std::uint32_t compress::dpz::crc(const std::uint8_t* data, std::size_t size)
{
  uLong c = crc32(0L, Z_NULL, 0);
  while (size > 0)
  {
    const uInt chunk = static_cast<uInt>(std::min<std::size_t>(size, 1u << 30));
    c = crc32(c, data, chunk);
    data += chunk;
    size -= chunk;
  }
  return static_cast<std::uint32_t>(c);
}

std::uint32_t compress::dpz::detailChecksum(const std::uint8_t* fields, const std::uint8_t* payload,
                                            std::size_t size)
{
  std::vector<std::uint8_t> all(fields, fields + DetailFieldsBytes);
  all.insert(all.end(), payload, payload + size);
  return crc(all.data(), all.size());
}

std::size_t compress::dpz::fineVerticesOf(const CompressedSequence& s, int levels)
{
  return SubdivisionMap(s.triangles, s.pca.model.vertices, levels).fineVertices();
}

namespace
{

void putSection(std::vector<std::uint8_t>& out, const std::vector<std::uint8_t>& raw)
{
  const std::vector<std::uint8_t> packed = compress::zstdCompress(raw);
  putRaw<std::uint64_t>(out, raw.size());
  putRaw<std::uint64_t>(out, packed.size());
  putRaw<std::uint32_t>(out, crc(packed.data(), packed.size()));
  out.insert(out.end(), packed.begin(), packed.end());
}

// The times as the header writes them: evenly spaced when first + t step gives each exactly.
void putTimes(std::vector<std::uint8_t>& header, const std::vector<double>& times)
{
  const double first = times.empty() ? 0.0 : times[0];
  const double step = times.size() > 1 ? times[1] - times[0] : 1.0;
  bool even = true;
  for (std::size_t t = 0; t < times.size() && even; ++t)
    even = first + static_cast<double>(t) * step == times[t];
  putRaw<std::uint8_t>(header, even ? EvenTimes : ListedTimes);
  if (even)
  {
    putRaw<double>(header, first);
    putRaw<double>(header, step);
  }
  else
    for (double v : times)
      putRaw<double>(header, v);
}

// A range-coded section (the geometry from version 4 on, the connectivity from 5): the coder's
// bytes with their size and CRC-32.
void putCoded(std::vector<std::uint8_t>& out, const std::vector<std::uint8_t>& coded)
{
  putRaw<std::uint64_t>(out, coded.size());
  putRaw<std::uint32_t>(out, crc(coded.data(), coded.size()));
  out.insert(out.end(), coded.begin(), coded.end());
}

// A detail layer the writer can store: levels in range, a step, and a payload beside
// displacements of the fine mesh's size.
void checkDetail(const CompressedSequence& s)
{
  const DetailLayer& d = s.detail;
  if (d.levels < 1 || d.levels > MaximumDetailLevels)
    throw std::invalid_argument("the detail layer's levels must be 1 to " +
                                std::to_string(MaximumDetailLevels) + ", not " +
                                std::to_string(d.levels));
  const std::size_t expected = fineVerticesOf(s, d.levels) * s.pca.model.frames;
  if (d.displacements.size() != expected || d.payload.empty() || !(d.step > 0))
    throw std::invalid_argument("the detail layer holds " + std::to_string(d.displacements.size()) +
                                " displacements and " + std::to_string(d.payload.size()) +
                                " coded bytes; its fine mesh needs " + std::to_string(expected) +
                                " displacements, coded (dp::setDetail)");
}

void putDetail(std::vector<std::uint8_t>& out, const DetailLayer& d, std::size_t fineVertices)
{
  const std::size_t fields = out.size();
  putRaw<std::uint8_t>(out, static_cast<std::uint8_t>(d.levels));
  putRaw<double>(out, d.step);
  putRaw<std::uint64_t>(out, fineVertices);
  putRaw<std::uint64_t>(out, d.payload.size());
  putRaw<std::uint32_t>(out,
                        detailChecksum(out.data() + fields, d.payload.data(), d.payload.size()));
  out.insert(out.end(), d.payload.begin(), d.payload.end());
}

} // namespace

std::vector<std::uint8_t> encodeCompressedSequence(const CompressedSequence& s)
{
  const QuantisedPca& q = s.pca;
  const PcaModel& m = q.model;
  if (q.step <= 0)
    throw std::invalid_argument("only a quantised sequence can be written (quantise = true)");
  checkColourCount(m, s.colours.size());
  std::vector<std::uint8_t> header;
  putRaw<std::uint8_t>(header, static_cast<std::uint8_t>(m.layout));
  putRaw<std::uint64_t>(header, m.vertices);
  putRaw<std::uint64_t>(header, m.frames);
  putRaw<std::uint64_t>(header, m.components());
  putRaw<std::uint64_t>(header, s.triangles.size() / 3);
  putRaw<double>(header, q.step);
  putRaw<double>(header, q.meanStep);
  for (double v : q.basisSteps)
    putRaw<double>(header, v);
  std::vector<double> times(m.frames);
  for (std::size_t t = 0; t < m.frames; ++t)
    times[t] = t < s.times.size() ? s.times[t] : static_cast<double>(t);
  putTimes(header, times);

  const bool detailed = s.detail.levels > 0;
  if (detailed)
    checkDetail(s);
  std::vector<std::uint8_t> out(Magic, Magic + sizeof(Magic));
  putRaw<std::uint32_t>(out, CodedConnectivityVersion);
  putRaw<std::uint64_t>(out, header.size());
  out.insert(out.end(), header.begin(), header.end());
  putRaw<std::uint32_t>(out, crc(header.data(), header.size()));

  putCoded(out, compress::encodeConnectivity(s.triangles, m.vertices));
  putCoded(out, compress::encodeModel(q, compress::VertexTraversal(s.triangles, m.vertices)));
  putRaw<std::uint8_t>(out, static_cast<std::uint8_t>((s.colours.empty() ? 0 : ColourFlag) |
                                                      (detailed ? DetailFlag : 0)));
  if (!s.colours.empty())
    putSection(out, colourResiduals(s.colours, m.vertices, m.frames));
  if (detailed)
    putDetail(out, s.detail, fineVerticesOf(s, s.detail.levels));
  return out;
}

std::size_t compress::colourSectionBytes(const std::vector<std::uint8_t>& colours,
                                         std::size_t vertices, std::size_t frames)
{
  return SectionHeaderBytes + zstdCompress(colourResiduals(colours, vertices, frames)).size();
}

void writeCompressedSequence(const std::string& path, const CompressedSequence& sequence)
{
  const std::vector<std::uint8_t> bytes = encodeCompressedSequence(sequence);
  // Write beside and rename, so a failed write never leaves a half file under the name.
  support::writeBesideAndMove(path,
                              [&](const std::string& partial)
                              {
                                std::ofstream out(partial, std::ios::binary | std::ios::trunc);
                                if (!out)
                                  throw std::runtime_error(path + ": cannot open for writing");
                                out.write(reinterpret_cast<const char*>(bytes.data()),
                                          static_cast<std::streamsize>(bytes.size()));
                                if (!out)
                                  throw std::runtime_error(path + ": write failed");
                              });
}

} // namespace dp
