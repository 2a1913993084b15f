// SPDX-License-Identifier: BSD-3-Clause
// libFuzzer target: the engine's reader for one format (DP_FUZZ_EXTENSION) on arbitrary bytes.
// A clear error (an exception) is the expected answer to a bad file; a crash, a hang, a leak or
// undefined behaviour (ASan + UBSan abort) is a finding.
#include "dp/PointCloudIO.h"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

namespace
{
// One file per process, rewritten for every input (the readers take paths).
const std::string& inputPath()
{
  static const std::string path = []
  {
    const char* dir = std::getenv("TMPDIR");
    return std::string(dir && *dir ? dir : "/tmp") + "/dp-fuzz-" + std::to_string(getpid()) +
           DP_FUZZ_EXTENSION;
  }();
  static const bool removedAtExit = std::atexit([] { std::remove(path.c_str()); }) == 0;
  (void)removedAtExit;
  return path;
}
} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  const std::string& path = inputPath();
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file)
    return 0;
  std::fwrite(data, 1, size, file);
  std::fclose(file);
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
