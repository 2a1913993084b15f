// SPDX-License-Identifier: BSD-3-Clause
// The main job on one input. A point sequence in; out: the tracked mesh sequence (.pvd + .vtp,
// written frame by frame so an interrupted run keeps what it finished), the compressed file
// (.dpz), the glTF animation (.glb) and a report (JSON + PNG plot). The work is done by the
// VTK pipeline vtkPointSequenceSource -> vtkDeformableTrackFilter -> vtkSurfaceDetailFilter (its
// data from a second vtkPointSequenceSource on the same files) -> vtkPCACompressFilter; this
// file only drives it, writes the files and talks to the user (JobSummary.h: the stages' closing
// lines; JobReport.h: the report and the views).
#include "MainJob.h"
#include "JobReport.h"
#include "JobState.h"
#include "JobSummary.h"
#include "MeshFidelity.h"

#include "CommandLine.h"
#include "Console.h"
#include "FrameReport.h"

#include "dp/compress/CompressionOptions.h"
#include "dp/compress/PcaCompression.h"
#include "dp/export/GltfExport.h"
#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/track/FrameFigures.h"
#include "dp/track/TrackerOptionTable.h"

#include "vtkCallbackCommand.h"
#include "vtkCommand.h"
#include "vtkDataArray.h"
#include "vtkDeformableTrackFilter.h"
#include "vtkExecutive.h"
#include "vtkFieldData.h"
#include "vtkNew.h"
#include "vtkPCACompressFilter.h"
#include "vtkPointData.h"
#include "vtkPointSequenceSource.h"
#include "vtkPolyData.h"
#include "vtkStringArray.h"
#include "vtkSurfaceDetailFilter.h"
#include "vtkXMLPolyDataWriter.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <sstream>
#include <unistd.h>
#include <utility>

namespace dp::cli
{

namespace
{
namespace fs = std::filesystem;

// The ParaView collection file listing the frames written so far.
std::string pvdText(const std::vector<std::pair<double, std::string>>& frames)
{
  std::ostringstream s;
  s.precision(17);
  s << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
  for (const auto& [time, file] : frames)
    s << "    <DataSet timestep=\"" << time << "\" part=\"0\" file=\"" << file << "\"/>\n";
  s << "  </Collection>\n</VTKFile>\n";
  return s.str();
}

// The main job, stage by stage; each stage reports its own errors and leaves what it finished.
class MainJob
{
public:
  explicit MainJob(Settings settings)
      : Given(std::move(settings)), Paths(Given.output), Bar(!Given.quiet)
  {
    Printer->ProgressShown = Bar.enabled();
  }

  int run()
  {
    if (!openSequence() || !prepareTracker())
      return 1;
    track();
    if (!Job.failed && !Interrupted)
      compress();
    writeReport(Given, Paths, Job, Source);
    return Interrupted ? 130 : Job.failed ? 1 : 0;
  }

private:
  // VTK messages of `a` go to the printer; its executive's "returned failure" (which only
  // repeats what the algorithm said) is dropped.
  void watch(vtkAlgorithm* a)
  {
    a->AddObserver(vtkCommand::ErrorEvent, Printer);
    a->AddObserver(vtkCommand::WarningEvent, Printer);
    a->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, Quiet);
  }

