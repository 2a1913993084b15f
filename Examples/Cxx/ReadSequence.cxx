// SPDX-License-Identifier: BSD-3-Clause
// A C++ VTK pipeline: read a point sequence and write every frame as a .vtp file plus a
// ParaView .pvd collection that plays it.
//
//   ReadSequence FOLDER_OR_SERIES OUTPUT_FOLDER
#include "vtkNew.h"
#include "vtkPointSequenceSource.h"
#include "vtkPolyData.h"
#include "vtkXMLPolyDataWriter.h"

#include <filesystem>
#include <fstream>
#include <iostream>

int main(int argc, char** argv)
{
  if (argc != 3)
  {
    std::cerr << "Usage: ReadSequence FOLDER_OR_SERIES OUTPUT_FOLDER\n";
    return 2;
  }
  vtkNew<vtkPointSequenceSource> source;
  if (std::filesystem::is_directory(argv[1]))
    source->SetDirectoryName(argv[1]);
  else
    source->SetFileName(argv[1]);
  const int frames = source->GetNumberOfFrames();
  if (frames < 0)
    return 1;

  std::filesystem::create_directories(argv[2]);
  std::ofstream pvd(std::filesystem::path(argv[2]) / "sequence.pvd");
  pvd << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetDataModeToBinary(); // inline data reads everywhere (see the README's platform notes)
  for (int f = 0; f < frames; ++f)
  {
    const std::string name = "frame_" + std::to_string(f) + ".vtp";
    source->UpdateTimeStep(source->GetFrameTime(f));
    writer->SetFileName((std::filesystem::path(argv[2]) / name).string().c_str());
    writer->SetInputData(source->GetOutput());
    if (writer->Write() != 1)
      return 1;
    pvd << "  <DataSet timestep=\"" << source->GetFrameTime(f) << "\" file=\"" << name << "\"/>\n";
  }
  pvd << "</Collection>\n</VTKFile>\n";
  std::cout << "wrote " << frames << " frames to " << argv[2] << "\n";
  return pvd ? 0 : 1;
}
