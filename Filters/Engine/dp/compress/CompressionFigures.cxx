// SPDX-License-Identifier: BSD-3-Clause
#include "dp/compress/CompressionFigures.h"

#include "dp/compress/PcaCompression.h"

namespace dp
{

const std::vector<CompressionFigures::Field>& CompressionFigures::fields()
{
  using F = CompressionFigures;
  static const std::vector<Field> table = {
      {"Components", &F::components, "principal components kept", true},
      {"Layout", &F::layout, "the layout kept: 0 trajectories (the paper), 1 shapes", true},
      {"PaperD0", &F::paperD0, "the paper's count of numbers before: 3 Nv Nt", true},
      {"PaperD1", &F::paperD1, "the paper's count of numbers after (basis and weights)", true},
      {"PaperRatio", &F::paperRatio, "PaperD0 / PaperD1"},
      {"BitsPerVertexFrame", &F::bitsPerVertexFrame,
       "the geometry's bits per vertex per frame (raw float32: 96)"},
      {"QuantizedPlainBitsPerVertexFrame", &F::quantisedPlainBits,
       "the same integers in fixed-width fields, no prediction or coding"},
      {"KGError", &F::kgError, "Karni-Gotsman error of the decompressed take, percent"},
      {"MaxError", &F::maxError, "the largest vertex error, world units"},
      {"MaxErrorRelative", &F::maxErrorRelative, "MaxError over the bounding-box diagonal"},
      {"RmsError", &F::rmsError, "RMS vertex error over all frames, world units"},
      {"ComponentsPerFrame", &F::componentsPerFrame,
       "components over what the frames allow (one a frame for shapes, three for "
       "trajectories); above 1/2 the compression is weak"},
      {"ColourBytes", &F::colourBytes, "colour: what the colour stream takes in the .dpz", true},
      {"ColourTolerance", &F::colourTolerance,
       "colour: the levels (of 255) a stored colour may differ from the given one", true},
      {"DistanceToDataInput", &F::distanceToDataInput,
       "against the data: the input mesh's RMS distance to it, world units"},
      {"DistanceToDataDecompressed", &F::distanceToDataDecompressed,
       "against the data: the decompressed mesh's RMS distance to it"},
      {"DistanceToDataGrowth", &F::distanceToDataGrowth,
       "against the data: the growth of that distance, percent"},
      {"SlidAlongSurface", &F::slid,
       "against the data: 1 where the take slid along its surface was kept (fewer bits)", true},
      {"DetailLevels", &F::detailLevels, "detail layer: subdivision levels over the tracked mesh",
       true},
      {"DetailBytes", &F::detailBytes, "detail layer: its section of the .dpz", true},
      {"DetailStep", &F::detailStep, "detail layer: the displacements' quantisation step"},
      {"DetailDistanceToDataInput", &F::detailDistanceToDataInput,
       "detail layer, against the data: the fitted fine mesh's RMS distance to it"},
      {"DetailDistanceToDataDecompressed", &F::detailDistanceToDataDecompressed,
       "detail layer, against the data: the decompressed fine mesh's"},
      {"DetailDistanceToDataGrowth", &F::detailDistanceToDataGrowth,
       "detail layer, against the data: the growth, percent"},
  };
  return table;
}

CompressionFigures CompressionFigures::of(const CompressedSequence& sequence, std::size_t frames)
{
  const PcaReport& r = sequence.report;
  const PcaLayout layout = sequence.pca.model.layout;
  CompressionFigures f;
  f.components = static_cast<double>(r.components);
  f.layout = static_cast<double>(layout);
  f.paperD0 = r.paperD0;
  f.paperD1 = r.paperD1;
  f.paperRatio = r.paperRatio;
  f.bitsPerVertexFrame = r.bitsPerVertexFrame;
  f.quantisedPlainBits = r.quantisedPlainBits;
  f.kgError = r.kgError;
  f.maxError = r.maxError;
  f.maxErrorRelative = r.maxErrorRelative;
  f.rmsError = r.rmsError;
  // One component a frame in the shape layout (a weight per frame), three in the trajectory
  // layout (x y z per frame in each basis vector).
  const double possible =
      static_cast<double>(layout == PcaLayout::Trajectories ? 3 * frames : frames);
  f.componentsPerFrame = static_cast<double>(r.components) / possible;
  if (!sequence.colours.empty())
  {
    f.colourBytes = static_cast<double>(r.colourBytes);
    f.colourTolerance = r.colourTolerance;
  }
  if (sequence.detail.levels > 0)
  {
    f.detailLevels = sequence.detail.levels;
    f.detailBytes = static_cast<double>(r.detailBytes);
    f.detailStep = sequence.detail.step;
  }
  return f;
}

std::string CompressionFigures::markdown()
{
  std::string md = "| field data and report.json | what |\n|---|---|\n";
  for (const Field& f : fields())
    md += std::string("| `") + f.name + "` | " + f.doc + " |\n";
  return md;
}

} // namespace dp
