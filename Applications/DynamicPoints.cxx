// SPDX-License-Identifier: BSD-3-Clause
// dynamicpoints: the main job. A point sequence in; out: the tracked mesh sequence (.pvd + .vtp,
// written frame by frame so an interrupted run keeps what it finished), the compressed file
// (.dpz), the glTF animation (.glb) and a report (JSON + PNG plot). The work is done by the
// VTK pipeline vtkPointSequenceSource -> vtkDeformableTrackFilter -> vtkPCACompressFilter;
// this file only drives it, writes the files and talks to the user.
#include "Batch.h"
#include "CommandLine.h"
#include "FramePlot.h"
#include "TrackerOptionFlags.h"

#include "dp/compress/PcaCompression.h"
#include "dp/export/GltfExport.h"
#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/track/FrameFigures.h"

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
#include <sstream>
#include <unistd.h>
#include <utility>

namespace
{
namespace fs = std::filesystem;

const char* const Usage = R"(Usage: dynamicpoints [OPTIONS] [INPUT ...]

Turns a time series of point clouds into one deforming triangle mesh of fixed
connectivity, tracked frame by frame; then compresses it and writes it for ParaView, VTK
and glTF viewers.

INPUT is a folder of point files (one per frame), a ParaView .series file, or one point
file. Readable: .ply .pcd .xyz .pts .csv .txt .obj .vtp .vtu .vtk.
Without INPUT, the built-in sample sequence is generated first: a bending, twisting tube,
30 frames of 20000 random surface points with normals, written to OUTPUT/input/.
With several INPUTs (a batch of takes), each is done as alone into OUTPUT/<name>/ (its
folder's name; a .series file's folder's; a file's stem), and OUTPUT/batch.json says how
each ended. Started by mpirun (mpirun -np N dynamicpoints ...), the inputs are spread over
the N processes, largest first; each input's files are the same as from one process.

Written to OUTPUT:
  tracked.pvd, tracked/*.vtp  the tracked mesh, one file per frame (open the .pvd in
                              ParaView); brought up to date after every frame; where the
                              points carry colour, each vertex's colour (Colors)
  tracked.dpz                 the compressed sequence (ParaView or vtkCompressedSequenceReader),
                              as close to the points as --fit-growth allows
  tracked.glb                 glTF 2.0 animation: morph targets, 24 frames per second
  report.json, report.png     per frame: distance to the points, quality (share of the
                              points far from the mesh and of the mesh far from the
                              points; frames retried and failed), time; compression

Options:
  --pattern GLOB      files of an INPUT folder to read (default: *)
  --template FILE     mesh to deform (.ply .obj .vtp .vtk ...), repaired if it must be
                      (what was done is said), never remeshed; default: made from the
                      first frame (--template-from)
  --template-from S   auto (default): the first frame's mesh when its file has polygons
                      (a capture's per-frame mesh: repaired and remeshed to --vertices),
                      else a surface reconstructed from its points; mesh; points
  --vertices N        vertex count of a template made from the first frame (default: 1000)
  --frames N          track only the first N frames (default: all; they are listed
                      with their times in OUTPUT/first-frames.series)
  --fit-growth P      compression judged against the data (default): the decompressed
                      mesh's RMS distance to the points may grow by at most P percent
                      over the tracked mesh's (default: 10)
  --error-target KG   compression judged against the motion instead: Karni-Gotsman error
                      in percent (e.g. 0.2)
  --meshopt           store tracked.glb's buffers compressed by meshoptimizer
                      (EXT_meshopt_compression: smaller, for web viewers such as
                      three.js; Blender 3.4 and ParaView cannot open it)
  --output DIR        where results go (default: dynamicpoints-output)
  --quiet             no per-frame table and no progress bar
  --describe-report   print the per-frame figures of report.json (and of the track
                      filter's field data) as a Markdown table, and exit
)";

const char* const UsageEnd = R"(  -h, --help          show this help

Exit status: 0 when every output was written; 1 when a frame or an output failed (the
frames tracked before it stay readable; in a batch: an input failed, named on stderr and
in batch.json, the others' outputs written); 2 for a bad command line; 130 when
interrupted.
)";

volatile std::sig_atomic_t Interrupted = 0;
extern "C" void onInterrupt(int)
{
  Interrupted = 1;
}

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
    if (ProgressShown)
      std::cerr << "\r\033[K";
    std::cerr << (event == vtkCommand::ErrorEvent ? "error: " : "warning: ") << line << "\n";
    if (event == vtkCommand::ErrorEvent)
      ++Errors;
  }
  int Errors = 0;
  bool ProgressShown = false;
};

// A one-line progress bar on stderr, drawn only when stderr is a terminal.
class ProgressBar
{
public:
  explicit ProgressBar(bool enabled) : Enabled(enabled && isatty(STDERR_FILENO)) {}
  void show(const std::string& what, double fraction)
  {
    if (!Enabled)
      return;
    const int width = 30, filled = static_cast<int>(std::lround(width * fraction));
    std::fprintf(stderr, "\r\033[K%-24s [%s%s] %3d%%", what.c_str(),
                 std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(),
                 static_cast<int>(std::lround(100 * fraction)));
    std::fflush(stderr);
  }
  void clear()
  {
    if (Enabled)
      std::fprintf(stderr, "\r\033[K");
  }
  bool enabled() const { return Enabled; }

private:
  bool Enabled;
};

// Aborts a filter when Ctrl-C was pressed, and moves the progress bar.
class ProgressWatcher : public vtkCommand
{
public:
  static ProgressWatcher* New() { return new ProgressWatcher; }
  void Execute(vtkObject* caller, unsigned long, void* callData) override
  {
    if (Interrupted)
      static_cast<vtkAlgorithm*>(caller)->SetAbortExecute(1);
    else if (Bar)
      Bar->show(What, *static_cast<double*>(callData));
  }
  ProgressBar* Bar = nullptr;
  std::string What;
};

/** Writes `text` to `path` through a file beside it, so a reader never sees half a file. */
void writeAtomically(const fs::path& path, const std::string& text)
{
  const fs::path partial = path.string() + ".partial";
  {
    std::ofstream out(partial, std::ios::trunc);
    out << text;
    if (!out)
      throw std::runtime_error(path.string() + ": cannot write");
  }
  fs::rename(partial, path);
}

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

double fieldValue(vtkDataObject* data, const char* name)
{
  vtkDataArray* a = vtkArrayDownCast<vtkDataArray>(data->GetFieldData()->GetAbstractArray(name));
  return a && a->GetNumberOfTuples() > 0 ? a->GetComponent(0, 0) : std::nan("");
}

// A tracked frame in the table and the report: its distance to the points, and what the track
// filter said of it (its field data, read back by the table that wrote it: dp::FrameFigures).
struct FrameRecord
{
  int frame;
  double time, rmsResidual, maxResidual;
  dp::FrameFigures figures;
  bool failed() const { return figures.failed > 0; }
  double milliseconds() const { return 1000 * figures.seconds; }
};

dp::FrameFigures figuresOf(vtkDataObject* mesh)
{
  dp::FrameFigures figures;
  for (const dp::FrameFigures::Field& field : dp::FrameFigures::fields())
    figures.*field.value = fieldValue(mesh, field.name);
  return figures;
}

// A figure in report.json: counts as integers, flags as true/false.
nlohmann::json figureJson(const dp::FrameFigures& figures, const dp::FrameFigures::Field& field)
{
  const double v = figures.*field.value;
  if (field.kind == dp::FrameFigures::Kind::Flag)
    return v > 0;
  if (field.kind == dp::FrameFigures::Kind::Count)
    return static_cast<long long>(v);
  return v;
}

// The upper median (0 for none): report.json's per-frame medians.
double medianOf(std::vector<double> values)
{
  if (values.empty())
    return 0.0;
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

struct Settings
{
  std::vector<std::string> inputs; // as given; a batch when more than one
  std::string input, pattern = "*", output = "dynamicpoints-output", templateFile;
  int vertices = 1000;
  int templateFrom = vtkDeformableTrackFilter::TEMPLATE_AUTO;
  long long frames = 0;   // 0: all
  double errorTarget = 0; // KG in percent; 0: judged against the data (fitGrowth)
  double fitGrowth = 10;  // percent the decompressed mesh's distance to the points may grow
  bool quiet = false;
  bool meshopt = false;
  // What to print instead of running: "values" (--print-options), "json" or "markdown"
  // (--describe-options), "report" (--describe-report).
  std::string printOptions;
  dp::TrackerOptions tracker; // --set, --options
};

Settings parse(int argc, char** argv, bool& help)
{
  using namespace dp::cli;
  Settings s;
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    if (arg == "-h" || arg == "--help")
      help = true;
    else if (arg == "--pattern")
      s.pattern = optionValue(argc, argv, i);
    else if (arg == "--output")
      s.output = optionValue(argc, argv, i);
    else if (arg == "--template")
      s.templateFile = optionValue(argc, argv, i);
    else if (arg == "--template-from")
    {
      const std::string from = optionValue(argc, argv, i);
      if (from != "auto" && from != "mesh" && from != "points")
        throw UsageError("--template-from wants auto, mesh or points, not '" + from + "'");
      s.templateFrom = from == "mesh"     ? vtkDeformableTrackFilter::TEMPLATE_FROM_MESH
                       : from == "points" ? vtkDeformableTrackFilter::TEMPLATE_FROM_POINTS
                                          : vtkDeformableTrackFilter::TEMPLATE_AUTO;
    }
    else if (arg == "--vertices")
      s.vertices = static_cast<int>(parseCount(arg, optionValue(argc, argv, i), 20, 10000000));
    else if (arg == "--frames")
      s.frames = static_cast<long long>(parseCount(arg, optionValue(argc, argv, i), 1, 10000000));
    else if (arg == "--error-target")
      s.errorTarget = parseDouble(arg, optionValue(argc, argv, i), 1e-4, 50);
    else if (arg == "--fit-growth")
      s.fitGrowth = parseDouble(arg, optionValue(argc, argv, i), 0.01, 1000);
    else if (arg == "--quiet")
      s.quiet = true;
    else if (arg == "--meshopt")
      s.meshopt = true;
    else if (arg == "--print-options")
      s.printOptions = "values";
    else if (arg == "--describe-report")
      s.printOptions = "report";
    else if (arg == "--describe-options")
    {
      s.printOptions = optionValue(argc, argv, i);
      if (s.printOptions != "json" && s.printOptions != "markdown")
        throw UsageError("--describe-options wants json or markdown, not '" + s.printOptions + "'");
    }
    else if (parseTrackerOptionFlag(arg, argc, argv, i, s.tracker))
      continue;
    else if (!arg.empty() && arg[0] == '-')
      throw UsageError("unknown option '" + arg + "'");
    else
      s.inputs.push_back(arg);
  }
  if (s.inputs.size() == 1)
    s.input = s.inputs.front();
  return s;
}

// The main job, stage by stage; each stage reports its own errors and leaves what it finished.
class MainJob
{
public:
  explicit MainJob(Settings settings)
      : S(std::move(settings)), Output(S.output), Pvd(Output / "tracked.pvd"),
        Dpz(Output / "tracked.dpz"), Glb(Output / "tracked.glb"), Bar(!S.quiet)
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
    return true;
  }

