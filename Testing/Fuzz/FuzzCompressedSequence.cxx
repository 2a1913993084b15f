// SPDX-License-Identifier: BSD-3-Clause
// libFuzzer target: the .dpz decoder on arbitrary bytes, in memory, and for a file with a detail
// layer its first frame at the fine level (the subdivision and the displacements as a reader
// uses them). Built with DP_FUZZING_BUILD, so the checksums are computed but not enforced and
// mutations reach the decoder. An exception is the expected answer to a bad file; a crash, a hang
// or undefined behaviour is a finding.
#include "dp/compress/DetailCoding.h"
#include "dp/compress/PcaCompression.h"
#include "dp/geometry/SubdivisionMap.h"

#include <cstdint>
#include <exception>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  try
  {
    const dp::CompressedSequence sequence = dp::decodeCompressedSequence(data, size, "fuzz.dpz");
    if (sequence.detail.levels > 0)
    {
      const dp::SubdivisionMap map(sequence.triangles, sequence.pca.model.vertices,
                                   sequence.detail.levels);
      std::vector<double> fine(3 * map.fineVertices());
      dp::detailedFrame(sequence, map, 0, fine.data());
    }
  }
  catch (const std::exception&)
  {
    // A refused file: what bad input should get.
  }
  return 0;
}
