// SPDX-License-Identifier: BSD-3-Clause
// dynamicpoints: the command line of the main job. One input is tracked, compressed and reported
// by MainJob (MainJob.h); several inputs are a batch, spread over the processes of an mpirun
// (Batch.h), each input's outputs in a folder of its own and OUTPUT/batch.json saying how each
// ended.
#include "Batch.h"
#include "CommandLine.h"
#include "Console.h"
#include "MainJob.h"
#include "OptionFlags.h"

#include "dp/compress/CompressionFigures.h"
#include "dp/compress/CompressionOptions.h"
#include "dp/field/TemplateMesh.h"
#include "dp/geometry/SubdivisionMap.h"
#include "dp/track/FrameFigures.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

namespace
{
namespace fs = std::filesystem;
using dp::cli::Interrupted;
using dp::cli::runJob;
using dp::cli::Settings;
using dp::cli::writeAtomically;

const char* const Usage = R"(Usage: dynamicpoints [OPTIONS] [INPUT ...]

Turns a time series of point clouds into one deforming triangle mesh of fixed
connectivity, tracked frame by frame; then compresses it and writes it for ParaView, VTK
and glTF viewers.

INPUT is a folder of point files (one per frame), a ParaView .series file, or one point
file. Readable: .ply .pcd .xyz .pts .csv .txt .obj .drc .vtp .vtu .vtk.
Without INPUT, the built-in sample sequence is generated first: a bending, twisting tube,
30 frames of 20000 random surface points with normals, written to OUTPUT/input/.
With several INPUTs (a batch of takes), each is done as alone into OUTPUT/<name>/ (its
folder's name; a .series file's folder's; a file's stem), and OUTPUT/batch.json says how
each ended. Started by mpirun (mpirun -np N dynamicpoints ...), the inputs are spread over
the N processes, largest first; each input's files are the same as from one process.

Written to OUTPUT:
  tracked.pvd, tracked/*.vtp  the tracked mesh, one file per frame (open the .pvd in
                              ParaView), at the fine level of its detail layer where the
                              data hold detail (--detail-levels); brought up to date after
                              every frame; where the points carry colour, each vertex's
                              colour (Colors)
  tracked.dpz                 the compressed sequence (ParaView or vtkCompressedSequenceReader),
                              as close to the points as --fit-growth allows
  tracked.glb                 glTF 2.0 animation: morph targets, 24 frames per second
  report.json, report.png     per frame: distance to the points, quality (share of the
                              points far from the mesh and of the mesh far from the
                              points; frames retried and failed), time; compression
  view.html                   a page that plays the take in any browser (no server, no
                              network), the report beside it
  paraview-state.py           the tracked take over its points, coloured by the distance
                              to them: paraview --state=OUTPUT/paraview-state.py

Options:
  --pattern GLOB      files of an INPUT folder to read (default: *)
  --template FILE     mesh to deform (.ply .obj .vtp .vtk ...), repaired if it must be
                      (what was done is said), never remeshed; default: made from the
                      first frame (--template-from)
  --template-from S   auto (default): the first frame's mesh when its file has polygons
                      (a capture's per-frame mesh: repaired and remeshed to --vertices),
                      else a surface reconstructed from its points; mesh; points
  --vertices N        vertex count of a template made from the first frame (default: 1000)
  --detail-levels N   the detail layer: the tracked mesh subdivided N times (0 to {MaximumDetailLevels}; each
                      level has 4x the triangles) and displaced onto each frame's data,
                      coded through the take in tracked.dpz; 0: the tracked mesh alone;
                      auto (default): measured on the first frame, the level that
                      matches the capture's vertex count (half its point count), kept
                      where it brings the mesh a fifth closer to the data
  --frames N          track only the first N frames (default: all; they are listed
                      with their times in OUTPUT/first-frames.series)
  --fit-growth P      compression judged against the data (the default): the decompressed
                      mesh's RMS distance to the points may grow by at most P percent
                      over the tracked mesh's (default: {compression.fitGrowth}); --set compression.fitGrowth=P
  --error-target KG   compression judged against the motion instead: Karni-Gotsman error
                      in percent (e.g. 0.2); --set compression.measure=kg
                      --set compression.kgTarget=KG
  --colour-tolerance L where the points carry colour: the levels (of 255) a stored
                      colour may differ from the tracked one (default: {compression.colourTolerance}; 0: lossless);
                      --set compression.colourTolerance=L
  --no-view           write no view.html and no paraview-state.py
  --meshopt           store tracked.glb's buffers compressed by meshoptimizer
                      (EXT_meshopt_compression: smaller, for web viewers such as
                      three.js; Blender 3.4 and ParaView cannot open it)
  --output DIR        where results go (default: dynamicpoints-output)
  --quiet             no per-frame table and no progress bar
  --describe-report   print the per-frame figures of report.json (and of the track
                      filter's field data) and the compression's as Markdown tables,
                      and exit
  --describe-limits   print the ranges of --vertices and --detail-levels (also the
                      ParaView properties') as JSON, and exit
)";

const char* const CompressionHelpHead = R"(
Compression options (--set NAME=VALUE; vtkPCACompressFilter and the writers have them as
properties; the main job judges the compression against the data by default):
)";

const char* const UsageEnd = R"(  -h, --help          show this help

Exit status: 0 when every output was written; 1 when a frame or an output failed (the
frames tracked before it stay readable; in a batch: an input failed, named on stderr and
in batch.json, the others' outputs written); 2 for a bad command line; 130 when
interrupted.
)";

extern "C" void onInterrupt(int)
{
  dp::cli::Interrupted = 1;
}

// The ranges the main job, the filters and their ParaView properties share besides the option
// tables (--describe-limits; a test checks the plugin's XML against them).
std::string limitsJson()
{
  const nlohmann::json limits = {
      {"templateVertices",
       {{"default", dp::TemplateOptions{}.targetVertices},
        {"minimum", dp::MinimumTemplateVertices},
        {"maximum", dp::MaximumTemplateVertices}}},
      {"detailLevels",
       {{"default", "auto"}, {"minimum", 0}, {"maximum", dp::MaximumDetailLevels}}}};
  return limits.dump(2) + "\n";
}

// The flags that print a description instead of running; false for another flag.
bool parsePrintFlag(const std::string& arg, int argc, char** argv, int& i, Settings& s)
{
  using dp::cli::UsageError;
  if (arg == "--print-options")
    s.printOptions = "values";
  else if (arg == "--describe-report")
    s.printOptions = "report";
  else if (arg == "--describe-limits")
    s.printOptions = "limits";
  else if (arg == "--describe-options")
  {
    s.printOptions = dp::cli::optionValue(argc, argv, i);
    if (s.printOptions != "json" && s.printOptions != "markdown")
      throw UsageError("--describe-options wants json or markdown, not '" + s.printOptions + "'");
  }
  else
    return false;
  return true;
}

// The flags of the input and the outputs; false for another flag.
bool parseFileFlag(const std::string& arg, int argc, char** argv, int& i, Settings& s)
{
  using dp::cli::optionValue;
  if (arg == "--pattern")
    s.pattern = optionValue(argc, argv, i);
  else if (arg == "--output")
    s.output = optionValue(argc, argv, i);
  else if (arg == "--quiet")
    s.quiet = true;
  else if (arg == "--meshopt")
    s.meshopt = true;
  else if (arg == "--no-view")
    s.view = false;
  else
    return false;
  return true;
}

// The flags of the tracked mesh: its template, its detail layer, the frames tracked; false for
// another flag.
bool parseMeshFlag(const std::string& arg, int argc, char** argv, int& i, Settings& s)
{
  using namespace dp::cli;
  if (arg == "--template")
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
    s.vertices = static_cast<int>(parseCount(
        arg, optionValue(argc, argv, i), dp::MinimumTemplateVertices, dp::MaximumTemplateVertices));
  else if (arg == "--detail-levels")
  {
    const std::string value = optionValue(argc, argv, i);
    s.detailLevels = value == "auto"
                         ? vtkSurfaceDetailFilter::AUTOMATIC
                         : static_cast<int>(parseCount(arg, value, 0, dp::MaximumDetailLevels));
  }
  else if (arg == "--frames")
    s.frames = static_cast<long long>(parseCount(arg, optionValue(argc, argv, i), 1, 10000000));
  else
    return false;
  return true;
}

// The compression's shortcuts for rows of its option table; false for another flag.
bool parseCompressionFlag(const std::string& arg, int argc, char** argv, int& i, Settings& s)
{
  using dp::cli::setShortcut;
  if (arg == "--error-target")
  {
    setShortcut(arg, argc, argv, i, {nullptr, &s.compression}, "compression.kgTarget");
    s.compression.measure = dp::CompressionMeasure::KarniGotsman;
  }
  else if (arg == "--fit-growth")
  {
    setShortcut(arg, argc, argv, i, {nullptr, &s.compression}, "compression.fitGrowth");
    s.compression.measure = dp::CompressionMeasure::DistanceToData;
  }
  else if (arg == "--colour-tolerance")
    setShortcut(arg, argc, argv, i, {nullptr, &s.compression}, "compression.colourTolerance");
  else
    return false;
  return true;
}

Settings parse(int argc, char** argv, bool& help)
{
  using namespace dp::cli;
  Settings s;
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    if (arg == "-h" || arg == "--help")
      help = true;
    else if (parseFileFlag(arg, argc, argv, i, s) || parseMeshFlag(arg, argc, argv, i, s) ||
             parseCompressionFlag(arg, argc, argv, i, s) || parsePrintFlag(arg, argc, argv, i, s) ||
             parseTableOptionFlag(arg, argc, argv, i, {&s.tracker, &s.compression}))
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

// Input `index` of a batch, handed out at turn `turn`: done into OUTPUT/<name>/ as a run on it
// alone would do it; what batch.json says of how it ended.
nlohmann::json runBatchInput(const Settings& base, const std::vector<dp::cli::BatchInput>& inputs,
                             std::size_t index, int turn, const dp::cli::Ranks& ranks)
{
  const dp::cli::BatchInput& input = inputs[index];
  const bool alone = ranks.size() == 1;
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
      std::cout << "== " << input.name << " (" << turn + 1 << " of " << inputs.size()
                << "): " << input.path << "\n";
    status = runJob(s);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!alone)
    std::cout << "[process " << ranks.rank() << "] " << input.name << ": " << outcome(status)
              << " in " << std::lround(seconds) << " s" << std::endl;
  return {{"index", index},          {"turn", turn},
          {"exitStatus", status},    {"result", started ? outcome(status) : "not started"},
          {"process", ranks.rank()}, {"seconds", seconds}};
}

// Several inputs: each into OUTPUT/<name>/ as a run on it alone would write it, spread over the
// MPI ranks (largest first, to whoever is free); rank 0 writes OUTPUT/batch.json and says which
// inputs failed.
int runBatch(const Settings& base, dp::cli::Ranks& ranks)
{
  const auto batchStart = std::chrono::steady_clock::now();
  const std::vector<dp::cli::BatchInput> inputs = dp::cli::describeBatch(base.inputs);
  const std::vector<std::size_t> order = dp::cli::largestFirst(inputs);
  nlohmann::json mine = nlohmann::json::array();
  ranks.shareCounter();
  // Whoever is free takes the next input, largest first: the processes end about together
  // however unequal the takes are (their sizes on disk do not tell their work).
  for (int next = ranks.takeNext(); next < static_cast<int>(order.size()); next = ranks.takeNext())
    mine.push_back(runBatchInput(base, inputs, order[static_cast<std::size_t>(next)], next, ranks));
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

// What --print-options, --describe-options, --describe-report and --describe-limits print.
std::string described(const Settings& s)
{
  if (s.printOptions == "values")
    return dp::cli::tableOptionsJson(s.tracker, &s.compression).dump(2) + "\n";
  if (s.printOptions == "json")
    return nlohmann::ordered_json{
               {"tracker", nlohmann::ordered_json::parse(dp::trackerOptions().describeJson())},
               {"compression",
                nlohmann::ordered_json::parse(dp::compressionOptions().describeJson())}}
               .dump(2) +
           "\n";
  if (s.printOptions == "report") // per frame, then the compression's
    return dp::FrameFigures::markdown() + "\n" + dp::CompressionFigures::markdown();
  if (s.printOptions == "limits")
    return limitsJson();
  // The two tables, each as its page of the documentation holds it.
  return dp::trackerOptions().describeMarkdown() + "\n" +
         dp::compressionOptions().describeMarkdown();
}

// The help's text with each {NAME} of a compression option replaced by its default (the table's)
// and {MaximumDetailLevels} by the engine's: no default is typed twice.
std::string withDefaults(std::string text)
{
  const dp::CompressionOptions defaults;
  const auto fill = [&](const std::string& key, const std::string& value)
  {
    for (std::size_t at = text.find(key); at != std::string::npos; at = text.find(key, at))
      text.replace(at, key.size(), value);
  };
  for (const auto& row : dp::compressionOptions())
    fill("{" + row.name + "}", row.said(row.get(defaults)));
  fill("{MaximumDetailLevels}", std::to_string(dp::MaximumDetailLevels));
  return text;
}

int run(int argc, char** argv, dp::cli::Ranks& ranks)
{
  bool help = false;
  Settings settings = parse(argc, argv, help);
  if (help)
  {
    if (ranks.rank() == 0)
      std::cout << withDefaults(Usage) << dp::cli::OptionHelp << UsageEnd << CompressionHelpHead
                << dp::cli::compressionOptionHelp(Settings{}.compression);
    return 0;
  }
  if (!settings.printOptions.empty())
  {
    if (ranks.rank() == 0)
      std::cout << described(settings);
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