  bool prepareTracker()
  {
    watch(Tracker);
    Tracker->SetInputConnection(Source->GetOutputPort());
    for (const dp::TrackerOptionDescription& option : dp::trackerOptionTable())
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
      if (!writeFrame(writer, folder, f, time, mesh))
        break;
      record(f, time, mesh);
      if (nextFailed)
      {
        stopAt(f + 1);
        break;
      }
    }
    Bar.clear();
    summariseTracking();
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
  void record(int f, double time, vtkPolyData* mesh)
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
    const FrameRecord r{f, time, std::sqrt(sum / n), largest, figuresOf(mesh)};
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
    const bool againstData = !(S.errorTarget > 0);
    vtkNew<vtkPCACompressFilter> compressor;
    watch(compressor);
    compressor->SetInputConnection(Tracker->GetOutputPort());
    compressor->SetLayout(vtkPCACompressFilter::SHAPES); // the layout glTF morph targets need
    compressor->SetErrorMeasure(againstData ? vtkPCACompressFilter::DISTANCE_TO_DATA
                                            : vtkPCACompressFilter::KARNI_GOTSMAN);
    compressor->SetErrorTarget(againstData ? S.fitGrowth : S.errorTarget);
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
    if (againstData)
      sayDataFit(compressor->GetOutput());
    else
      sayMotionFit(*sequence);
    std::printf("glTF: %s\n", Glb.string().c_str());
  }

  // The codec's figures in report.json's "compression".
  void recordCompression(vtkPolyData* result)
  {
    for (const char* name : {"Components", "KGError", "RmsError", "MaxError", "MaxErrorRelative",
                             "BitsPerVertexFrame", "QuantizedPlainBitsPerVertexFrame", "PaperD0",
                             "PaperD1", "PaperRatio", "ComponentsPerFrame"})
      Compression[name] = fieldValue(result, name);
    double rawBytes = 0;
    for (const FrameRecord& r : Records)
      rawBytes += 12.0 * r.figures.points;
    Compression["Bytes"] = fs::file_size(Dpz);
    Compression["InputPointBytes"] = rawBytes;
    Compression["InputPointsOverFile"] = rawBytes / static_cast<double>(fs::file_size(Dpz));
  }

  void sayDataFit(vtkPolyData* result)
  {
    const double before = fieldValue(result, "DistanceToDataInput");
    const double after = fieldValue(result, "DistanceToDataDecompressed");
    const double growth = fieldValue(result, "DistanceToDataGrowth");
    Compression["Target"] =
        "the distance to the points grows by at most " + std::to_string(S.fitGrowth) + " %";
    Compression["FitGrowthAllowedPercent"] = S.fitGrowth;
    Compression["DistanceToPointsTracked"] = before;
    Compression["DistanceToPointsDecompressed"] = after;
    Compression["FitGrowthPercent"] = growth;
    std::printf("Compressed: %s, %.0f components, %.3g bits per vertex per frame, %.0fx smaller "
                "than the input points (float32); the decompressed mesh lies %.3g from the "
                "points (RMS), the tracked one %.3g (%+.1f %%, at most %g %%)\n",
                Dpz.string().c_str(), Compression["Components"].get<double>(),
                Compression["BitsPerVertexFrame"].get<double>(),
                Compression["InputPointsOverFile"].get<double>(), after, before, growth,
                S.fitGrowth);
  }

  void sayMotionFit(const dp::CompressedSequence& sequence)
  {
    const bool weak = Written.size() >= 8 && Compression["ComponentsPerFrame"].get<double>() > 0.5;
    Compression["weak"] = weak;
    if (weak)
      Compression["note"] = "most of the frames' worth of components were kept: the motion is "
                            "not low-rank, the tracking shakes, or the KG target asks for more "
                            "than the data's noise (the default target is the data's)";
    Compression["Target"] = "KG " + std::to_string(S.errorTarget) + " %";
    Compression["ErrorTargetKG"] = S.errorTarget;
    std::printf("Compressed: %s, %zu components, %.3g bits per vertex per frame (%.1fx "
                "smaller than float32), KG error %.3g%%\n",
                Dpz.string().c_str(), sequence.report.components,
                sequence.report.bitsPerVertexFrame, 96.0 / sequence.report.bitsPerVertexFrame,
                sequence.report.kgError);
    if (weak)
      std::printf("Compression is weak: %zu components for %zu frames (the motion is not "
                  "low-rank, the tracking shakes, or KG %.3g %% asks for more than the data's "
                  "noise: without --error-target the target is the data's)\n",
                  sequence.report.components, Written.size(), S.errorTarget);
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
      dp::writeGlb(Glb.string(), sequence, glb);
      return true;
    }
    catch (const std::exception& e)
    {
      std::cerr << "error: " << e.what() << "; the tracked frames are in " << Pvd.string() << "\n";
      Failed = true;
      return false;
    }
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
    report["boundingBoxDiagonal"] = Diagonal;
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
    report["medianStageSecondsPerFrame"] = stageMediansJson();
    const fs::path plot = Output / "report.png";
    nlohmann::json outputs = {{"tracked", Pvd.string()}, {"plot", plot.string()}};
    if (!Compression.empty())
    {
      report["compression"] = Compression;
      outputs["compressed"] = Dpz.string();
      outputs["gltf"] = Glb.string();
    }
    report["outputs"] = outputs;
    report["wallSeconds"] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - Started).count();
    writeAtomically(Output / "report.json", report.dump(1) + "\n");
    writePlot(plot);
    std::cout << "Report: " << (Output / "report.json").string() << ", " << plot.string() << "\n";
  }

  // A frame in report.json: its distance to the points, then every figure of dp::FrameFigures.
  static nlohmann::json frameJson(const FrameRecord& r)
  {
    nlohmann::json frame = {{"frame", r.frame},
                            {"time", r.time},
                            {"rmsResidual", r.rmsResidual},
                            {"maxResidual", r.maxResidual}};
    for (const dp::FrameFigures::Field& field : dp::FrameFigures::fields())
      frame[dp::FrameFigures::reportKey(field.name)] = figureJson(r.figures, field);
    return frame;
  }

  // Each stage's median seconds over the frames.
  nlohmann::json stageMediansJson() const
  {
    nlohmann::json medians = nlohmann::json::object();
    for (const dp::FrameFigures::Field& stage : dp::FrameFigures::stages())
    {
      std::vector<double> seconds;
      for (const FrameRecord& r : Records)
        seconds.push_back(r.figures.*stage.value);
      medians[dp::FrameFigures::reportKey(stage.name)] = medianOf(std::move(seconds));
    }
    return medians;
  }

  // report.png: the distance to the points, the quality, the largest stretch and the time, per
  // frame, the failed frames marked.
  void writePlot(const fs::path& plot) const
  {
    std::vector<double> rms, largest, ms, unexplained, unsupported, stretch;
    std::vector<std::size_t> failed;
    for (const FrameRecord& r : Records)
    {
      unexplained.push_back(100 * r.figures.unexplained);
      unsupported.push_back(100 * r.figures.unsupported);
      stretch.push_back(r.figures.largestStretch);
      if (r.failed())
        failed.push_back(static_cast<std::size_t>(r.frame));
      rms.push_back(Diagonal > 0 ? 100 * r.rmsResidual / Diagonal : r.rmsResidual);
      largest.push_back(Diagonal > 0 ? 100 * r.maxResidual / Diagonal : r.maxResidual);
      ms.push_back(r.milliseconds());
    }
    const dp::cli::PlotPanel residualPanel{
        "distance to the points, % of diagonal",
        {{"RMS", rms, {31, 119, 180}}, {"largest", largest, {255, 127, 14}}},
        {},
        ""};
    const dp::cli::PlotPanel qualityPanel{"beyond 3 voxels, %",
                                          {{"points far from mesh", unexplained, {148, 103, 189}},
                                           {"mesh far from points", unsupported, {140, 86, 75}}},
                                          failed,
                                          "failed frame"};
    const dp::cli::PlotPanel stretchPanel{"largest stretch, edge lengths (2: torn)",
                                          {{"stiffest edge's growth", stretch, {23, 190, 207}}},
                                          failed,
                                          "failed frame"};
    const dp::cli::PlotPanel timePanel{
        "tracking time, ms", {{"per frame", ms, {44, 160, 44}}}, {}, ""};
    dp::cli::writeFramePlot(plot.string(),
                            "DynamicPoints: " + fs::path(InputName).filename().string(),
                            {residualPanel, qualityPanel, stretchPanel, timePanel});
  }

  const Settings S;
  const fs::path Output, Pvd, Dpz, Glb;
  const std::chrono::steady_clock::time_point Started = std::chrono::steady_clock::now();
  vtkNew<MessagePrinter> Printer;
  vtkNew<vtkCallbackCommand> Quiet;
  ProgressBar Bar;
  vtkNew<vtkPointSequenceSource> Source;
  vtkNew<vtkPointSequenceSource> TemplateReader;
  vtkNew<vtkDeformableTrackFilter> Tracker;
  vtkNew<ProgressWatcher> TrackProgress;

  std::string InputName;
  int Frames = 0;
  bool Failed = false;
  std::vector<std::pair<double, std::string>> Written; // (time, file) of each frame written
  std::vector<FrameRecord> Records;
  double Diagonal = 0;
  long long MeshVertices = 0, MeshTriangles = 0;
  std::string TemplateMade; // what the template was made from, and how
  nlohmann::json Compression;
};

