// SPDX-License-Identifier: BSD-3-Clause
// dp-option-code: rewrites, or checks, the regions of the product's files that restate the option
// tables (dp/io/OptionCode.h): the VTK classes' named accessors, ParaView's properties, the
// documentation's tables. A developer's tool: after a row of a table changes,
//   build/bin/dp-option-code write .     (from the source tree's root)
// and `check` (the test suite runs it) lists the regions out of date, exit 1.
#include "dp/io/OptionCode.h"
#include "dp/compress/CompressionOptions.h"
#include "dp/detail/DetailOptions.h"
#include "dp/io/FileText.h"
#include "dp/track/TrackerOptionTable.h"

#include <iostream>
#include <stdexcept>

namespace
{

// The files holding regions, from the source tree's root.
const char* const RegionFiles[] = {
    "Filters/vtkDeformableTrackFilter.h",
    "Filters/vtkPCACompressFilter.h",
    "Filters/vtkCompressedSequenceWriter.h",
    "Filters/vtkSurfaceDetailFilter.h",
    "ParaViewPlugin/DeformableTrackFilter.xml",
    "ParaViewPlugin/PCACompressFilter.xml",
    "ParaViewPlugin/SurfaceDetailFilter.xml",
    "Documentation/TrackerOptions.md",
    "Documentation/Compression.md",
};

dp::OptionCodeTable tableNamed(const std::string& name)
{
  if (name == "tracker")
    return dp::trackerOptions().codeTable("TrackerOption");
  if (name == "compression")
    return dp::compressionOptions().codeTable("CompressionOption");
  if (name == "detail")
    return dp::detailOptions().codeTable("DetailOption");
  throw std::invalid_argument("no option table '" + name + "' (tracker, compression, detail)");
}

std::string generated(const std::string& path, const dp::OptionRegion& region)
{
  const dp::OptionCodeTable table = tableNamed(region.table);
  const std::string extension = path.substr(path.rfind('.'));
  if (extension == ".h")
    return dp::vtkAccessors(table, region.except);
  if (extension == ".xml")
    return dp::paraviewProperties(table, region.except);
  return dp::option_forms::describeMarkdown(table.specs, table.defaults);
}

} // namespace

int main(int argc, char** argv)
{
  const std::string mode = argc == 3 ? argv[1] : "";
  if (mode != "write" && mode != "check")
  {
    std::cerr << "usage: dp-option-code write|check SOURCE_ROOT\n";
    return 2;
  }
  try
  {
    int stale = 0;
    for (const char* file : RegionFiles)
    {
      const std::string path = std::string(argv[2]) + "/" + file;
      const std::string before = dp::support::readWholeFile(path);
      const std::string after = dp::rewriteOptionRegions(
          before, path, [&](const dp::OptionRegion& r) { return generated(path, r); });
      if (after == before)
        continue;
      ++stale;
      if (mode == "write")
        dp::support::writeWholeFile(path, after);
      std::cout << path << (mode == "write" ? ": rewritten\n" : ": out of date with the tables\n");
    }
    if (mode == "check" && stale > 0)
      std::cout << "run: dp-option-code write SOURCE_ROOT (the build's bin/dp-option-code)\n";
    return mode == "check" && stale > 0 ? 1 : 0;
  }
  catch (const std::exception& e)
  {
    std::cerr << "dp-option-code: error: " << e.what() << "\n";
    return 1;
  }
}
