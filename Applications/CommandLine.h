// SPDX-License-Identifier: BSD-3-Clause
// Small helpers shared by the command-line tools: option values with clear errors.
#pragma once

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace dp::cli
{

/** A bad command line: main() prints the message and a hint to --help, and exits with 2. */
struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/** The value after option argv[i] (advances i); throws UsageError when it is missing. */
inline std::string optionValue(int argc, char** argv, int& i)
{
  if (i + 1 >= argc)
    throw UsageError(std::string("option ") + argv[i] + " needs a value");
  return argv[++i];
}

inline double parseDouble(const std::string& option, const std::string& text, double min,
                          double max)
{
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || errno != 0 || !std::isfinite(value))
    throw UsageError("option " + option + ": '" + text + "' is not a number");
  if (value < min || value > max)
    throw UsageError("option " + option + ": " + text + " is outside [" + std::to_string(min) +
                     ", " + std::to_string(max) + "]");
  return value;
}

inline unsigned long long parseCount(const std::string& option, const std::string& text,
                                     unsigned long long min, unsigned long long max)
{
  char* end = nullptr;
  errno = 0;
  const unsigned long long value = std::strtoull(text.c_str(), &end, 10);
  if (text.empty() || text[0] == '-' || *end != '\0' || errno != 0)
    throw UsageError("option " + option + ": '" + text + "' is not a whole number");
  if (value < min || value > max)
    throw UsageError("option " + option + ": " + text + " is outside [" + std::to_string(min) +
                     ", " + std::to_string(max) + "]");
  return value;
}

/** Writes `text` to `path` through a file beside it, so a reader never sees half a file. */
inline void writeAtomically(const std::filesystem::path& path, const std::string& text)
{
  const std::filesystem::path partial = path.string() + ".partial";
  {
    std::ofstream out(partial, std::ios::trunc);
    out << text;
    if (!out)
      throw std::runtime_error(path.string() + ": cannot write");
  }
  std::filesystem::rename(partial, path);
}

} // namespace dp::cli