// One input's whole job; an error it did not foresee is its failure, not the batch's.
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

std::string outcome(int status)
{
  return status == 0 ? "done" : status == 130 ? "interrupted" : "failed";
}

// What OUTPUT/<name>/report.json says of a finished input, for the batch's report.
nlohmann::json summaryOf(const fs::path& folder)
{
  std::ifstream file(folder / "report.json");
  nlohmann::json report = nlohmann::json::parse(file, nullptr, false);
  if (report.is_discarded() || !report.is_object())
    return nlohmann::json::object();
  nlohmann::json summary = {{"report", (folder / "report.json").string()}};
  for (const char* key : {"frames", "framesFailed", "medianMillisecondsPerFrame", "wallSeconds"})
    if (report.contains(key))
      summary[key] = report[key];
  return summary;
}

// Rank 0: OUTPUT/batch.json (every input in the order given: where its outputs are, which
// process did it, how it ended, what its own report says) and a line naming the failures.
int reportBatch(const Settings& base, const std::vector<dp::cli::BatchInput>& inputs,
                const std::vector<std::string>& outcomes, int processes, double wallSeconds)
{
  nlohmann::json entries = nlohmann::json::array();
  for (const dp::cli::BatchInput& input : inputs)
    entries.push_back({{"input", input.path},
                       {"output", (fs::path(base.output) / input.name).string()},
                       {"bytes", input.bytes}});
  for (const std::string& text : outcomes)
    for (const nlohmann::json& done : nlohmann::json::parse(text))
    {
      nlohmann::json& entry = entries[done["index"].get<std::size_t>()];
      for (const char* key : {"turn", "exitStatus", "result", "process", "seconds"})
        entry[key] = done[key];
      entry.update(summaryOf(entry["output"].get<std::string>()));
    }
  std::vector<std::string> failed;
  int status = 0;
  for (const nlohmann::json& entry : entries)
  {
    const int exit = entry.value("exitStatus", 1);
    if (exit != 0)
      failed.push_back(entry["input"].get<std::string>() + " (" +
                       entry.value("result", std::string("failed")) + ")");
    status = std::max(status, exit == 130 ? 130 : exit != 0 ? 1 : 0);
  }
  fs::create_directories(base.output);
  const fs::path path = fs::path(base.output) / "batch.json";
  writeAtomically(
      path,
      nlohmann::json{{"inputs", entries}, {"processes", processes}, {"wallSeconds", wallSeconds}}
              .dump(1) +
          "\n");
  std::cout << "Batch: " << inputs.size() << " inputs on " << processes << " process(es), "
            << inputs.size() - failed.size() << " done in " << std::lround(wallSeconds)
            << " s; report " << path.string() << "\n";
  if (!failed.empty())
  {
    std::cerr << "dynamicpoints: " << failed.size() << " of " << inputs.size()
              << " inputs did not finish:";
    for (const std::string& f : failed)
      std::cerr << "\n  " << f;
    std::cerr << "\n";
  }
  return status;
}