  bool openSequence()
  {
    watch(Source);
    Job.inputName = Given.input;
    if (Given.input.empty())
    {
      const std::string folder = (Paths.output / "input").string();
      std::cout << "No input given: generating the built-in sample sequence in " << folder << "\n";
      dp::SamplerOptions sampling;
      sampling.pointsPerFrame = 20000;
      sampling.seed = 1;
      Job.inputName = dp::writeSampledSequence(dp::BendingTube(), sampling, folder);
      Source->SetFileName(Job.inputName.c_str());
    }
    else if (fs::is_directory(Given.input))
    {
      Source->SetDirectoryName(Given.input.c_str());
      Source->SetFilePattern(Given.pattern.c_str());
    }
    else
      Source->SetFileName(Given.input.c_str());
    Job.frames = Source->GetNumberOfFrames();
    if (Job.frames < 0)
      return false; // the printer has said why
    if (Given.frames > 0 && Given.frames < Job.frames)
    {
      // Only the first N frames: a .series file listing them with their times, which the
      // source then reads (and the user can see what was tracked).
      nlohmann::json files = nlohmann::json::array();
      for (int f = 0; f < Given.frames; ++f)
        files.push_back({{"name", fs::absolute(Source->GetFramePath(f)).string()},
                         {"time", Source->GetFrameTime(f)}});
      fs::create_directories(Paths.output);
      const fs::path series = Paths.output / "first-frames.series";
      writeAtomically(series,
                      nlohmann::json{{"file-series-version", "1.0"}, {"files", files}}.dump(1));
      Source->SetDirectoryName(nullptr);
      Source->SetFileName(series.string().c_str());
      Job.frames = Source->GetNumberOfFrames();
      if (Job.frames < 0)
        return false;
    }
    std::cout << "Sequence: " << Job.frames << " frame(s) from " << Job.inputName << "\n";
    // The detail layer reads the same frames through a source of its own, so that neither
    // source re-reads a frame the other asked for.
    DataSource->SetFileName(Source->GetFileName());
    DataSource->SetDirectoryName(Source->GetDirectoryName());
    DataSource->SetFilePattern(Source->GetFilePattern());
    return true;
  }

  bool prepareTracker()
  {
    watch(Tracker);
    Tracker->SetInputConnection(Source->GetOutputPort());
    for (const dp::TrackerOptionDescription& option : dp::trackerOptions())
      Tracker->SetTrackerOption(option.name.c_str(), option.get(Given.tracker));
    Tracker->SetTemplateVertices(Given.vertices);
    Tracker->SetTemplateSource(Given.templateFrom);
    if (!Given.templateFile.empty())
    {
      watch(TemplateReader);
      TemplateReader->SetFileName(Given.templateFile.c_str());
      if (TemplateReader->GetNumberOfFrames() < 0)
        return false;
      TemplateReader->Update();
      if (Printer->Errors)
        return false;
      if (TemplateReader->GetOutput()->GetNumberOfPolys() == 0)
      {
        std::cerr << "error: " << Given.templateFile
                  << ": has no polygons, so it cannot be the template mesh\n";
        return false;
      }
      Tracker->SetTemplateConnection(TemplateReader->GetOutputPort());
    }
    TrackProgress->Bar = &Bar;
    Tracker->AddObserver(vtkCommand::ProgressEvent, TrackProgress);
    watch(Detail);
    watch(DataSource);
    Detail->SetInputConnection(0, Tracker->GetOutputPort());
    Detail->SetDataConnection(DataSource->GetOutputPort());
    Detail->SetDetailLevels(Given.detailLevels);
    return true;
  }

  // Says where tracking stopped and which frames are kept.
  void stopAt(int f)
  {
    Bar.clear();
    std::cerr << "error: tracking stopped at frame " << f << " (" << Source->GetFramePath(f)
              << "); ";
    if (f == 0)
      std::cerr << "no frame was tracked\n";
    else
      std::cerr << "frames 0-" << f - 1 << " are in " << Paths.pvd.string() << "\n";
    Job.failed = true;
  }

  // Tracks frame after frame; each finished frame is written and listed in the .pvd at once.
  void track()
  {
    const fs::path folder = clearedFrameFolder();
    vtkNew<vtkXMLPolyDataWriter> writer;
    // Inline data: appended data trips ParaView 5.11's XML readers here
    // (Documentation/Development.md, platform notes).
    writer->SetDataModeToBinary();
    writer->SetCompressorTypeToZLib();
    watch(writer);
    if (!Given.quiet)
      std::printf("%6s %10s %9s %6s %12s %12s %9s %8s %8s\n", "frame", "time", "points", "iter",
                  "rms dist", "max dist", "ms", "far pts%", "bare %");
    for (int f = 0; f < Job.frames && !Interrupted; ++f)
      if (!trackFrame(writer, folder, f))
        break;
    Bar.clear();
    summariseTracking(Paths, Job);
  }

