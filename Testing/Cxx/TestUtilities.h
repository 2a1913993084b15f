// SPDX-License-Identifier: BSD-3-Clause
// Helpers for the C++ tests: a temporary folder that cleans up, file text in and out, a check
// that a call throws dp::FileError naming the right file, and the bending tube compressed.
#pragma once

#include "dp/compress/PcaCompression.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/io/PointCloud.h"

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace dp::test
{

/** The bending tube's first `frames` frames, compressed with the default options. */
inline dp::CompressedSequence compressedTube(std::size_t frames)
{
  dp::BendingTube::Options o;
  o.frames = frames;
  const dp::BendingTube mesh(o);
  std::vector<double> positions;
  for (std::size_t t = 0; t < frames; ++t)
  {
    const std::vector<double> p = mesh.positions(t);
    positions.insert(positions.end(), p.begin(), p.end());
  }
  return dp::compressSequence(positions.data(), mesh.numberOfVertices(), frames, dp::PcaOptions{},
                              mesh.triangles());
}

class TempDir
{
public:
  TempDir()
  {
    static std::atomic<int> counter{0};
    Path = std::filesystem::temp_directory_path() /
           ("dp-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
    std::filesystem::remove_all(Path);
    std::filesystem::create_directories(Path);
  }
  ~TempDir()
  {
    std::error_code ec;
    std::filesystem::remove_all(Path, ec);
  }
  std::string file(const std::string& name) const { return (Path / name).string(); }
  std::string path() const { return Path.string(); }

private:
  std::filesystem::path Path;
};

inline void writeText(const std::string& path, const std::string& text)
{
  std::ofstream out(path, std::ios::binary);
  out << text;
}

inline std::string readText(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/** Expects `call` to throw dp::FileError whose message starts with `path` and contains `part`. */
template <typename Call>
void expectFileError(Call call, const std::string& path, const std::string& part)
{
  try
  {
    call();
    ADD_FAILURE() << "no error for " << path << " (expected '" << part << "')";
  }
  catch (const dp::FileError& e)
  {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path, 0), 0u) << "message does not start with the file name: " << what;
    EXPECT_NE(what.find(part), std::string::npos) << "message lacks '" << part << "': " << what;
  }
}

} // namespace dp::test
