// SPDX-License-Identifier: BSD-3-Clause
// libFuzzer target: the .dpz decoder on arbitrary bytes, in memory. Built with DP_FUZZING_BUILD,
// so the checksums are computed but not enforced and mutations reach the decoder. An exception
// is the expected answer to a bad file; a crash, a hang or undefined behaviour is a finding.
#include "dp/compress/PcaCompression.h"

#include <cstdint>
#include <exception>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  try
  {
    const dp::CompressedSequence sequence = dp::decodeCompressedSequence(data, size, "fuzz.dpz");
    (void)sequence;
  }
  catch (const std::exception&)
  {
    // A refused file: what bad input should get.
  }
  return 0;
}