  // Tracks frame f, writes it and adds its line to the table; false when the run stops there
  // (interrupted, or said why).
  bool trackFrame(vtkXMLPolyDataWriter* writer, const fs::path& folder, int f)
  {
    const double time = Source->GetFrameTime(f);
    const int errorsBefore = Printer->Errors;
    TrackProgress->What =
        "tracking frame " + std::to_string(f + 1) + "/" + std::to_string(Job.frames);
    Tracker->UpdateTimeStep(time);
    if (Interrupted)
      return false;
    vtkPolyData* mesh = Tracker->GetOutput();
    // The track filter reads frame f + 1 before it tracks frame f (so that its data is prepared
    // beside the solve): an error with frame f tracked is frame f + 1's, and frame f is kept.
    const bool tracked = mesh->GetNumberOfPoints() > 0 &&
                         Tracker->GetNumberOfCachedFrames() == f + 1 &&
                         fieldValue(mesh, "FrameIndex") == f;
    const bool nextFailed = tracked && Printer->Errors > errorsBefore;
    if (!tracked || (Printer->Errors > errorsBefore && !nextFailed))
    {
      stopAt(f);
      return false;
    }
    if (f == 0)
      describeMesh(mesh);
    vtkPolyData* detailed = detailOf(f, time);
    if (!detailed)
    {
      stopAt(f);
      return false;
    }
    if (!writeFrame(writer, folder, f, time, detailed))
      return false;
    record(f, time, mesh, fieldValue(detailed, "DetailSeconds"));
    if (nextFailed)
    {
      stopAt(f + 1);
      return false;
    }
    return true;
  }

  // Frame f's detail layer (the tracked mesh itself with none), or null when it failed (the
  // printer has said why). The first frame's says what was chosen.
  vtkPolyData* detailOf(int f, double time)
  {
    const int errorsBefore = Printer->Errors;
    Detail->UpdateTimeStep(time);
    vtkPolyData* detailed = Detail->GetOutput();
    if (Printer->Errors > errorsBefore || detailed->GetNumberOfPoints() == 0)
      return nullptr;
    if (f == 0)
      describeDetail(detailed);
    return detailed;
  }

  // The detail layer chosen, from its first frame, for the summary and the report.
  void describeDetail(vtkPolyData* detailed)
  {
    Job.detailLevels = Detail->GetLevelsUsed();
    Job.fineVertices = detailed->GetNumberOfPoints();
    auto* choice =
        vtkStringArray::SafeDownCast(detailed->GetFieldData()->GetAbstractArray("DetailChoice"));
    Job.detailChoice =
        choice && choice->GetNumberOfValues() > 0 ? choice->GetValue(0) : std::string();
    if (!Given.quiet)
    {
      Bar.clear();
      std::printf("Detail: %s\n", Job.detailChoice.c_str());
    }
  }

  // OUTPUT/tracked, without a previous run's frames.
  fs::path clearedFrameFolder() const
  {
    const fs::path folder = Paths.output / "tracked";
    fs::create_directories(folder);
    for (const auto& entry : fs::directory_iterator(folder))
      if (entry.path().extension() == ".vtp" || entry.path().extension() == ".partial")
        fs::remove(entry.path());
    return folder;
  }

  // The tracked mesh's size, from its first frame, for the summary and the report.
  void describeMesh(vtkPolyData* mesh)
  {
    double b[6];
    mesh->GetBounds(b);
    Job.diagonal = std::sqrt((b[1] - b[0]) * (b[1] - b[0]) + (b[3] - b[2]) * (b[3] - b[2]) +
                             (b[5] - b[4]) * (b[5] - b[4]));
    Job.meshVertices = mesh->GetNumberOfPoints();
    Job.meshTriangles = mesh->GetNumberOfPolys();
    auto* made = vtkStringArray::SafeDownCast(mesh->GetFieldData()->GetAbstractArray("Template"));
    Job.templateMade = made && made->GetNumberOfValues() > 0 ? made->GetValue(0) : std::string();
    if (!Job.templateMade.empty() && !Given.quiet)
    {
      Bar.clear();
      std::printf("Template: %s\n", Job.templateMade.c_str());
    }
  }

