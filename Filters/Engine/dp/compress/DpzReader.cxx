// SPDX-License-Identifier: BSD-3-Clause
// The .dpz file's reading (its layout: DpzFormat.h; its writing: DpzFormat.cxx). Every count is
// checked against what the bytes can hold, and what the decoded take will hold against the memory
// budget (dp::MemoryAccount), before anything is allocated for it, so a corrupt or hostile file is
// refused with its name and the reason. Worst case: the budget; below it, the model's values (16
// bytes each) at the range coder's densest, about 6 KiB per byte of the geometry, and zstd
// sections at 32 768x.
#include "dp/compress/ColourStream.h"
#include "dp/compress/ConnectivityCoding.h"
#include "dp/compress/DetailCoding.h"
#include "dp/compress/DpzFormat.h"
#include "dp/compress/IntegerCodec.h"
#include "dp/compress/ModelCoding.h"
#include "dp/compress/RangeCoder.h"
#include "dp/io/MemoryBudget.h"

#include <zstd.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <utility>

namespace dp
{

using compress::BasisStride;
using compress::ByteReader;
using compress::coloursFromResiduals;
using compress::EarlierNeighbours;
using compress::MeanStride;
using compress::WeightStride;
using namespace compress::dpz;

namespace
{

// A fuzzing build (Testing/Fuzz) computes the checksums but does not enforce them, so mutated
// inputs reach the decoder behind them.
#ifdef DP_FUZZING_BUILD
constexpr bool EnforceChecksums = false;
#else
constexpr bool EnforceChecksums = true;
#endif

// A zstd section's bytes, unpacked: its sizes held to `limit` and to what zstd can expand to,
// its checksum checked; `in` moves past it.
std::vector<std::uint8_t> getSection(ByteReader& in, const std::uint8_t* bytes,
                                     const std::string& what, std::uint64_t limit)
{
  const auto rawSize = in.raw<std::uint64_t>();
  const auto packedSize = in.raw<std::uint64_t>();
  const auto expected = in.raw<std::uint32_t>();
  if (packedSize > in.remaining())
    in.fail(what + " is truncated (" + std::to_string(in.remaining()) + " of " +
            std::to_string(packedSize) + " bytes)");
  if (rawSize > limit)
    in.fail(what + " claims " + std::to_string(rawSize) + " bytes, more than its counts allow");
  // A zstd block holds at most 128 KiB and takes at least 4 bytes (an RLE block): no frame
  // expands more than that, so a larger claim is refused before it is allocated.
  if (rawSize > 32768 * packedSize + 131072)
    in.fail(what + " claims " + std::to_string(rawSize) + " bytes from " +
            std::to_string(packedSize) + " packed bytes, more than zstd can expand to");
  const std::uint8_t* packed = bytes + in.position();
  if (crc(packed, packedSize) != expected && EnforceChecksums)
    in.fail(what + ": checksum mismatch (the file is corrupt)");
  std::vector<std::uint8_t> raw(rawSize);
  const std::size_t n = ZSTD_decompress(raw.data(), raw.size(), packed, packedSize);
  if (ZSTD_isError(n) || n != rawSize)
    in.fail(what + ": cannot be decompressed");
  for (std::uint64_t i = 0; i < packedSize; ++i)
    in.byte();
  return raw;
}

// The counts the header gives.
struct Counts
{
  std::uint64_t vertices = 0, frames = 0, components = 0, triangles = 0;
  std::uint64_t meanCount() const { return 3 * (shapes ? vertices : frames); }
  std::uint64_t basisRows() const { return 3 * (shapes ? vertices : frames); }
  std::uint64_t weightRows() const { return shapes ? frames : vertices; }
  bool shapes = true;
};

// The frame times of a header: from version 5 on a byte of form, then the list or the first
// and the step; before, the list. Listed, the frames are bounded by the header's length; evenly
// spaced, by what the file's `sectionBytes` after the header can hold (every frame takes a
// value of the geometry, at least 0.022 bits, unless the take is still: some slack for that).
void readTimes(ByteReader& header, std::uint32_t version, std::uint64_t frames,
               std::size_t sectionBytes, std::vector<double>& times)
{
  const std::uint8_t form = version >= CodedConnectivityVersion ? header.byte() : ListedTimes;
  if (form != ListedTimes && form != EvenTimes)
    header.fail("unknown form of the frame times (" + std::to_string(form) + ")");
  if (header.remaining() != (form == ListedTimes ? 8 * frames : 16))
    header.fail("header length does not match its counts");
  if (form == EvenTimes && !compress::canHold(sectionBytes, static_cast<double>(frames)))
    header.fail("claims more frames (" + std::to_string(frames) + ") than the file can hold");
  times.resize(frames);
  if (form == EvenTimes)
  {
    const auto first = header.raw<double>(), step = header.raw<double>();
    for (std::size_t t = 0; t < frames; ++t)
      times[t] = first + static_cast<double>(t) * step;
  }
  else
    for (double& v : times)
      v = header.raw<double>();
  for (double v : times)
    if (!std::isfinite(v))
      header.fail("a time value is not finite");
}

// What decoding holds, per count, generously (TestMemoryBudget measures it): a triangle's
// three ids and the coders' corner tables and rings; a vertex's traversal and neighbour lists;
// a value of the model as an integer and a double (and its varint in versions 1 to 3); a frame's
// positions given to the caller.
constexpr double BytesPerTriangle = 160, BytesPerVertex = 160, BytesPerValue = 32,
                 BytesPerFramePosition = 24;
// The detail layer: a fine vertex's displacement per frame (and its share of the coded bytes),
// and once its place in the subdivision, its position, normal and colour in the frame given to
// the caller; a fine triangle's ids, in the map and in the caller's cells.
constexpr double BytesPerFineDisplacement = 10, BytesPerFineVertex = 160, BytesPerFineTriangle = 96;

// Claims from `account` what the header's counts make the decoder hold, before any of it.
void claimBase(MemoryAccount& account, const Counts& n)
{
  const double nv = static_cast<double>(n.vertices), nt = static_cast<double>(n.frames);
  const double values =
      static_cast<double>(n.meanCount()) +
      static_cast<double>(n.components) * static_cast<double>(n.basisRows() + n.weightRows());
  account.claim(8 * nt + BytesPerTriangle * static_cast<double>(n.triangles) +
                    (BytesPerVertex + BytesPerFramePosition) * nv + BytesPerValue * values,
                std::to_string(n.vertices) + " vertices, " + std::to_string(n.triangles) +
                    " triangles, " + std::to_string(n.frames) + " frames, " +
                    std::to_string(n.components) + " components");
}

// The header: layout, counts, quantisation steps, times.
Counts readHeader(ByteReader& header, std::uint32_t version, std::size_t sectionBytes,
                  MemoryAccount& account, CompressedSequence& s)
{
  QuantisedPca& q = s.pca;
  PcaModel& m = q.model;
  const auto layout = header.raw<std::uint8_t>();
  if (layout > 1)
    header.fail("unknown layout " + std::to_string(layout));
  m.layout = static_cast<PcaLayout>(layout);
  Counts n;
  n.shapes = m.layout == PcaLayout::Shapes;
  n.vertices = header.raw<std::uint64_t>();
  n.frames = header.raw<std::uint64_t>();
  n.components = header.raw<std::uint64_t>();
  n.triangles = header.raw<std::uint64_t>();
  const std::uint64_t nv = n.vertices, nt = n.frames, k = n.components;
  const std::uint64_t limit = std::uint64_t{1} << 40;
  if (nv == 0 || nt == 0 || nv > limit || nt > limit || nv * nt > limit || k > 3 * nt ||
      k > 3 * nv || n.triangles > limit)
    header.fail("implausible counts (vertices " + std::to_string(nv) + ", frames " +
                std::to_string(nt) + ", components " + std::to_string(k) + ")");
  if (header.remaining() < 8 * (2 + k))
    header.fail("header length does not match its counts");
  m.vertices = nv;
  m.frames = nt;
  q.step = header.raw<double>();
  q.meanStep = header.raw<double>();
  if (!(q.step > 0) || !(q.meanStep > 0) || !std::isfinite(q.step) || !std::isfinite(q.meanStep))
    header.fail("invalid quantisation step");
  q.basisSteps.resize(k);
  for (double& v : q.basisSteps)
  {
    v = header.raw<double>();
    if (!(v > 0) || !std::isfinite(v))
      header.fail("invalid basis step");
  }
  claimBase(account, n);
  readTimes(header, version, nt, sectionBytes, s.times);
  return n;
}

// Versions 1 to 4's connectivity: predicted varints through zstd. Each varint takes at most 10
// bytes, each sequence one more for its order.
void readPackedConnectivity(ByteReader& in, const std::uint8_t* bytes, const std::string& name,
                            const Counts& n, CompressedSequence& s)
{
  const std::vector<std::uint8_t> raw =
      getSection(in, bytes, "connectivity", 10 * 3 * n.triangles + 1);
  s.triangles = compress::unpackTriangles(raw, name + " (connectivity)", n.triangles, n.vertices);
}

// Versions 1 to 3: the integers of the mean, the basis and the weights, as predicted varints
// through zstd (IntegerCodec.h).
void readGeometry(ByteReader& in, const std::uint8_t* bytes, const std::string& name,
                  const Counts& n, CompressedSequence& s)
{
  QuantisedPca& q = s.pca;
  const std::uint64_t k = n.components, meanCount = n.meanCount(), basisRows = n.basisRows(),
                      weightRows = n.weightRows();
  const std::uint64_t numbers = meanCount + k * (basisRows + weightRows);
  const std::vector<std::uint8_t> raw = getSection(in, bytes, "geometry", 10 * numbers + 1 + 2 * k);
  ByteReader g(raw.data(), raw.size(), name + " (geometry)");
  if (raw.size() < numbers) // every number takes at least a byte
    g.fail("holds " + std::to_string(raw.size()) + " bytes for " + std::to_string(numbers) +
           " numbers");
  // Every vertex is a triangle's corner or has values of its own (a byte each at least): more
  // are refused before their neighbour lists are made.
  if (n.vertices > 3 * n.triangles + raw.size())
    g.fail("claims " + std::to_string(n.vertices) + " vertices; its " +
           std::to_string(n.triangles) + " triangles and " + std::to_string(raw.size()) +
           " bytes of values hold at most " + std::to_string(3 * n.triangles + raw.size()));
  const EarlierNeighbours mesh(s.triangles, n.vertices);
  const EarlierNeighbours* perVertex = n.shapes ? &mesh : nullptr;
  q.meanIntegers.resize(meanCount);
  g.sequence(q.meanIntegers.data(), meanCount, MeanStride, perVertex);
  q.basisIntegers.resize(k * basisRows);
  for (std::uint64_t j = 0; j < k; ++j)
    g.sequence(q.basisIntegers.data() + j * basisRows, basisRows, BasisStride, perVertex);
  q.weightIntegers.resize(k * weightRows);
  for (std::uint64_t j = 0; j < k; ++j)
    g.sequence(q.weightIntegers.data() + j * weightRows, weightRows, WeightStride,
               n.shapes ? nullptr : &mesh);
  if (g.remaining() != 0)
    g.fail("unexpected bytes after the weights");
}
// The bytes of a range-coded section, their checksum checked; `in` moves past them.
std::pair<const std::uint8_t*, std::size_t> getCoded(ByteReader& in, const std::uint8_t* bytes,
                                                     const std::string& what)
{
  const auto size = in.raw<std::uint64_t>();
  const auto expected = in.raw<std::uint32_t>();
  if (size > in.remaining())
    in.fail(what + " is truncated (" + std::to_string(in.remaining()) + " of " +
            std::to_string(size) + " bytes)");
  const std::uint8_t* coded = bytes + in.position();
  if (crc(coded, size) != expected && EnforceChecksums)
    in.fail(what + ": checksum mismatch (the file is corrupt)");
  for (std::uint64_t i = 0; i < size; ++i)
    in.byte();
  return {coded, static_cast<std::size_t>(size)};
}

void readCodedConnectivity(ByteReader& in, const std::uint8_t* bytes, const std::string& name,
                           const Counts& n, CompressedSequence& s)
{
  const auto [coded, size] = getCoded(in, bytes, "connectivity");
  s.triangles =
      compress::decodeConnectivity(coded, size, name + " (connectivity)", n.triangles, n.vertices);
}

void readCodedGeometry(ByteReader& in, const std::uint8_t* bytes, const std::string& name,
                       const Counts& n, CompressedSequence& s)
{
  const auto [coded, size] = getCoded(in, bytes, "geometry");
  // More values (or vertices to visit) than the coder's bytes can hold are refused before
  // anything is allocated.
  const double numbers =
      static_cast<double>(n.meanCount() + n.components * (n.basisRows() + n.weightRows()));
  if (!compress::canHold(size, numbers + static_cast<double>(n.vertices)))
    in.fail("geometry claims more values than its " + std::to_string(size) + " bytes can hold");
  const compress::VertexTraversal traversal(s.triangles, n.vertices);
  compress::decodeModel(coded, size, name + " (geometry)", traversal, s.pca.model.layout, n.frames,
                        n.components, s.pca);
}

// Version 2's colour section: exactly three bytes per vertex and frame.
void readColours(ByteReader& in, const std::uint8_t* bytes, const Counts& n, MemoryAccount& account,
                 CompressedSequence& s)
{
  const std::uint64_t count = 3 * n.vertices * n.frames;
  // The stream as zstd gives it back, the colours from it, a frame's given to the caller.
  account.claim(2.0 * static_cast<double>(count) + 3.0 * static_cast<double>(n.vertices),
                "the colours of " + std::to_string(n.frames) + " frames");
  const std::size_t start = in.position();
  const std::vector<std::uint8_t> raw = getSection(in, bytes, "colour stream", count);
  if (raw.size() != count)
    in.fail("colour stream holds " + std::to_string(raw.size()) + " bytes; " +
            std::to_string(n.frames) + " frames of " + std::to_string(n.vertices) +
            " vertices need " + std::to_string(count));
  s.colours = coloursFromResiduals(raw, n.vertices, n.frames);
  s.report.colourBytes = in.position() - start;
}

// The model's values from its integers and steps.
void dequantise(const Counts& n, QuantisedPca& q)
{
  PcaModel& m = q.model;
  const std::uint64_t k = n.components, meanCount = n.meanCount(), basisRows = n.basisRows(),
                      weightRows = n.weightRows();
  m.mean.resize(static_cast<Eigen::Index>(meanCount));
  for (std::uint64_t i = 0; i < meanCount; ++i)
    m.mean[i] = static_cast<double>(q.meanIntegers[i]) * q.meanStep;
  m.basis.resize(basisRows, k);
  for (std::uint64_t j = 0; j < k; ++j)
    for (std::uint64_t i = 0; i < basisRows; ++i)
      m.basis(i, j) = static_cast<double>(q.basisIntegers[j * basisRows + i]) * q.basisSteps[j];
  m.weights.resize(weightRows, k);
  for (std::uint64_t i = 0; i < k * weightRows; ++i)
    m.weights.data()[i] = static_cast<double>(q.weightIntegers[i]) * q.step;
}

// The detail section's fields before its coded bytes.
struct DetailFields
{
  std::uint64_t fine = 0, size = 0; // fine vertices, coded bytes
  std::uint32_t checksum = 0;
};

// The detail section's fields: its levels and step into `d`, checked, and its bytes' presence.
DetailFields readDetailFields(ByteReader& in, DetailLayer& d)
{
  DetailFields f;
  d.levels = in.raw<std::uint8_t>();
  d.step = in.raw<double>();
  f.fine = in.raw<std::uint64_t>();
  f.size = in.raw<std::uint64_t>();
  f.checksum = in.raw<std::uint32_t>();
  if (d.levels < 1 || d.levels > MaximumDetailLevels)
    in.fail("detail layer of " + std::to_string(d.levels) + " levels (1 to " +
            std::to_string(MaximumDetailLevels) + " are possible)");
  if (!(d.step > 0) || !std::isfinite(d.step))
    in.fail("invalid detail step");
  if (f.size > in.remaining())
    in.fail("detail layer is truncated (" + std::to_string(in.remaining()) + " of " +
            std::to_string(f.size) + " bytes)");
  return f;
}

// Refuses a detail layer whose counts its bytes cannot hold, then claims from `account` what
// decoding it holds.
void claimDetail(ByteReader& in, const Counts& n, int levels, const DetailFields& f,
                 MemoryAccount& account)
{
  const std::uint64_t fine = f.fine, size = f.size;
  // More values than the coder's bytes can hold are refused before anything is allocated; and a
  // subdivision of more triangles than the fine vertices claimed is not made.
  if (!compress::canHold(size, static_cast<double>(fine) * static_cast<double>(n.frames)))
    in.fail("detail layer claims more values than its " + std::to_string(size) + " bytes can hold");
  if (std::ldexp(static_cast<double>(n.triangles), 2 * levels) >
      8.0 * static_cast<double>(fine) + 1e6)
    in.fail("detail layer claims " + std::to_string(fine) + " fine vertices, too few for " +
            std::to_string(levels) + " levels over " + std::to_string(n.triangles) + " triangles");
  const double fineTriangles = std::ldexp(static_cast<double>(n.triangles), 2 * levels);
  account.claim(
      static_cast<double>(size) +
          static_cast<double>(fine) *
              (BytesPerFineVertex + BytesPerFineDisplacement * static_cast<double>(n.frames)) +
          BytesPerFineTriangle * fineTriangles,
      "a detail layer of " + std::to_string(fine) + " fine vertices over " +
          std::to_string(n.frames) + " frames");
}

// Refuses a detail layer whose fine vertex count is not that of the base's subdivision.
void checkFineVertices(ByteReader& in, const CompressedSequence& s, int levels, std::uint64_t fine)
{
  std::size_t computed = 0;
  try
  {
    computed = fineVerticesOf(s, levels);
  }
  catch (const std::invalid_argument& e)
  {
    in.fail(std::string("the connectivity cannot be subdivided: ") + e.what());
  }
  if (fine != computed)
    in.fail("detail layer claims " + std::to_string(fine) + " fine vertices; the base's " +
            std::to_string(levels) + " levels make " + std::to_string(computed));
}

// The detail section back: its header checked against the base, its displacements decoded.
void readDetail(ByteReader& in, const std::uint8_t* bytes, const std::string& name, const Counts& n,
                MemoryAccount& account, CompressedSequence& s)
{
  const std::size_t start = in.position();
  DetailLayer& d = s.detail;
  const std::uint8_t* fields = bytes + start;
  const DetailFields f = readDetailFields(in, d);
  const std::uint64_t size = f.size;
  claimDetail(in, n, d.levels, f, account);
  checkFineVertices(in, s, d.levels, f.fine);
  const std::uint8_t* payload = bytes + in.position();
  if (detailChecksum(fields, payload, size) != f.checksum && EnforceChecksums)
    in.fail("detail layer: checksum mismatch (the file is corrupt)");
  d.payload.assign(payload, payload + size);
  for (std::uint64_t i = 0; i < size; ++i)
    in.byte();
  const SubdivisionMap map(s.triangles, n.vertices, d.levels);
  d.displacements = decodeDetail(map, n.frames, d.step, d.payload.data(), d.payload.size(),
                                 name + " (detail layer)");
  for (double v : d.displacements)
    if (!std::isfinite(v))
      in.fail("detail layer: displacements out of range");
  s.report.detailBytes = in.position() - start;
}

// The magic number and the format version; `in` moves past them.
std::uint32_t readVersion(ByteReader& in, const std::uint8_t* bytes, std::size_t size)
{
  if (size < sizeof(Magic) || std::memcmp(bytes, Magic, sizeof(Magic)) != 0)
    in.fail("not a DynamicPoints compressed sequence (.dpz)");
  for (std::size_t i = 0; i < sizeof(Magic); ++i)
    in.byte();
  const auto version = in.raw<std::uint32_t>();
  if (version < PlainVersion || version > CodedConnectivityVersion)
    in.fail("format version " + std::to_string(version) + " is not supported (this reader: " +
            std::to_string(PlainVersion) + " to " + std::to_string(CodedConnectivityVersion) + ")");
  return version;
}

// The header's bytes, their checksum checked, to be read on their own; `in` moves past them.
ByteReader headerOf(ByteReader& in, const std::uint8_t* bytes, const std::string& name)
{
  const auto headerSize = in.raw<std::uint64_t>();
  if (headerSize > in.remaining())
    in.fail("header truncated");
  const std::uint8_t* headerBytes = bytes + in.position();
  ByteReader header(headerBytes, headerSize, name + " (header)");
  for (std::uint64_t i = 0; i < headerSize; ++i)
    in.byte();
  if (in.raw<std::uint32_t>() != crc(headerBytes, headerSize) && EnforceChecksums)
    in.fail("header checksum mismatch (the file is corrupt)");
  return header;
}

// The sections after the header, each in the form its version gives it.
void readSections(ByteReader& in, const std::uint8_t* bytes, const std::string& name,
                  std::uint32_t version, const Counts& n, MemoryAccount& account,
                  CompressedSequence& s)
{
  if (version >= CodedConnectivityVersion)
    readCodedConnectivity(in, bytes, name, n, s);
  else
    readPackedConnectivity(in, bytes, name, n, s);
  if (version >= CodedGeometryVersion)
    readCodedGeometry(in, bytes, name, n, s);
  else
    readGeometry(in, bytes, name, n, s);
  std::uint8_t flags = version == ColourVersion ? ColourFlag : 0;
  if (version >= DetailVersion)
  {
    flags = in.byte();
    if (flags & ~(ColourFlag | DetailFlag))
      in.fail("unknown sections (flags " + std::to_string(flags) + ")");
  }
  if (flags & ColourFlag)
    readColours(in, bytes, n, account, s);
  if (flags & DetailFlag)
    readDetail(in, bytes, name, n, account, s);
}

} // namespace

CompressedSequence decodeCompressedSequence(const std::uint8_t* bytes, std::size_t size,
                                            const std::string& name)
{
  ByteReader in(bytes, size, name);
  const std::uint32_t version = readVersion(in, bytes, size);
  ByteReader header = headerOf(in, bytes, name);

  CompressedSequence s;
  MemoryAccount account(name);
  account.claim(static_cast<double>(size), "the file's bytes"); // held by the caller throughout
  const Counts n = readHeader(header, version, in.remaining(), account, s);
  readSections(in, bytes, name, version, n, account, s);
  if (in.remaining() != 0)
    in.fail("unexpected bytes after the last section");
  dequantise(n, s.pca);
  const PcaModel& m = s.pca.model;
  if (!m.mean.allFinite() || !m.basis.allFinite() || !m.weights.allFinite())
    in.fail("values out of range");
  s.report.components = n.components;
  return s;
}

CompressedSequence readCompressedSequence(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::runtime_error(path + ": cannot open");
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  return decodeCompressedSequence(bytes.data(), bytes.size(), path);
}

} // namespace dp
