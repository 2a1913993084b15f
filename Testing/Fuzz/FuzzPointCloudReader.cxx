// SPDX-License-Identifier: BSD-3-Clause
// libFuzzer target: the engine's reader for one format (DP_FUZZ_EXTENSION) on arbitrary bytes.
// A clear error (an exception) is the expected answer to a bad file; a crash, a hang, a leak or
// undefined behaviour (ASan + UBSan abort) is a finding.
#include "FuzzInputFile.h"

#include "dp/io/PointCloudIO.h"

#include <cstdint>
#include <exception>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  const std::string path = dp::fuzz::writeInput(data, size, DP_FUZZ_EXTENSION);
  if (path.empty())
    return 0;
  try
  {
    const dp::PointCloud cloud = dp::readPointCloud(path);
    (void)cloud.numberOfPoints();
  }
  catch (const std::exception&)
  {
    // A refused file: what bad input should get.
  }
  return 0;
}