  // Writes frame f (beside its name, renamed when complete) and lists it in the .pvd; false,
  // said on stderr, when it cannot be written.
  bool writeFrame(vtkXMLPolyDataWriter* writer, const fs::path& folder, int f, double time,
                  vtkPolyData* mesh)
  {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04d.vtp", f);
    const fs::path file = folder / name;
    const std::string partial = file.string() + ".partial";
    // The frame's data samples are for the compressor (DISTANCE_TO_DATA), not the file.
    vtkNew<vtkPolyData> written;
    written->ShallowCopy(mesh);
    vtkNew<vtkFieldData> fields;
    fields->DeepCopy(mesh->GetFieldData());
    fields->RemoveArray("DataSamples");
    fields->RemoveArray("DataReach");
    written->SetFieldData(fields);
    writer->SetInputData(written);
    writer->SetFileName(partial.c_str());
    if (!writer->Write())
    {
      Bar.clear();
      std::cerr << "error: " << file.string() << ": cannot write\n";
      Job.failed = true;
      return false;
    }
    fs::rename(partial, file);
    Job.written.emplace_back(time, (fs::path("tracked") / name).string());
    writeAtomically(Paths.pvd, pvdText(Job.written));
    return true;
  }

  // The frame's line of the table and of the report.
  void record(int f, double time, vtkPolyData* mesh, double detailSeconds)
  {
    vtkDataArray* residual = mesh->GetPointData()->GetArray("Residual");
    double sum = 0, largest = 0;
    for (vtkIdType i = 0; residual && i < residual->GetNumberOfTuples(); ++i)
    {
      const double r = residual->GetComponent(i, 0);
      sum += r * r;
      largest = std::max(largest, r);
    }
    const double n = std::max<double>(1, static_cast<double>(mesh->GetNumberOfPoints()));
    const FrameRecord r{f,
                        time,
                        std::sqrt(sum / n),
                        largest,
                        figuresOf(mesh),
                        std::isfinite(detailSeconds) ? detailSeconds : 0.0};
    Job.records.push_back(r);
    if (!Given.quiet)
    {
      Bar.clear();
      const dp::FrameFigures& g = r.figures;
      std::printf("%6d %10.4g %9.0f %6.0f %12.4g %12.4g %9.1f %8.2f %8.2f%s\n", f, time, g.points,
                  g.iterations, r.rmsResidual, r.maxResidual, r.milliseconds(), 100 * g.unexplained,
                  100 * g.unsupported, r.failed() ? "  FAILED" : "");
      std::fflush(stdout);
    }
  }

  // The codec's target: by default the data's (--fit-growth: the decompressed mesh's distance to
  // the points may grow by that percent, DISTANCE_TO_DATA), else KG (--error-target); through
  // vtkPCACompressFilter as any VTK pipeline would.
  void compress()
  {
    vtkNew<vtkPCACompressFilter> compressor;
    watch(compressor);
    compressor->SetInputConnection(Detail->GetOutputPort());
    compressor->SetCompressionOptions(Given.compression);
    vtkNew<ProgressWatcher> progress;
    progress->Bar = &Bar;
    progress->What = "compressing";
    compressor->AddObserver(vtkCommand::ProgressEvent, progress);
    const int errorsBefore = Printer->Errors;
    compressor->Update();
    Bar.clear();
    if (Interrupted)
    {
      std::cerr << "interrupted while compressing: the tracked frames are in " << Paths.pvd.string()
                << "\n";
      return;
    }
    const dp::CompressedSequence* sequence = compressor->GetCompressedSequence();
    if (Printer->Errors > errorsBefore || !sequence)
    {
      std::cerr << "error: compression failed; the tracked frames are in " << Paths.pvd.string()
                << "\n";
      Job.failed = true;
      return;
    }
    if (!writeCompressed(*sequence))
      return;
    sayCompression(compressor->GetOutput(), *sequence, Given.compression, Paths, Job);
    sayAgainstInputMeshes(*sequence);
    sayGlb(Paths, Job);
  }

