// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file DpzFormat.h
 * @brief The .dpz file's layout, shared by its writer (DpzFormat.cxx) and its reader
 *        (DpzReader.cxx); the functions that write and read it are declared in PcaCompression.h.
 *
 * A magic number and format version, a header of counts, steps and times with its CRC-32, then
 * sections each with its sizes and CRC-32: the connectivity (range-coded from version 5 on, zstd
 * before), the geometry (range-coded from version 4 on, zstd before), a byte of flags (from
 * version 3 on), the colour (zstd) and the detail layer (range-coded).
 *
 * Internal to the compression; not installed API.
 */
#pragma once

#include "dp/compress/PcaCompression.h"

#include <cstddef>
#include <cstdint>

namespace dp::compress::dpz
{

constexpr char Magic[8] = {'\x89', 'D', 'P', 'Z', '\r', '\n', '\x1a', '\n'};
// Version 1: connectivity and geometry. Version 2 adds the colour section after them. Version 3
// adds a byte of flags after the geometry (ColourFlag, DetailFlag) and the detail section.
// Version 4 codes the geometry over the mesh by the range coder (ModelCoding.h) instead of
// predicted varints through zstd. Version 5 codes the connectivity by the range coder too
// (ConnectivityCoding.h) and the frame times evenly spaced as their first and step; it is what
// the writer writes, and the reader reads all five.
constexpr std::uint32_t PlainVersion = 1;
constexpr std::uint32_t ColourVersion = 2;
constexpr std::uint32_t DetailVersion = 3;
constexpr std::uint32_t CodedGeometryVersion = 4;
constexpr std::uint32_t CodedConnectivityVersion = 5;
// Version 5's times: as a list (one double a frame), or evenly spaced (the first and the step).
constexpr std::uint8_t ListedTimes = 0, EvenTimes = 1;
constexpr std::uint8_t ColourFlag = 1, DetailFlag = 2;

// A section's sizes and checksum before its packed bytes.
constexpr std::size_t SectionHeaderBytes = 8 + 8 + 4;

// The detail section: levels, step, fine vertex count, the range coder's bytes (already
// entropy-coded: no zstd) with their size, then a CRC-32 of all of these, then the bytes.
constexpr std::size_t DetailFieldsBytes = 1 + 8 + 8 + 8;

/** zlib's CRC-32 of `size` bytes (any size: fed to zlib in chunks of 1 GiB). */
std::uint32_t crc(const std::uint8_t* data, std::size_t size);

/** The detail section's checksum: of its DetailFieldsBytes fields and its coded bytes. */
std::uint32_t detailChecksum(const std::uint8_t* fields, const std::uint8_t* payload,
                             std::size_t size);

/** The fine mesh's vertex count of the sequence's base subdivided `levels` times (a corrupt
 *  connectivity or level count is refused as a std::invalid_argument). */
std::size_t fineVerticesOf(const CompressedSequence& s, int levels);

} // namespace dp::compress::dpz
