// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file CompressionOptions.h
 * @brief Every compression option described once (an OptionTable over CompressionOptions): what
 *        the error target measures and each measure's target, the layout, the component count,
 *        quantisation and the colour tolerance, with their ranges, units and documentation.
 *
 * Everything else follows from this table or is checked against it: the codec filter's and the
 * writers' properties (vtkPCACompressFilter::SetCompressionOption and the named setters over
 * it), the command line (`--set compression.NAME=VALUE`, the shortcuts --fit-growth,
 * --error-target and --colour-tolerance, `--help`), report.json's record of the options a run
 * used, and Documentation/Compression.md's option table. A test compares the ParaView XML (the
 * filter and both writers) with it.
 *
 * Each measure has its own target, with its own unit and range, so a target never means another
 * measure's number: the Karni-Gotsman error (percent of the motion), the largest vertex error (a
 * fraction of the bounding-box diagonal), or the growth of the distance to the data the mesh was
 * tracked to (percent; dp::compressAgainstData).
 */
#pragma once

#include "dp/compress/PcaCompression.h"
#include "dp/io/OptionTable.h"

#include <cstddef>

namespace dp
{

enum class CompressionMeasure
{
  KarniGotsman = 0,   // kgTarget, percent
  MaxVertexError = 1, // maxVertexTarget, a fraction of the bounding-box diagonal
  DistanceToData = 2  // fitGrowth, percent (the input must carry the data it was tracked to)
};

struct CompressionOptions
{
  CompressionMeasure measure = CompressionMeasure::KarniGotsman;
  double kgTarget = 0.2;
  double maxVertexTarget = 0.002;
  double fitGrowth = 10;
  bool slide =
      true; // measure data: also code the take slid along its surface (compressAgainstData)
  PcaLayout layout = PcaLayout::Automatic;
  std::size_t components = 0; // 0: chosen for the fewest bytes that meet the target
  bool quantise = true;       // false: the paper's float PCA (no file can hold it)
  int colourTolerance = 4;    // levels (of 255) a stored colour may differ from the given one
};

/** The table, in the order the documentation lists it. */
const OptionTable<CompressionOptions>& compressionOptions();

/** The codec's options for `options` (the target of its measure; DistanceToData: the codec's
 *  options besides the target, which dp::compressAgainstData sets). Throws
 *  std::invalid_argument naming an option out of its range. */
PcaOptions pcaOptionsOf(const CompressionOptions& options);

/** The target of the measure chosen, as users read it: "KG 0.2 %", "the distance to the data
 *  grows by at most 10 %", "max vertex error 0.002 of the diagonal". */
std::string targetSaid(const CompressionOptions& options);

} // namespace dp