  // Per-frame mesh input: each decompressed frame against the frame's own mesh, as
  // volumetric-video codecs are measured (report.json's compression.againstInputMeshes).
  void sayAgainstInputMeshes(const dp::CompressedSequence& sequence)
  {
    std::vector<std::string> paths;
    for (int f = 0; f < Job.frames; ++f)
      paths.emplace_back(Source->GetFramePath(f));
    nlohmann::json m;
    try
    {
      m = measureAgainstInputMeshes(
          sequence, paths, fs::file_size(Paths.dpz),
          [this](std::size_t t)
          { Bar.show("measuring against input", static_cast<double>(t + 1) / Job.frames); });
      Bar.clear();
    }
    catch (const std::exception& e)
    {
      Bar.clear();
      std::cerr << "warning: the decompressed frames were not measured against the input "
                   "meshes: "
                << e.what() << "\n";
      return;
    }
    if (m.is_null())
      return;
    Job.compression["againstInputMeshes"] = m;
    std::printf("Against the input meshes: D1 PSNR %.1f dB, D2 PSNR %.1f dB (means over the "
                "frames; worst frame %.1f and %.1f dB; peak: each frame's diagonal), %.3g bits "
                "per input vertex per frame (%.3g without the colour)\n",
                m["d1PsnrDb"].get<double>(), m["d2PsnrDb"].get<double>(),
                m["worstD1PsnrDb"].get<double>(), m["worstD2PsnrDb"].get<double>(),
                m["bitsPerInputVertexFrame"].get<double>(),
                m["geometryBitsPerInputVertexFrame"].get<double>());
  }

  /** Writes tracked.dpz and tracked.glb (each beside its name, renamed when complete); says
   *  which failed and why. */
  bool writeCompressed(const dp::CompressedSequence& sequence)
  {
    try
    {
      dp::writeCompressedSequence(Paths.dpz.string(), sequence);
      dp::GlbOptions glb;
      glb.meshopt = Given.meshopt;
      Job.glbWritten = dp::writeGlb(Paths.glb.string(), sequence, glb);
      if (Given.view)
        keepPageGlb(sequence);
      Job.compression["glb"] = {{"detailLevel", Job.glbWritten.level},
                                {"vertices", Job.glbWritten.vertices},
                                {"morphTargetShapes", Job.glbWritten.shapes},
                                {"bytes", fs::file_size(Paths.glb)}};
      return true;
    }
    catch (const std::exception& e)
    {
      std::cerr << "error: " << e.what() << "; the tracked frames are in " << Paths.pvd.string()
                << "\n";
      Job.failed = true;
      return false;
    }
  }

  // The plain .glb the page plays (the meshopt variant is for viewers that decode it).
  void keepPageGlb(const dp::CompressedSequence& sequence)
  {
    fs::path plain = Paths.glb;
    if (Given.meshopt)
    {
      plain = Paths.output / "view.glb.partial";
      dp::writeGlb(plain.string(), sequence);
    }
    std::ifstream in(plain, std::ios::binary);
    Job.pageGlb.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (Given.meshopt)
      fs::remove(plain);
  }

  const Settings Given; // what the command line asked
  const JobPaths Paths;
  JobState Job;
  vtkNew<MessagePrinter> Printer;
  vtkNew<vtkCallbackCommand> Quiet;
  ProgressBar Bar;
  vtkNew<vtkPointSequenceSource> Source;
  vtkNew<vtkPointSequenceSource> TemplateReader;
  vtkNew<vtkDeformableTrackFilter> Tracker;
  vtkNew<ProgressWatcher> TrackProgress;
  vtkNew<vtkPointSequenceSource> DataSource;
  vtkNew<vtkSurfaceDetailFilter> Detail;
};

} // namespace

int runJob(const Settings& settings)
{
  try
  {
    return MainJob(settings).run();
  }
  catch (const std::exception& e)
  {
    std::cerr << "dynamicpoints: error: " << (settings.input.empty() ? "" : settings.input + ": ")
              << e.what() << "\n";
    return 1;
  }
}

} // namespace dp::cli
