// SPDX-License-Identifier: BSD-3-Clause
// The animated meshes the benchmarks run on: the built-in tube or a folder of ../shared/data.
#pragma once

#include "dp/io/AnimatedMesh.h"
#include "dp/io/FrameSequence.h"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace dp::bench
{

/** "tube" or the PLY (else OBJ) frames of data/name; nullptr (with a line saying so) when not
 *  there. */
inline std::unique_ptr<dp::AnimatedMesh> loadAnimation(const std::string& data,
                                                       const std::string& name)
{
  if (name == "tube")
    return std::make_unique<dp::BendingTube>();
  const std::string folder = data + "/" + name;
  if (!std::filesystem::is_directory(folder))
  {
    std::printf("\n== %s: %s not found, skipped\n", name.c_str(), folder.c_str());
    return nullptr;
  }
  // One mesh file per frame: PLY, else OBJ.
  for (const char* extension : {".ply", ".obj"})
    for (const auto& entry : std::filesystem::directory_iterator(folder))
      if (entry.path().extension() == extension)
        return std::make_unique<dp::MeshSequenceFiles>(
            dp::FrameSequence::fromDirectory(folder, std::string("*") + extension));
  std::printf("\n== %s: no .ply or .obj frames in %s, skipped\n", name.c_str(), folder.c_str());
  return nullptr;
}

} // namespace dp::bench
