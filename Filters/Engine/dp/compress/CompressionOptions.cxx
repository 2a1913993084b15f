// SPDX-License-Identifier: BSD-3-Clause
#include "dp/compress/CompressionOptions.h"

#include "dp/compress/ColourStream.h"

#include <sstream>

namespace dp
{

namespace
{

using Row = OptionDescription<CompressionOptions>;
using Rows = OptionRows<CompressionOptions>;
using Panel = OptionPanel;

// The error target's measure and its targets on the motion (measure kg and max-vertex).
std::vector<Row> motionTargetRows()
{
  return {
      Rows::choice(
          "compression.measure", "ErrorMeasure", Panel::Shown, {"kg", "max-vertex", "data"},
          "what the error target measures: the Karni-Gotsman error of the motion, the largest "
          "vertex error, or the distance to the data the mesh was tracked to (the input must "
          "carry it: the track filter's output)",
          [](auto& o) -> auto& { return o.measure; })
          .withChoiceLabels({"KG error (%)", "Max vertex error (fraction of diagonal)",
                             "Distance to the data (growth %)"})
          .withHelp("What the error target measures: Karni and Gotsman's error, 100 |A - A'| / |A -"
                    " E(A)| in percent, the largest vertex error as a fraction of the bounding-box "
                    "diagonal, or (for Deformable Track's output, which carries each frame's "
                    "points) the percent by which the decompressed mesh's RMS distance to the "
                    "points may grow: a target of the data's, not the motion's (10 suits noisy "
                    "captures; the main job's default)."),
      Rows::real(
          "compression.kgTarget", "KGTarget", Panel::Shown, MinimumKarniGotsmanTarget,
          MaximumKarniGotsmanTarget, "percent",
          "measure kg: the largest Karni-Gotsman error, the norm of the positions' error over "
          "that of their motion about each frame's centroid",
          [](auto& o) -> auto& { return o.kgTarget; })
          .withLabel("KG Target")
          .withHelp("Error Measure KG: the largest Karni-Gotsman error, 100 |A - A'| / |A - E(A)| "
                    "in percent (e.g. 0.5, 0.2, 0.1). The compressor meets it on the actual "
                    "reconstruction.")
          .shownWith("ErrorMeasure=0"),
      Rows::real(
          "compression.maxVertexTarget", "MaxVertexTarget", Panel::Shown, 1e-7, 0.5,
          "of the diagonal",
          "measure max-vertex: the largest distance of a vertex from its place, over the "
          "sequence's bounding-box diagonal",
          [](auto& o) -> auto& { return o.maxVertexTarget; })
          .withHelp("Error Measure max vertex: the largest distance of a vertex from its place, as "
                    "a fraction of the sequence's bounding-box diagonal (e.g. 0.002).")
          .shownWith("ErrorMeasure=1"),
  };
}

// The error target on the data (measure data).
std::vector<Row> dataTargetRows()
{
  return {
      Rows::real(
          "compression.fitGrowth", "FitGrowth", Panel::Shown, MinimumFitGrowth, MaximumFitGrowth,
          "percent",
          "measure data: how much the decompressed mesh's RMS distance to the data may grow over "
          "the tracked mesh's (10 suits noisy captures)",
          [](auto& o) -> auto& { return o.fitGrowth; })
          .withHelp("Error Measure distance to the data: the percent by which the decompressed "
                    "mesh's RMS distance to the tracked points may grow over the tracked mesh's (10"
                    " suits noisy captures; the main job's default).")
          .shownWith("ErrorMeasure=2"),
      Rows::flag(
          "compression.slide", "SlideAlongSurface", Panel::Advanced,
          "measure data: also code the take with each vertex slid along its surface toward a "
          "model of fewer components (the tracker's sliding, which the data do not see, costs "
          "bits), and keep the fewer bits that keep the fit",
          [](auto& o) -> auto& { return o.slide; })
          .withHelp("Error Measure distance to the data: also code the take with each vertex slid "
                    "along its surface toward a model of fewer components (the tracker's sliding, "
                    "which the data do not see, costs bits), and keep the fewer bits that keep the "
                    "fit.")
          .shownWith("ErrorMeasure=2"),
  };
}

std::vector<Row> codingRows()
{
  return {
      Rows::choice(
          "compression.layout", "Layout", Panel::Shown, {"trajectories", "shapes", "automatic"},
          "the components: vertex trajectories with per-vertex weights (the paper), shapes with "
          "per-frame weights (morph targets), or both coded and the one of fewer bits kept",
          [](auto& o) -> auto& { return o.layout; })
          .withChoiceLabels(
              {"Trajectories (the paper)", "Shapes (morph targets)", "Automatic (fewer bits)"})
          .withHelp("Trajectories: each component is a motion over time and each vertex has a "
                    "weight per component (the paper). Shapes: each component is a shape and each "
                    "frame has a weight per component (Alexa and Mueller; what glTF morph targets "
                    "hold). Automatic: both are coded and the one of fewer bits kept (field data "
                    "Layout: 0 trajectories, 1 shapes)."),
      Rows::integer(
          "compression.components", "NumberOfComponents", Panel::Advanced, 0, 1e6,
          "principal components kept, the target then setting only the quantisation; 0: the "
          "fewest bytes that meet the target",
          [](auto& o) -> auto& { return o.components; })
          .withHelp("0: as few bytes as meet the error target. Otherwise this many components, the "
                    "target then only setting the quantisation."),
      Rows::flag(
          "compression.quantise", "Quantize", Panel::Advanced,
          "quantise, predict and range-code the components; off: the paper's float PCA, to "
          "study it (the writers always quantise)",
          [](auto& o) -> auto& { return o.quantise; })
          .withHelp("Quantise, predict and entropy-code the components (default). Off: the paper's "
                    "float PCA, to study it (the writers always quantise)."),
      Rows::integer(
          "compression.colourTolerance", "ColourTolerance", Panel::Advanced, 0,
          MaximumColourTolerance,
          "where the input carries colour: the levels (of 255) a stored colour may differ from "
          "the given one; more holds each vertex's colour while it stays within them (no "
          "flicker, a smaller colour stream); 0: lossless",
          [](auto& o) -> auto& { return o.colourTolerance; })
          .withHelp("Where the input carries Colors: the levels (of 255) a stored colour may differ"
                    " from the input's. 0 stores them losslessly. More (default 4) holds each "
                    "vertex's colour while it stays within that many levels: the colour stops "
                    "flickering and its stream shrinks (to about half at 4 on a tracked person), "
                    "and any larger change still passes."),
  };
}

std::vector<Row> makeTable()
{
  std::vector<Row> rows = motionTargetRows();
  for (Row& row : dataTargetRows())
    rows.push_back(std::move(row));
  for (Row& row : codingRows())
    rows.push_back(std::move(row));
  return rows;
}

} // namespace

const OptionTable<CompressionOptions>& compressionOptions()
{
  static const OptionTable<CompressionOptions> table("compression option", makeTable());
  return table;
}

PcaOptions pcaOptionsOf(const CompressionOptions& options)
{
  compressionOptions().check(options);
  PcaOptions o;
  o.layout = options.layout;
  o.measure = options.measure == CompressionMeasure::MaxVertexError
                  ? PcaErrorMeasure::MaxVertexError
                  : PcaErrorMeasure::KarniGotsman;
  o.target = options.measure == CompressionMeasure::MaxVertexError ? options.maxVertexTarget
                                                                   : options.kgTarget;
  o.components = options.components;
  o.quantise = options.quantise;
  return o;
}

std::string targetSaid(const CompressionOptions& options)
{
  std::ostringstream s;
  switch (options.measure)
  {
  case CompressionMeasure::MaxVertexError:
    s << "max vertex error " << options.maxVertexTarget << " of the diagonal";
    break;
  case CompressionMeasure::DistanceToData:
    s << "the distance to the data grows by at most " << options.fitGrowth << " %";
    break;
  default:
    s << "KG " << options.kgTarget << " %";
  }
  return s.str();
}

} // namespace dp
