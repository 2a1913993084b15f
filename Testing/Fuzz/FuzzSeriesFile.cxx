// SPDX-License-Identifier: BSD-3-Clause
// libFuzzer target: a ParaView .series file (JSON list of frame files and times) on arbitrary
// bytes, then the time lookup a reader does with it. An exception is the expected answer to a
// bad file; a crash, a hang, a leak or undefined behaviour is a finding.
#include "FuzzInputFile.h"

#include "dp/io/FrameSequence.h"

#include <cstdint>
#include <exception>
#include <limits>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  try
  {
    const dp::FrameSequence sequence =
        dp::FrameSequence::fromSeriesFile(dp::fuzz::writeInput(data, size, ".series"));
    if (!sequence.empty())
      for (const double time : {-std::numeric_limits<double>::infinity(), 0.0, 0.5, 1e300,
                                std::numeric_limits<double>::quiet_NaN()})
        (void)sequence[sequence.frameAtTime(time)].path.size();
  }
  catch (const std::exception&)
  {
    // A refused file: what bad input should get.
  }
  return 0;
}
