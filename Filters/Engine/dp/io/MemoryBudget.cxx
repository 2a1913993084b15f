// SPDX-License-Identifier: BSD-3-Clause
// The memory budget of a file being read (MemoryBudget.h).
#include "dp/io/MemoryBudget.h"
#include "dp/io/PointCloud.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace dp
{

std::uint64_t memoryBudget()
{
  const char* text = std::getenv("DP_MEMORY_BUDGET");
  if (!text || !*text)
    return DefaultMemoryBudget;
  char* end = nullptr;
  const double value = std::strtod(text, &end);
  double unit = 1;
  switch (*end)
  {
  case 'K':
  case 'k':
    unit = 0x1p10;
    ++end;
    break;
  case 'M':
  case 'm':
    unit = 0x1p20;
    ++end;
    break;
  case 'G':
  case 'g':
    unit = 0x1p30;
    ++end;
    break;
  case 'T':
  case 't':
    unit = 0x1p40;
    ++end;
    break;
  default:
    break;
  }
  const double bytes = value * unit;
  if (end == text || *end != '\0' || !(bytes >= 1) || bytes > 0x1p62)
    throw std::invalid_argument(std::string("DP_MEMORY_BUDGET='") + text +
                                "' is not a size (bytes, or a number with K, M, G or T: 16G)");
  return static_cast<std::uint64_t>(bytes);
}

std::string formatBytes(double bytes)
{
  const char* units[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int u = 0;
  while (bytes >= 1024 && u < 6)
  {
    bytes /= 1024;
    ++u;
  }
  char text[64];
  if (u == 0)
    std::snprintf(text, sizeof text, "%.0f bytes", bytes);
  else if (bytes < 1e6)
    std::snprintf(text, sizeof text, "%.*f %s", bytes < 10 ? 1 : 0, bytes, units[u]);
  else
    std::snprintf(text, sizeof text, "%.3g %s", bytes, units[u]);
  return text;
}

MemoryAccount::MemoryAccount(std::string path, std::uint64_t budget)
    : Path(std::move(path)), Budget(budget)
{
}

void MemoryAccount::claim(double bytes, const std::string& what)
{
  Claimed += bytes;
  if (!(Claimed <= static_cast<double>(Budget))) // NaN refused too
    throw FileError(Path, "reading it needs " + formatBytes(Claimed) + " (" + what +
                              "), more than the memory budget of " +
                              formatBytes(static_cast<double>(Budget)) +
                              "; set DP_MEMORY_BUDGET (e.g. DP_MEMORY_BUDGET=32G) to raise it");
}

} // namespace dp
