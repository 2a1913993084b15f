// SPDX-License-Identifier: BSD-3-Clause
// dynamicpoints: the main job. Today it reads a point sequence through the VTK pipeline and
// prints a summary of every frame; tracking and compression join it as they land.
#include "CommandLine.h"

#include "dp/AnimatedMesh.h"
#include "dp/SurfaceSampler.h"

#include "vtkCommand.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPointSequenceSource.h"
#include "vtkPolyData.h"

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

namespace
{

const char* const Usage = R"(Usage: dynamicpoints [OPTIONS] [INPUT]

Reads a time series of point clouds and prints a summary of every frame.

INPUT is a folder of point files (one per frame), a ParaView .series file, or one point
file. Readable: .ply .pcd .xyz .pts .csv .txt .obj .vtp .vtu .vtk.
Without INPUT, the built-in sample sequence is generated first: a bending, twisting tube,
30 frames of 20000 random surface points with normals, written to OUTPUT/input/.

Options:
  --pattern GLOB   files of an INPUT folder to read (default: *)
  --output DIR     where generated and result files go (default: dynamicpoints-output)
  -h, --help       show this help

Exit status: 0 when every frame was read, 1 when a frame failed, 2 for a bad command line.
)";

// Turns VTK errors and warnings into single lines on stderr and counts the errors.
class MessagePrinter : public vtkCommand
{
public:
  static MessagePrinter* New() { return new MessagePrinter; }
  void Execute(vtkObject*, unsigned long event, void* callData) override
  {
    const char* text = static_cast<const char*>(callData);
    std::string line = text ? text : "";
    // VTK prefixes "ERROR: In <source file>, line N\n<class> (<address>): "; keep the message.
    const std::size_t colon = line.find("): ");
    if (colon != std::string::npos)
      line = line.substr(colon + 3);
    while (!line.empty() && (line.back() == '\n' || line.back() == ' '))
      line.pop_back();
    std::cerr << (event == vtkCommand::ErrorEvent ? "error: " : "warning: ") << line << "\n";
    if (event == vtkCommand::ErrorEvent)
      ++Errors;
  }
  int Errors = 0;
};

int run(int argc, char** argv)
{
  using namespace dp::cli;
  std::string input, pattern = "*", output = "dynamicpoints-output";
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    if (arg == "-h" || arg == "--help")
    {
      std::cout << Usage;
      return 0;
    }
    else if (arg == "--pattern")
      pattern = optionValue(argc, argv, i);
    else if (arg == "--output")
      output = optionValue(argc, argv, i);
    else if (!arg.empty() && arg[0] == '-')
      throw UsageError("unknown option '" + arg + "'");
    else if (input.empty())
      input = arg;
    else
      throw UsageError("more than one INPUT given ('" + input + "', '" + arg + "')");
  }

  vtkNew<vtkPointSequenceSource> source;
  vtkNew<MessagePrinter> printer;
  source->AddObserver(vtkCommand::ErrorEvent, printer);
  source->AddObserver(vtkCommand::WarningEvent, printer);

  if (input.empty())
  {
    const std::string folder = (std::filesystem::path(output) / "input").string();
    std::cout << "No input given: generating the built-in sample sequence in " << folder << "\n";
    dp::SamplerOptions sampling;
    sampling.pointsPerFrame = 20000;
    sampling.seed = 1;
    source->SetFileName(dp::writeSampledSequence(dp::BendingTube(), sampling, folder).c_str());
  }
  else if (std::filesystem::is_directory(input))
  {
    source->SetDirectoryName(input.c_str());
    source->SetFilePattern(pattern.c_str());
  }
  else
  {
    source->SetFileName(input.c_str());
  }

  const int frames = source->GetNumberOfFrames();
  if (frames < 0)
    return 1; // the printer has said why
  std::cout << "Sequence: " << frames << " frame(s)\n";
  std::printf("%6s %10s %9s %8s  %-52s %s\n", "frame", "time", "points", "dropped",
              "bounds (xmin xmax ymin ymax zmin zmax)", "point arrays");
  int failed = 0;
  for (int f = 0; f < frames; ++f)
  {
    const int before = printer->Errors;
    source->UpdateTimeStep(source->GetFrameTime(f));
    if (printer->Errors > before)
    {
      ++failed;
      continue;
    }
    vtkPolyData* frame = source->GetOutput();
    double b[6];
    frame->GetBounds(b);
    std::ostringstream arrays;
    for (int a = 0; a < frame->GetPointData()->GetNumberOfArrays(); ++a)
      arrays << (a ? "," : "") << frame->GetPointData()->GetArrayName(a);
    char bounds[128];
    std::snprintf(bounds, sizeof(bounds), "%8.3g %8.3g %8.3g %8.3g %8.3g %8.3g", b[0], b[1], b[2],
                  b[3], b[4], b[5]);
    std::printf("%6d %10.4g %9lld %8lld  %-52s %s\n", f, source->GetFrameTime(f),
                static_cast<long long>(frame->GetNumberOfPoints()),
                static_cast<long long>(source->GetNumberOfDroppedPoints()), bounds,
                arrays.str().c_str());
  }
  std::cout << (frames - failed) << " of " << frames << " frame(s) read";
  if (failed)
    std::cout << ", " << failed << " failed (see the errors above)";
  std::cout << ".\n";
  return failed ? 1 : 0;
}

} // namespace

int main(int argc, char** argv)
{
  try
  {
    return run(argc, argv);
  }
  catch (const dp::cli::UsageError& e)
  {
    std::cerr << "dynamicpoints: " << e.what() << "\nTry 'dynamicpoints --help'.\n";
    return 2;
  }
  catch (const std::exception& e)
  {
    std::cerr << "dynamicpoints: error: " << e.what() << "\n";
    return 1;
  }
}
