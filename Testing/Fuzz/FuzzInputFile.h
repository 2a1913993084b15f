// SPDX-License-Identifier: BSD-3-Clause
// The fuzz targets' input file: the engine's readers take paths, so each input is written to one
// file per process (in $TMPDIR), rewritten for every input and removed at exit.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace dp
{
namespace fuzz
{
/** Writes the input to this process's file with `extension` (which picks the reader) and returns
 *  its path; the path is empty when the file cannot be written. */
inline std::string writeInput(const std::uint8_t* data, std::size_t size, const char* extension)
{
  static const std::string stem = []
  {
    const char* dir = std::getenv("TMPDIR");
    return std::string(dir && *dir ? dir : "/tmp") + "/dp-fuzz-" + std::to_string(getpid());
  }();
  const std::string path = stem + extension;
  static const std::string removed = path; // one extension per target
  static const bool removedAtExit = std::atexit([] { std::remove(removed.c_str()); }) == 0;
  (void)removedAtExit;
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file)
    return {};
  std::fwrite(data, 1, size, file);
  std::fclose(file);
  return path;
}
} // namespace fuzz
} // namespace dp
