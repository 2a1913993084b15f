// SPDX-License-Identifier: BSD-3-Clause
// A VTK C++ pipeline built by hand, the whole job:
//
//   vtkPointSequenceSource -> vtkDeformableTrackFilter -> vtkPCACompressFilter ->
//   vtkXMLPolyDataWriter
//                                                  \-> vtkCompressedSequenceWriter
//
// reads a point sequence, tracks it with one mesh, compresses the tracked sequence, writes the
// decompressed mesh of every frame (OUTPUT/frame_NNNN.vtp + OUTPUT/sequence.pvd, which ParaView
// plays) and the compressed sequence (OUTPUT/tracked.dpz and OUTPUT/tracked.glb).
//
//   TrackAndCompress FOLDER_OR_SERIES OUTPUT_FOLDER [TEMPLATE_VERTICES]
//
// The tracker computes frame t from frame t-1 and keeps every frame it computed, so asking the
// frames in order costs one tracking step each, and the compressor's pass over all frames
// reuses them.
#include "vtkCompressedSequenceWriter.h"
#include "vtkDataArray.h"
#include "vtkDeformableTrackFilter.h"
#include "vtkFieldData.h"
#include "vtkNew.h"
#include "vtkPCACompressFilter.h"
#include "vtkPointData.h"
#include "vtkPointSequenceSource.h"
#include "vtkPolyData.h"
#include "vtkXMLPolyDataWriter.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace
{
// The RMS of the tracker's residual (each vertex's distance to the data).
double rootMeanSquare(vtkDataArray* residual)
{
  double sum = 0;
  for (vtkIdType i = 0; i < residual->GetNumberOfTuples(); ++i)
    sum += residual->GetComponent(i, 0) * residual->GetComponent(i, 0);
  return std::sqrt(sum / static_cast<double>(residual->GetNumberOfTuples()));
}

// Tracks the source's `frames` frames in order and writes each one's decompressed mesh
// (OUTPUT/frame_NNNN.vtp, listed in `pvd`), a line of figures a frame; false when a frame could
// not be written.
bool writeFrames(vtkPointSequenceSource* source, int frames, vtkDeformableTrackFilter* tracker,
                 vtkPCACompressFilter* compressor, const std::filesystem::path& output,
                 std::ofstream& pvd)
{
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetInputConnection(compressor->GetOutputPort());
  writer->SetDataModeToBinary(); // inline data reads everywhere (see Documentation/Development.md,
                                 // platform notes)
  pvd << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
  std::printf("%6s %10s %14s %16s\n", "frame", "vertices", "rms distance", "max compr. error");
  for (int f = 0; f < frames; ++f)
  {
    const double time = source->GetFrameTime(f);
    tracker->UpdateTimeStep(time); // track frame f (the frames before it are cached)
    const double rms = rootMeanSquare(tracker->GetOutput()->GetPointData()->GetArray("Residual"));
    const long long vertices = tracker->GetOutput()->GetNumberOfPoints();

    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04d.vtp", f);
    writer->SetFileName((output / name).string().c_str());
    // A writer has no output to carry a time request: ask the compressor for the frame, then
    // write (its first call compresses the whole sequence).
    compressor->UpdateTimeStep(time);
    if (writer->Write() != 1)
      return false;
    double range[2];
    compressor->GetOutput()->GetPointData()->GetArray("CompressionError")->GetRange(range);
    pvd << "  <DataSet timestep=\"" << time << "\" file=\"" << name << "\"/>\n";
    std::printf("%6d %10lld %14.4g %16.4g\n", f, vertices, rms, range[1]);
  }
  pvd << "</Collection>\n</VTKFile>\n";
  return true;
}

// The files: a writer compresses the tracked sequence with the same settings (the tracker
// answers every frame from its cache) and writes the format the name's extension says
// (OUTPUT/tracked.dpz and OUTPUT/tracked.glb); false when one could not be written.
bool writeCompressedFiles(vtkDeformableTrackFilter* tracker, double errorTarget,
                          const std::filesystem::path& output)
{
  vtkNew<vtkCompressedSequenceWriter> files;
  files->SetInputConnection(tracker->GetOutputPort());
  files->SetKGTarget(errorTarget);
  for (const char* name : {"tracked.dpz", "tracked.glb"})
  {
    files->SetFileName((output / name).string().c_str());
    if (files->Write() != 1)
      return false; // the writer has reported why
  }
  return true;
}
} // namespace

int main(int argc, char** argv)
{
  if (argc != 3 && argc != 4)
  {
    std::fprintf(stderr, "Usage: TrackAndCompress FOLDER_OR_SERIES OUTPUT_FOLDER [VERTICES]\n");
    return 2;
  }
  const std::filesystem::path output = argv[2];
  std::filesystem::create_directories(output);

  vtkNew<vtkPointSequenceSource> source;
  if (std::filesystem::is_directory(argv[1]))
    source->SetDirectoryName(argv[1]);
  else
    source->SetFileName(argv[1]);
  const int frames = source->GetNumberOfFrames();
  if (frames < 1)
    return 1; // the source has reported why

  vtkNew<vtkDeformableTrackFilter> tracker; // no template given: one is built from frame 0
  tracker->SetInputConnection(source->GetOutputPort());
  tracker->SetTemplateVertices(argc == 4 ? std::stoi(argv[3]) : 1000);

  vtkNew<vtkPCACompressFilter> compressor;
  compressor->SetInputConnection(tracker->GetOutputPort());
  compressor->SetKGTarget(0.2); // Karni-Gotsman error, percent

  std::ofstream pvd(output / "sequence.pvd");
  if (!writeFrames(source, frames, tracker, compressor, output, pvd))
    return 1;
  if (!writeCompressedFiles(tracker, compressor->GetKGTarget(), output))
    return 1;

  vtkFieldData* figures = compressor->GetOutput()->GetFieldData();
  std::printf("compressed %d frames: %g components, %.3g bits per vertex per frame, KG error "
              "%.3g%%\n",
              frames, figures->GetArray("Components")->GetComponent(0, 0),
              figures->GetArray("BitsPerVertexFrame")->GetComponent(0, 0),
              figures->GetArray("KGError")->GetComponent(0, 0));
  return pvd ? 0 : 1;
}
