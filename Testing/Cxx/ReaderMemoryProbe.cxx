// SPDX-License-Identifier: BSD-3-Clause
// A small program for TestReaderMemory: reads one file with one of the engine's readers, in a
// process of its own, and prints what the reading cost:
//   ReaderMemoryProbe dpz|cloud|series FILE [LIMIT_BYTES]
//   -> "refused <seconds> <peak KiB> <message>" or "read <seconds> <peak KiB> <what was read>"
// The peak is the resident high-water mark of the reading alone (reset before it, less what was
// resident then). With
// LIMIT_BYTES the address space is also capped at what the process had plus that much, so a
// reservation that is never touched (and so never resident) fails too; not under AddressSanitizer,
// whose shadow memory needs terabytes of address space.
#include "dp/compress/DetailCoding.h"
#include "dp/compress/PcaCompression.h"
#include "dp/geometry/SubdivisionMap.h"
#include "dp/io/FrameSequence.h"
#include "dp/io/PointCloudIO.h"

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <string>

namespace
{

// A field of /proc/self/status in KiB (VmHWM, VmSize), or -1.
long statusKiB(const std::string& field)
{
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.compare(0, field.size() + 1, field + ":") == 0)
      return std::atol(line.c_str() + field.size() + 1);
  return -1;
}

std::string readWith(const std::string& kind, const std::string& path)
{
  if (kind == "dpz") // as vtkCompressedSequenceReader does: the file, then frame 0, finest
  {
    const dp::CompressedSequence s = dp::readCompressedSequence(path);
    const dp::PcaModel& m = s.pca.model;
    std::vector<double> frame(3 * m.vertices);
    m.frame(0, frame.data());
    if (s.detail.levels > 0)
    {
      const dp::SubdivisionMap map(s.triangles, m.vertices, s.detail.levels);
      frame.resize(3 * map.fineVertices());
      dp::detailedFrame(s, map, 0, frame.data());
    }
    return std::to_string(m.vertices) + " vertices, " + std::to_string(m.frames) + " frames";
  }
  if (kind == "cloud")
    return std::to_string(dp::readPointCloud(path).numberOfPoints()) + " points";
  if (kind == "series")
    return std::to_string(dp::FrameSequence::fromSeriesFile(path).size()) + " frames";
  throw std::invalid_argument("unknown reader '" + kind + "'");
}

} // namespace

int main(int argc, char** argv)
{
  if (argc < 3)
  {
    std::fprintf(stderr, "usage: ReaderMemoryProbe dpz|cloud|series FILE [LIMIT_BYTES]\n");
    return 2;
  }
#if !defined(__SANITIZE_ADDRESS__)
  if (argc > 3)
  {
    const rlim_t cap = static_cast<rlim_t>(statusKiB("VmSize")) * 1024 + std::stoull(argv[3]);
    const rlimit limit{cap, cap};
    setrlimit(RLIMIT_AS, &limit);
  }
#endif
  std::ofstream("/proc/self/clear_refs") << "5"; // the high-water mark from here on
  const long before = statusKiB("VmRSS");
  const auto start = std::chrono::steady_clock::now();
  std::string outcome, text;
  try
  {
    text = readWith(argv[1], argv[2]);
    outcome = "read";
  }
  catch (const std::exception& e)
  {
    text = e.what();
    outcome = "refused";
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%s %.3f %ld %s\n", outcome.c_str(), seconds, statusKiB("VmHWM") - before,
              text.c_str());
  return 0;
}
