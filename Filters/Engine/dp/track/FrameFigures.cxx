// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/FrameFigures.h"

#include "dp/track/Tracker.h"

#include <algorithm>
#include <cctype>

namespace dp
{

const std::vector<FrameFigures::Field>& FrameFigures::fields()
{
  using F = FrameFigures;
  static const std::vector<Field> table = {
      {"FrameIndex", &F::frameIndex, Kind::Count, "the frame's index in the take"},
      {"Points", &F::points, Kind::Count, "the frame's points"},
      {"Iterations", &F::iterations, Kind::Count, "the fine level's steps (the kept attempt)"},
      {"CoarseIterations", &F::coarseIterations, Kind::Count,
       "the coarse level's steps (the kept attempt)"},
      {"InternalEnergy", &F::internalEnergy, Kind::Number, "E_int at the result"},
      {"DistanceEnergy", &F::distanceEnergy, Kind::Number, "E_dis at the result"},
      {"Seconds", &F::seconds, Kind::Number, "the frame's wall time"},
      {"OverlappedSeconds", &F::overlappedSeconds, Kind::Number,
       "of its data's preparation, what ran beside the frame before"},
      {"DataSeconds", &F::dataSeconds, Kind::Number,
       "the frame's data: distance field, normals, subsample"},
      {"PredictionSeconds", &F::predictionSeconds, Kind::Number, "the kept attempt's start"},
      {"CoarseSeconds", &F::coarseSeconds, Kind::Number, "the kept attempt's coarse level"},
      {"FineSeconds", &F::fineSeconds, Kind::Number, "the kept attempt's fine level"},
      {"QualitySeconds", &F::qualitySeconds, Kind::Number, "the kept attempt's quality check"},
      {"RetrySeconds", &F::retrySeconds, Kind::Number, "the other attempts"},
      {"EmptyFrame", &F::emptyFrame, Kind::Flag, "1: the frame had no points"},
      {"Unexplained", &F::unexplained, Kind::Number,
       "share of the points farther than DataReach from the mesh"},
      {"Unsupported", &F::unsupported, Kind::Number,
       "share of the mesh farther than DataReach from the points (holes in the data too)"},
      {"LargestStretch", &F::largestStretch, Kind::Number,
       "the most a stiff edge grew beyond its template length, in mean edge lengths (above 2: "
       "a torn limb)"},
      {"Retries", &F::retries, Kind::Count, "attempts after the first"},
      {"Failed", &F::failed, Kind::Flag,
       "1: the frame still failed after its retries; do not trust it"},
      {"DataReach", &F::dataReach, Kind::Number,
       "how far from the mesh a point still counts as explained"},
      {"DataNoise", &F::dataNoise, Kind::Number,
       "the data's noise: the RMS distance of points from their local plane (a sensor's layer "
       "thickness); the quality's reach is at least six times it"},
      {"Seen", &F::seen, Kind::Number, "share of the mesh the data see (1 - Unsupported)"},
  };
  return table;
}

const std::vector<FrameFigures::Field>& FrameFigures::stages()
{
  static const std::vector<Field> stages = []
  {
    const std::vector<Field>& all = fields();
    const auto first =
        std::find_if(all.begin(), all.end(),
                     [](const Field& f) { return std::string(f.name) == "DataSeconds"; });
    return std::vector<Field>(first, first + 6);
  }();
  return stages;
}

FrameFigures FrameFigures::of(const FrameResult& r, std::size_t frame, double reach)
{
  FrameFigures f;
  f.frameIndex = static_cast<double>(frame);
  f.points = static_cast<double>(r.pointsGiven);
  f.iterations = r.iterations;
  f.coarseIterations = r.coarseIterations;
  f.internalEnergy = r.internalEnergy;
  f.distanceEnergy = r.distanceEnergy;
  // The frame's wall time: its data's preparation ran partly beside the frame before.
  f.seconds = r.seconds - r.overlapped;
  f.overlappedSeconds = r.overlapped;
  // Where the frame's work went: its data, then the kept attempt's stages; the other attempts
  // (retries) take the rest of the frame's work.
  const FrameTimings& t = r.timings;
  const double stages = t.data + t.prediction + t.coarse + t.fine + t.quality;
  f.dataSeconds = t.data;
  f.predictionSeconds = t.prediction;
  f.coarseSeconds = t.coarse;
  f.fineSeconds = t.fine;
  f.qualitySeconds = t.quality;
  f.retrySeconds = r.retries > 0 ? std::max(0.0, r.seconds - stages) : 0.0;
  f.emptyFrame = r.emptyFrame ? 1 : 0;
  f.unexplained = r.unexplained;
  f.unsupported = r.unsupported;
  f.largestStretch = r.tear;
  f.retries = r.retries;
  f.failed = r.failed ? 1 : 0;
  f.dataReach = reach;
  f.dataNoise = r.noise;
  f.seen = r.emptyFrame ? 0.0 : 1.0 - r.unsupported;
  return f;
}

std::string FrameFigures::reportKey(const char* name)
{
  std::string key = name;
  if (!key.empty())
    key[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(key[0])));
  return key;
}

std::string FrameFigures::markdown()
{
  std::string md = "| field data | report.json | what |\n|---|---|---|\n";
  for (const Field& f : fields())
    md += std::string("| `") + f.name + "` | `" + reportKey(f.name) + "` | " + f.doc + " |\n";
  return md;
}

} // namespace dp