// Several inputs: each into OUTPUT/<name>/ as a run on it alone would write it, spread over the
// MPI ranks (largest first, to whoever is free); rank 0 writes OUTPUT/batch.json and says which
// inputs failed.
int runBatch(const Settings& base, dp::cli::Ranks& ranks)
{
  const auto batchStart = std::chrono::steady_clock::now();
  const std::vector<dp::cli::BatchInput> inputs = dp::cli::describeBatch(base.inputs);
  const std::vector<std::size_t> order = dp::cli::largestFirst(inputs);
  const bool alone = ranks.size() == 1;
  nlohmann::json mine = nlohmann::json::array();
  ranks.shareCounter();
  // Whoever is free takes the next input, largest first: the processes end about together
  // however unequal the takes are (their sizes on disk do not tell their work).
  for (int next = ranks.takeNext(); next < static_cast<int>(order.size()); next = ranks.takeNext())
  {
    const std::size_t index = order[static_cast<std::size_t>(next)];
    const dp::cli::BatchInput& input = inputs[index];
    Settings s = base;
    s.input = input.path;
    s.output = (fs::path(base.output) / input.name).string();
    s.quiet = base.quiet || !alone; // several processes' tables would interleave
    int status = 130;
    const bool started = !Interrupted; // after Ctrl-C the rest are not started
    const auto start = std::chrono::steady_clock::now();
    if (started)
    {
      if (alone)
        std::cout << "== " << input.name << " (" << next + 1 << " of " << inputs.size()
                  << "): " << input.path << "\n";
      status = runJob(s);
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!alone)
      std::cout << "[process " << ranks.rank() << "] " << input.name << ": " << outcome(status)
                << " in " << std::lround(seconds) << " s" << std::endl;
    mine.push_back({{"index", index},
                    {"turn", next},
                    {"exitStatus", status},
                    {"result", started ? outcome(status) : "not started"},
                    {"process", ranks.rank()},
                    {"seconds", seconds}});
  }
  const std::vector<std::string> all = ranks.gather(mine.dump());
  int status = 0;
  if (ranks.rank() == 0)
  {
    try // every process waits for this status: no exception may skip the broadcast
    {
      status = reportBatch(
          base, inputs, all, ranks.size(),
          std::chrono::duration<double>(std::chrono::steady_clock::now() - batchStart).count());
    }
    catch (const std::exception& e)
    {
      std::cerr << "dynamicpoints: error: the batch's report: " << e.what() << "\n";
      status = 1;
    }
  }
  return ranks.broadcast(status);
}

int run(int argc, char** argv, dp::cli::Ranks& ranks)
{
  bool help = false;
  Settings settings = parse(argc, argv, help);
  if (help)
  {
    if (ranks.rank() == 0)
      std::cout << Usage << dp::cli::TrackerOptionHelp << UsageEnd;
    return 0;
  }
  if (!settings.printOptions.empty())
  {
    if (ranks.rank() == 0)
      std::cout << (settings.printOptions == "values"   ? dp::trackerOptionsJson(settings.tracker)
                    : settings.printOptions == "json"   ? dp::trackerOptionTableJson()
                    : settings.printOptions == "report" ? dp::FrameFigures::markdown()
                                                        : dp::trackerOptionTableMarkdown());
    return 0;
  }
  std::signal(SIGINT, onInterrupt);
  std::signal(SIGTERM, onInterrupt);
  if (settings.inputs.size() > 1)
    return runBatch(settings, ranks);
  // One input: one process does it (under mpirun the others end at once; mpirun's exit status
  // is the first non-zero one).
  return ranks.rank() == 0 ? runJob(settings) : 0;
}

} // namespace

int main(int argc, char** argv)
{
  dp::cli::Ranks ranks(&argc, &argv);
  try
  {
    return run(argc, argv, ranks);
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
