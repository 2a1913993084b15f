// SPDX-License-Identifier: BSD-3-Clause
// The main job on one input. A point sequence in; out: the tracked mesh sequence (.pvd + .vtp,
// written frame by frame so an interrupted run keeps what it finished), the compressed file
// (.dpz), the glTF animation (.glb) and a report (JSON + PNG plot). The work is done by the
// VTK pipeline vtkPointSequenceSource -> vtkDeformableTrackFilter -> vtkSurfaceDetailFilter (its
// data from a second vtkPointSequenceSource on the same files) -> vtkPCACompressFilter; this
// file only drives it, writes the files and talks to the user.
#include "MainJob.h"
#include "MeshFidelity.h"
#include "Viewer.h"

#include "CommandLine.h"
#include "Console.h"
#include "FrameReport.h"

#include "dp/compress/CompressionFigures.h"
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
#include <chrono>
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
      : S(std::move(settings)), Output(S.output), Pvd(Output / "tracked.pvd"),
        Dpz(Output / "tracked.dpz"), Glb(Output / "tracked.glb"), Page(Output / "view.html"),
        State(Output / "paraview-state.py"), Bar(!S.quiet)
  {
    Printer->ProgressShown = Bar.enabled();
  }

  int run()
  {
    if (!openSequence() || !prepareTracker())
      return 1;
    track();
    if (!Failed && !Interrupted)
      compress();
    writeReport();
    return Interrupted ? 130 : Failed ? 1 : 0;
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
    InputName = S.input;
    if (S.input.empty())
    {
      const std::string folder = (Output / "input").string();
      std::cout << "No input given: generating the built-in sample sequence in " << folder << "\n";
      dp::SamplerOptions sampling;
      sampling.pointsPerFrame = 20000;
      sampling.seed = 1;
      InputName = dp::writeSampledSequence(dp::BendingTube(), sampling, folder);
      Source->SetFileName(InputName.c_str());
    }
    else if (fs::is_directory(S.input))
    {
      Source->SetDirectoryName(S.input.c_str());
      Source->SetFilePattern(S.pattern.c_str());
    }
    else
      Source->SetFileName(S.input.c_str());
    Frames = Source->GetNumberOfFrames();
    if (Frames < 0)
      return false; // the printer has said why
    if (S.frames > 0 && S.frames < Frames)
    {
      // Only the first N frames: a .series file listing them with their times, which the
      // source then reads (and the user can see what was tracked).
      nlohmann::json files = nlohmann::json::array();
      for (int f = 0; f < S.frames; ++f)
        files.push_back({{"name", fs::absolute(Source->GetFramePath(f)).string()},
                         {"time", Source->GetFrameTime(f)}});
      fs::create_directories(Output);
      const fs::path series = Output / "first-frames.series";
      writeAtomically(series,
                      nlohmann::json{{"file-series-version", "1.0"}, {"files", files}}.dump(1));
      Source->SetDirectoryName(nullptr);
      Source->SetFileName(series.string().c_str());
      Frames = Source->GetNumberOfFrames();
      if (Frames < 0)
        return false;
    }
    std::cout << "Sequence: " << Frames << " frame(s) from " << InputName << "\n";
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
      Tracker->SetTrackerOption(option.name.c_str(), option.get(S.tracker));
    Tracker->SetTemplateVertices(S.vertices);
    Tracker->SetTemplateSource(S.templateFrom);
    if (!S.templateFile.empty())
    {
      watch(TemplateReader);
      TemplateReader->SetFileName(S.templateFile.c_str());
      if (TemplateReader->GetNumberOfFrames() < 0)
        return false;
      TemplateReader->Update();
      if (Printer->Errors)
        return false;
      if (TemplateReader->GetOutput()->GetNumberOfPolys() == 0)
      {
        std::cerr << "error: " << S.templateFile
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
    Detail->SetDetailLevels(S.detailLevels);
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
      std::cerr << "frames 0-" << f - 1 << " are in " << Pvd.string() << "\n";
    Failed = true;
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
    if (!S.quiet)
      std::printf("%6s %10s %9s %6s %12s %12s %9s %8s %8s\n", "frame", "time", "points", "iter",
                  "rms dist", "max dist", "ms", "far pts%", "bare %");
    for (int f = 0; f < Frames && !Interrupted; ++f)
    {
      const double time = Source->GetFrameTime(f);
      const int errorsBefore = Printer->Errors;
      TrackProgress->What =
          "tracking frame " + std::to_string(f + 1) + "/" + std::to_string(Frames);
      Tracker->UpdateTimeStep(time);
      if (Interrupted)
        break;
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
        break;
      }
      if (f == 0)
        describeMesh(mesh);
      vtkPolyData* detailed = detailOf(f, time);
      if (!detailed)
      {
        stopAt(f);
        break;
      }
      if (!writeFrame(writer, folder, f, time, detailed))
        break;
      record(f, time, mesh, fieldValue(detailed, "DetailSeconds"));
      if (nextFailed)
      {
        stopAt(f + 1);
        break;
      }
    }
    Bar.clear();
    summariseTracking();
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
    DetailLevels = Detail->GetLevelsUsed();
    FineVertices = detailed->GetNumberOfPoints();
    auto* choice =
        vtkStringArray::SafeDownCast(detailed->GetFieldData()->GetAbstractArray("DetailChoice"));
    DetailChoice = choice && choice->GetNumberOfValues() > 0 ? choice->GetValue(0) : std::string();
    if (!S.quiet)
    {
      Bar.clear();
      std::printf("Detail: %s\n", DetailChoice.c_str());
    }
  }

  // OUTPUT/tracked, without a previous run's frames.
  fs::path clearedFrameFolder() const
  {
    const fs::path folder = Output / "tracked";
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
    Diagonal = std::sqrt((b[1] - b[0]) * (b[1] - b[0]) + (b[3] - b[2]) * (b[3] - b[2]) +
                         (b[5] - b[4]) * (b[5] - b[4]));
    MeshVertices = mesh->GetNumberOfPoints();
    MeshTriangles = mesh->GetNumberOfPolys();
    auto* made = vtkStringArray::SafeDownCast(mesh->GetFieldData()->GetAbstractArray("Template"));
    TemplateMade = made && made->GetNumberOfValues() > 0 ? made->GetValue(0) : std::string();
    if (!TemplateMade.empty() && !S.quiet)
    {
      Bar.clear();
      std::printf("Template: %s\n", TemplateMade.c_str());
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
      Failed = true;
      return false;
    }
    fs::rename(partial, file);
    Written.emplace_back(time, (fs::path("tracked") / name).string());
    writeAtomically(Pvd, pvdText(Written));
    return true;
  }

  // What was tracked, and a warning naming the frames that failed.
  void summariseTracking() const
  {
    if (Interrupted)
      std::cerr << "interrupted: " << Written.size() << " of " << Frames << " frame(s) tracked, in "
                << Pvd.string() << "; nothing compressed\n";
    else if (DetailLevels > 0)
      std::cout << Written.size() << " of " << Frames << " frame(s) tracked: " << Pvd.string()
                << " (" << FineVertices << " vertices: " << DetailLevels
                << " level(s) of detail over the tracked mesh's " << MeshVertices << ")\n";
    else
      std::cout << Written.size() << " of " << Frames << " frame(s) tracked: " << Pvd.string()
                << " (" << MeshVertices << " vertices, " << MeshTriangles << " triangles)\n";
    std::string failed;
    for (const FrameRecord& r : Records)
      if (r.failed())
        failed += (failed.empty() ? "" : ", ") + std::to_string(r.frame);
    if (!failed.empty())
      std::cerr << "warning: frame(s) " << failed
                << " failed after retries (mesh and points do not match there): do not trust "
                   "them; report.json and report.png mark them\n";
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
    Records.push_back(r);
    if (!S.quiet)
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
    const bool againstData = S.compression.measure == dp::CompressionMeasure::DistanceToData;
    vtkNew<vtkPCACompressFilter> compressor;
    watch(compressor);
    compressor->SetInputConnection(Detail->GetOutputPort());
    compressor->SetCompressionOptions(S.compression);
    vtkNew<ProgressWatcher> progress;
    progress->Bar = &Bar;
    progress->What = "compressing";
    compressor->AddObserver(vtkCommand::ProgressEvent, progress);
    const int errorsBefore = Printer->Errors;
    compressor->Update();
    Bar.clear();
    if (Interrupted)
    {
      std::cerr << "interrupted while compressing: the tracked frames are in " << Pvd.string()
                << "\n";
      return;
    }
    const dp::CompressedSequence* sequence = compressor->GetCompressedSequence();
    if (Printer->Errors > errorsBefore || !sequence)
    {
      std::cerr << "error: compression failed; the tracked frames are in " << Pvd.string() << "\n";
      Failed = true;
      return;
    }
    if (!writeCompressed(*sequence))
      return;
    recordCompression(compressor->GetOutput());
    if (DetailLevels > 0)
      sayDetail(compressor->GetOutput(), *sequence);
    if (againstData)
      sayDataFit(compressor->GetOutput());
    else
      sayMotionFit(*sequence);
    sayAgainstInputMeshes(*sequence);
    sayGlb();
  }

  // What the .glb holds: the tracked mesh, or a level of the detail layer.
  void sayGlb() const
  {
    if (GlbWritten.level == 0)
      std::printf("glTF: %s (the tracked mesh, %zu morph targets)\n", Glb.string().c_str(),
                  GlbWritten.shapes);
    else
      std::printf("glTF: %s (detail level %d of %d: %zu vertices, %zu morph targets, %.1f MB)\n",
                  Glb.string().c_str(), GlbWritten.level, DetailLevels, GlbWritten.vertices,
                  GlbWritten.shapes, static_cast<double>(fs::file_size(Glb)) / 1e6);
  }

  // The detail layer's share of the file and what it costs in fit.
  void sayDetail(vtkPolyData* result, const dp::CompressedSequence& sequence)
  {
    nlohmann::json d = {{"levels", DetailLevels},
                        {"bytes", sequence.report.detailBytes},
                        {"step", sequence.detail.step},
                        {"fineVertices", FineVertices}};
    const double before = fieldValue(result, "DetailDistanceToDataInput");
    const double after = fieldValue(result, "DetailDistanceToDataDecompressed");
    if (std::isfinite(before))
    {
      d["distanceToPointsFitted"] = before;
      d["distanceToPointsDecompressed"] = after;
      d["fitGrowthPercent"] = fieldValue(result, "DetailDistanceToDataGrowth");
    }
    Compression["detail"] = d;
    std::printf(
        "Detail layer: %zu of the file's %lld bytes (%d level(s), %lld vertices, step %.3g)",
        sequence.report.detailBytes, static_cast<long long>(fs::file_size(Dpz)), DetailLevels,
        FineVertices, sequence.detail.step);
    if (std::isfinite(before))
      std::printf("; the decompressed fine mesh lies %.3g from the points (RMS), the fitted one "
                  "%.3g (%+.1f %%)",
                  after, before, d["fitGrowthPercent"].get<double>());
    std::printf("\n");
  }

  // Per-frame mesh input: each decompressed frame against the frame's own mesh, as
  // volumetric-video codecs are measured (report.json's compression.againstInputMeshes).
  void sayAgainstInputMeshes(const dp::CompressedSequence& sequence)
  {
    std::vector<std::string> paths;
    for (int f = 0; f < Frames; ++f)
      paths.emplace_back(Source->GetFramePath(f));
    nlohmann::json m;
    try
    {
      m = measureAgainstInputMeshes(
          sequence, paths, fs::file_size(Dpz),
          [this](std::size_t t)
          { Bar.show("measuring against input", static_cast<double>(t + 1) / Frames); });
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
    Compression["againstInputMeshes"] = m;
    std::printf("Against the input meshes: D1 PSNR %.1f dB, D2 PSNR %.1f dB (means over the "
                "frames; worst frame %.1f and %.1f dB; peak: each frame's diagonal), %.3g bits "
                "per input vertex per frame (%.3g without the colour)\n",
                m["d1PsnrDb"].get<double>(), m["d2PsnrDb"].get<double>(),
                m["worstD1PsnrDb"].get<double>(), m["worstD2PsnrDb"].get<double>(),
                m["bitsPerInputVertexFrame"].get<double>(),
                m["geometryBitsPerInputVertexFrame"].get<double>());
  }

  // The codec's figures in report.json's "compression": each of dp::CompressionFigures the
  // filter's output carries, by its name.
  void recordCompression(vtkPolyData* result)
  {
    for (const dp::CompressionFigures::Field& field : dp::CompressionFigures::fields())
    {
      const double value = fieldValue(result, field.name);
      if (!std::isnan(value))
        Compression[field.name] =
            field.count ? nlohmann::json(std::llround(value)) : nlohmann::json(value);
    }
    // The input as raw points: float32 x y z, and r g b bytes where the file keeps colour.
    const double bytesPerPoint = Compression.contains("ColourBytes") ? 15.0 : 12.0;
    double rawBytes = 0;
    for (const FrameRecord& r : Records)
      rawBytes += bytesPerPoint * r.figures.points;
    Compression["Bytes"] = fs::file_size(Dpz);
    Compression["InputPointBytes"] = rawBytes;
    Compression["InputPointsOverFile"] = rawBytes / static_cast<double>(fs::file_size(Dpz));
  }

  // The compressed file's name for the "Compressed:" line, with its colour's share when it has
  // colour.
  std::string dpzSaid() const
  {
    if (!Compression.contains("ColourBytes"))
      return Dpz.string();
    return Dpz.string() +
           " (with colour: " + std::to_string(Compression["ColourBytes"].get<long long>()) +
           " of its " + std::to_string(Compression["Bytes"].get<long long>()) + " bytes, " +
           (S.compression.colourTolerance > 0
                ? "within " + std::to_string(S.compression.colourTolerance) + " levels"
                : std::string("lossless")) +
           ")";
  }

  void sayDataFit(vtkPolyData* result)
  {
    const double before = fieldValue(result, "DistanceToDataInput");
    const double after = fieldValue(result, "DistanceToDataDecompressed");
    const double growth = fieldValue(result, "DistanceToDataGrowth");
    Compression["Target"] = dp::targetSaid(S.compression);
    Compression["FitGrowthAllowedPercent"] = S.compression.fitGrowth;
    Compression["DistanceToPointsTracked"] = before;
    Compression["DistanceToPointsDecompressed"] = after;
    Compression["FitGrowthPercent"] = growth;
    std::printf("Compressed: %s, %.0f components, %.3g bits per vertex per frame, %.0fx smaller "
                "than the input points (float32 x y z%s); the decompressed mesh lies %.3g from "
                "the points (RMS), the tracked one %.3g (%+.1f %%, at most %g %%)\n",
                dpzSaid().c_str(), Compression["Components"].get<double>(),
                Compression["BitsPerVertexFrame"].get<double>(),
                Compression["InputPointsOverFile"].get<double>(),
                Compression.contains("ColourBytes") ? ", r g b bytes" : "", after, before, growth,
                S.compression.fitGrowth);
  }

  void sayMotionFit(const dp::CompressedSequence& sequence)
  {
    const bool weak = Written.size() >= 8 && Compression["ComponentsPerFrame"].get<double>() > 0.5;
    Compression["weak"] = weak;
    if (weak)
      Compression["note"] = "most of the frames' worth of components were kept: the motion is "
                            "not low-rank, the tracking shakes, or the KG target asks for more "
                            "than the data's noise (the default target is the data's)";
    Compression["Target"] = dp::targetSaid(S.compression);
    std::printf("Compressed: %s, %zu components, %.3g bits per vertex per frame (%.1fx "
                "smaller than float32), KG error %.3g%%\n",
                dpzSaid().c_str(), sequence.report.components, sequence.report.bitsPerVertexFrame,
                96.0 / sequence.report.bitsPerVertexFrame, sequence.report.kgError);
    if (weak)
      std::printf("Compression is weak: %zu components for %zu frames (the motion is not "
                  "low-rank, the tracking shakes, or %s asks for more than the data's noise: "
                  "without --error-target the target is the data's)\n",
                  sequence.report.components, Written.size(),
                  dp::targetSaid(S.compression).c_str());
  }

  /** Writes tracked.dpz and tracked.glb (each beside its name, renamed when complete); says
   *  which failed and why. */
  bool writeCompressed(const dp::CompressedSequence& sequence)
  {
    try
    {
      dp::writeCompressedSequence(Dpz.string(), sequence);
      dp::GlbOptions glb;
      glb.meshopt = S.meshopt;
      GlbWritten = dp::writeGlb(Glb.string(), sequence, glb);
      if (S.view)
        keepPageGlb(sequence);
      Compression["glb"] = {{"detailLevel", GlbWritten.level},
                            {"vertices", GlbWritten.vertices},
                            {"morphTargetShapes", GlbWritten.shapes},
                            {"bytes", fs::file_size(Glb)}};
      return true;
    }
    catch (const std::exception& e)
    {
      std::cerr << "error: " << e.what() << "; the tracked frames are in " << Pvd.string() << "\n";
      Failed = true;
      return false;
    }
  }

  // The plain .glb the page plays (the meshopt variant is for viewers that decode it).
  void keepPageGlb(const dp::CompressedSequence& sequence)
  {
    fs::path plain = Glb;
    if (S.meshopt)
    {
      plain = Output / "view.glb.partial";
      dp::writeGlb(plain.string(), sequence);
    }
    std::ifstream in(plain, std::ios::binary);
    PageGlb.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (S.meshopt)
      fs::remove(plain);
  }

  // The options the run used, by the names --set and --options take (the tables'), and the
  // main job's own.
  nlohmann::json optionsJson() const
  {
    return {
        {"tracker", nlohmann::json::parse(dp::trackerOptions().valuesJson(S.tracker))},
        {"compression", nlohmann::json::parse(dp::compressionOptions().valuesJson(S.compression))},
        {"vertices", S.vertices},
        {"templateFrom", S.templateFrom == vtkDeformableTrackFilter::TEMPLATE_FROM_MESH ? "mesh"
                         : S.templateFrom == vtkDeformableTrackFilter::TEMPLATE_FROM_POINTS
                             ? "points"
                             : "auto"},
        {"detailLevels",
         S.detailLevels < 0 ? nlohmann::json("auto") : nlohmann::json(S.detailLevels)},
        {"frames", S.frames > 0 ? nlohmann::json(S.frames) : nlohmann::json("all")}};
  }

  // report.json and report.png.
  void writeReport() const
  {
    nlohmann::json report;
    report["input"] = InputName;
    report["frames"] = Frames;
    report["framesTracked"] = Written.size();
    report["interrupted"] = Interrupted != 0;
    report["template"] = {{"source", S.templateFile.empty() ? "frame 0" : S.templateFile},
                          {"made", TemplateMade},
                          {"vertices", MeshVertices},
                          {"triangles", MeshTriangles}};
    report["detail"] = {
        {"levels", DetailLevels},
        {"asked", S.detailLevels < 0 ? std::string("automatic") : std::to_string(S.detailLevels)},
        {"choice", DetailChoice},
        {"fineVertices", DetailLevels > 0 ? FineVertices : MeshVertices}};
    report["boundingBoxDiagonal"] = Diagonal;
    report["options"] = optionsJson();
    nlohmann::json perFrame = nlohmann::json::array(), failedFrames = nlohmann::json::array();
    std::vector<double> ms;
    int retried = 0;
    for (const FrameRecord& r : Records)
    {
      perFrame.push_back(frameJson(r));
      retried += r.figures.retries > 0 ? 1 : 0;
      if (r.failed())
        failedFrames.push_back(r.frame);
      ms.push_back(r.milliseconds());
    }
    report["perFrame"] = perFrame;
    report["framesRetried"] = retried;
    report["framesFailed"] = failedFrames;
    report["medianMillisecondsPerFrame"] = medianOf(ms);
    report["medianStageSecondsPerFrame"] = stageMediansJson(Records);
    const fs::path plot = Output / "report.png";
    nlohmann::json outputs = {{"tracked", Pvd.string()}, {"plot", plot.string()}};
    if (!Compression.empty())
    {
      report["compression"] = Compression;
      outputs["compressed"] = Dpz.string();
      outputs["gltf"] = Glb.string();
    }
    const bool viewed = S.view && !Records.empty();
    if (viewed)
    {
      outputs["paraviewState"] = State.string();
      if (!PageGlb.empty() && viewerAvailable())
        outputs["page"] = Page.string();
    }
    report["outputs"] = outputs;
    report["wallSeconds"] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - Started).count();
    writeAtomically(Output / "report.json", report.dump(1) + "\n");
    writeReportPlot(plot.string(), "DynamicPoints: " + fs::path(InputName).filename().string(),
                    Records, Diagonal);
    std::cout << "Report: " << (Output / "report.json").string() << ", " << plot.string() << "\n";
    if (viewed)
      writeViews(report);
  }

  // The page (view.html: the take in any browser) and the ParaView state, each named on a line
  // of its own, the last lines of the job; a failure is said and changes nothing else.
  void writeViews(const nlohmann::json& report) const
  {
    try
    {
      StateInputs state;
      state.tracked = fs::absolute(Pvd).string();
      state.points = fs::absolute(Source->GetDirectoryName() ? Source->GetDirectoryName()
                                                             : Source->GetFileName())
                         .string();
      state.pattern = Source->GetDirectoryName() ? S.pattern : std::string();
      state.plugin = pluginPath();
      state.largestResidual = Records.front().maxResidual;
      writeParaViewState(State.string(), state);
      if (!PageGlb.empty() && viewerAvailable())
      {
        writeViewerPage(Page.string(), PageGlb, report);
        std::cout << "Page: " << Page.string()
                  << " (the take in a browser, from the file system)\n";
      }
      else if (!PageGlb.empty())
        std::cerr << "warning: no view.html: this build of dynamicpoints has no three.js "
                     "(Utilities/dp.sh installs it from npm)\n";
      std::cout << "ParaView: paraview --state=" << State.string() << "\n";
    }
    catch (const std::exception& e)
    {
      std::cerr << "warning: " << e.what() << "\n";
    }
  }

  // The DynamicPoints ParaView plugin beside this program's build or install
  // (bin/../lib/paraview-plugins/DynamicPoints/DynamicPoints.so), empty when there is none.
  static std::string pluginPath()
  {
    std::error_code error;
    const fs::path self = fs::read_symlink("/proc/self/exe", error);
    const fs::path plugin = self.parent_path().parent_path() / "lib" / "paraview-plugins" /
                            "DynamicPoints" / "DynamicPoints.so";
    return !error && fs::exists(plugin) ? plugin.string() : std::string();
  }

  const Settings S;
  const fs::path Output, Pvd, Dpz, Glb, Page, State;
  const std::chrono::steady_clock::time_point Started = std::chrono::steady_clock::now();
  vtkNew<MessagePrinter> Printer;
  vtkNew<vtkCallbackCommand> Quiet;
  ProgressBar Bar;
  vtkNew<vtkPointSequenceSource> Source;
  vtkNew<vtkPointSequenceSource> TemplateReader;
  vtkNew<vtkDeformableTrackFilter> Tracker;
  vtkNew<ProgressWatcher> TrackProgress;
  vtkNew<vtkPointSequenceSource> DataSource;
  vtkNew<vtkSurfaceDetailFilter> Detail;

  std::string InputName;
  int Frames = 0;
  bool Failed = false;
  std::vector<std::pair<double, std::string>> Written; // (time, file) of each frame written
  std::vector<FrameRecord> Records;
  double Diagonal = 0;
  long long MeshVertices = 0, MeshTriangles = 0;
  std::string TemplateMade; // what the template was made from, and how
  int DetailLevels = 0;
  long long FineVertices = 0;
  std::string DetailChoice; // what the detail layer's levels were chosen from
  dp::GlbSummary GlbWritten;
  std::vector<unsigned char> PageGlb; // the plain .glb's bytes, for the page
  nlohmann::json Compression;
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
