// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkPCACompressFilter
 * @brief   compresses a temporal mesh sequence of fixed connectivity by PCA; outputs the
 *          reconstruction and the codec's figures
 *
 * Input: temporal vtkPolyData whose every time step has the same number of points and the same
 * polygons (the output of vtkDeformableTrackFilter, or an animated mesh read from disk). The
 * filter reads every time step in order (CONTINUE_EXECUTING, with progress and abort), then
 * compresses them with dp::compressSequence: principal components of the vertex positions in
 * the paper's layout (basis = trajectories, weights per vertex) or Alexa & Mueller's (basis =
 * shapes, weights per frame), the component count chosen for an error target (Karni-Gotsman
 * error in percent, KGTarget; or the largest vertex error as a fraction of the bounding-box
 * diagonal, MaxVertexTarget) or given; then, unless Quantize is off (the paper's float PCA),
 * quantised, predicted over the mesh and along time, and range-coded. With DISTANCE_TO_DATA the
 * error target is the data's, not the motion's: the decompressed mesh's RMS distance to each
 * frame's points (the input's "DataSamples") may grow by at most FitGrowth percent. The options
 * are described once, in dp::compressionOptions().
 *
 * Output: the reconstruction at the requested time (the input's time steps), the input's
 * polygons, point array "CompressionError" (distance of each vertex to its input position; the
 * active scalars).
 * Colour: where every input frame has point array "Colors" (unsigned char, 3 or 4 components;
 * alpha is dropped), the colours go into the compressed sequence (the .dpz's colour stream, the
 * .glb's COLOR_0), losslessly or within ColourTolerance levels, and the output carries the
 * frame's stored "Colors" too, with field data "ColourBytes" (what the colour stream takes in
 * the .dpz) and "ColourTolerance".
 * Field data: the figures of dp::CompressionFigures (Documentation/MainJob.md lists them):
 * "Components", "Layout" (the one kept), the paper's counts of numbers, "BitsPerVertexFrame",
 * the errors ("KGError", "MaxError", "RmsError"), with DISTANCE_TO_DATA the distance to the data
 * before and after, and "ComponentsPerFrame" (components kept over what the frames allow: above
 * 1/2, with a target of the motion's, the compression is weak and a warning says so; so does an
 * input without polygons, which is unlikely to be one mesh moving).
 *
 * A detail layer (an input from vtkSurfaceDetailFilter: a fine mesh with field data
 * "DetailLevels" > 0, "BasePoints", "BaseTriangles", point data "Detail"): the tracked (base)
 * mesh it carries is compressed as above, then the fine mesh's displacements are carried over to
 * the decompressed base and coded through the take (dp::compressDetailAgainstData: with
 * DISTANCE_TO_DATA the decompressed fine mesh's distance to the data grows by at most
 * FitGrowth percent over the input's; with a motion target the displacements take the base's
 * RMS error). The output is then the decompressed fine mesh, "CompressionError" its vertices'
 * distance to the input's, and field data "DetailLevels", "DetailBytes", "DetailStep" and, with
 * DISTANCE_TO_DATA, "DetailDistanceToDataInput", "DetailDistanceToDataDecompressed",
 * "DetailDistanceToDataGrowth"; colour ("BaseColors") is stored per base vertex and carried to
 * the fine mesh by the subdivision.
 *
 * The filter writes no file: vtkCompressedSequenceWriter writes .dpz (read back by
 * vtkCompressedSequenceReader) and glTF 2.0 binaries (.glb, morph targets); C++ callers holding
 * this filter can write its result with the engine's writers (GetCompressedSequence, the main
 * job does). A failure is reported as an error and kept in GetFailureMessage.
 *
 * The result is kept: any time is answered without recomputing until a parameter or the input
 * changes. Memory: the input's positions for every frame (24 bytes per vertex and frame) plus
 * the decomposition (see dp::PcaCompression.h).
 */
#ifndef vtkPCACompressFilter_h
#define vtkPCACompressFilter_h

#include "DynamicPointsFiltersModule.h" // for export macro
#include "vtkDPTemporalFilter.h"

#include <functional> // for std::function
#include <string>     // for std::string

namespace dp
{
struct CompressedSequence;
struct CompressionFigures;
struct CompressionOptions;
} // namespace dp

class DYNAMICPOINTSFILTERS_EXPORT vtkPCACompressFilter : public vtkDPTemporalFilter
{
public:
  static vtkPCACompressFilter* New();
  vtkTypeMacro(vtkPCACompressFilter, vtkDPTemporalFilter);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum LayoutType
  {
    TRAJECTORIES = 0, // the paper: basis = trajectories, weights per vertex
    SHAPES = 1,       // Alexa & Mueller: basis = shapes, weights per frame (glTF morph targets)
    AUTOMATIC = 2     // both coded, the one of fewer bits kept (field data "Layout" says which)
  };
  enum ErrorMeasureType
  {
    KARNI_GOTSMAN = 0,   // KGTarget, percent
    MAX_VERTEX = 1,      // MaxVertexTarget, a fraction of the bounding-box diagonal
    DISTANCE_TO_DATA = 2 // FitGrowth: the percent the distance to the data may grow by
  };

  ///@{
  /**
   * Any compression option by its name in dp::CompressionOptions ("compression.fitGrowth") or
   * its property name ("FitGrowth"); dp::compressionOptions() describes them all (as does
   * Documentation/Compression.md). A value out of the option's range is clamped to it, as
   * vtkSetClampMacro does; an unknown name or a NaN is an error. The named accessors below are
   * this under the property's name.
   */
  void SetCompressionOption(const char* name, double value);
  double GetCompressionOption(const char* name);
  ///@}

  // The named accessors of the table's options that ParaView's panel shows, written by
  // build/bin/dp-option-code from the table (dp/io/OptionCode.h): edit the table, not here.
  // BEGIN generated options: compression
  // clang-format off
  ///@{
  /** What the error target measures: Karni and Gotsman's error, 100 |A - A'| / |A - E(A)| in
   *  percent, the largest vertex error as a fraction of the bounding-box diagonal, or (for
   *  Deformable Track's output, which carries each frame's points) the percent by which the
   *  decompressed mesh's RMS distance to the points may grow: a target of the data's, not the
   *  motion's (10 suits noisy captures; the main job's default). (compression.measure; range
   *  kg|max-vertex|data) */
  void SetErrorMeasure(int value) { this->SetCompressionOption("ErrorMeasure", value); }
  int GetErrorMeasure() { return static_cast<int>(this->GetCompressionOption("ErrorMeasure")); }
  ///@}
  ///@{
  /** Error Measure KG: the largest Karni-Gotsman error, 100 |A - A'| / |A - E(A)| in percent
   *  (e.g. 0.5, 0.2, 0.1). The compressor meets it on the actual reconstruction.
   *  (compression.kgTarget; range [0.0001, 50], percent) */
  void SetKGTarget(double value) { this->SetCompressionOption("KGTarget", value); }
  double GetKGTarget() { return this->GetCompressionOption("KGTarget"); }
  ///@}
  ///@{
  /** Error Measure max vertex: the largest distance of a vertex from its place, as a fraction of
   *  the sequence's bounding-box diagonal (e.g. 0.002). (compression.maxVertexTarget; range
   *  [1e-07, 0.5], of the diagonal) */
  void SetMaxVertexTarget(double value) { this->SetCompressionOption("MaxVertexTarget", value); }
  double GetMaxVertexTarget() { return this->GetCompressionOption("MaxVertexTarget"); }
  ///@}
  ///@{
  /** Error Measure distance to the data: the percent by which the decompressed mesh's RMS
   *  distance to the tracked points may grow over the tracked mesh's (10 suits noisy captures;
   *  the main job's default). (compression.fitGrowth; range [0.01, 1000], percent) */
  void SetFitGrowth(double value) { this->SetCompressionOption("FitGrowth", value); }
  double GetFitGrowth() { return this->GetCompressionOption("FitGrowth"); }
  ///@}
  ///@{
  /** Error Measure distance to the data: also code the take with each vertex slid along its
   *  surface toward a model of fewer components (the tracker's sliding, which the data do not
   *  see, costs bits), and keep the fewer bits that keep the fit. (compression.slide; range
   *  true|false) */
  void SetSlideAlongSurface(vtkTypeBool value) { this->SetCompressionOption("SlideAlongSurface", value); }
  vtkTypeBool GetSlideAlongSurface() { return static_cast<vtkTypeBool>(this->GetCompressionOption("SlideAlongSurface")); }
  vtkBooleanMacro(SlideAlongSurface, vtkTypeBool);
  ///@}
  ///@{
  /** Trajectories: each component is a motion over time and each vertex has a weight per
   *  component (the paper). Shapes: each component is a shape and each frame has a weight per
   *  component (Alexa and Mueller; what glTF morph targets hold). Automatic: both are coded and
   *  the one of fewer bits kept (field data Layout: 0 trajectories, 1 shapes).
   *  (compression.layout; range trajectories|shapes|automatic) */
  void SetLayout(int value) { this->SetCompressionOption("Layout", value); }
  int GetLayout() { return static_cast<int>(this->GetCompressionOption("Layout")); }
  ///@}
  ///@{
  /** 0: as few bytes as meet the error target. Otherwise this many components, the target then
   *  only setting the quantisation. (compression.components; range [0, 1000000]) */
  void SetNumberOfComponents(int value) { this->SetCompressionOption("NumberOfComponents", value); }
  int GetNumberOfComponents() { return static_cast<int>(this->GetCompressionOption("NumberOfComponents")); }
  ///@}
  ///@{
  /** Quantise, predict and entropy-code the components (default). Off: the paper's float PCA, to
   *  study it (the writers always quantise). (compression.quantise; range true|false) */
  void SetQuantize(vtkTypeBool value) { this->SetCompressionOption("Quantize", value); }
  vtkTypeBool GetQuantize() { return static_cast<vtkTypeBool>(this->GetCompressionOption("Quantize")); }
  vtkBooleanMacro(Quantize, vtkTypeBool);
  ///@}
  ///@{
  /** Where the input carries Colors: the levels (of 255) a stored colour may differ from the
   *  input's. 0 stores them losslessly. More (default 4) holds each vertex's colour while it
   *  stays within that many levels: the colour stops flickering and its stream shrinks (to about
   *  half at 4 on a tracked person), and any larger change still passes.
   *  (compression.colourTolerance; range [0, 64]) */
  void SetColourTolerance(int value) { this->SetCompressionOption("ColourTolerance", value); }
  int GetColourTolerance() { return static_cast<int>(this->GetCompressionOption("ColourTolerance")); }
  ///@}
  // clang-format on
  // END generated options

#ifndef __VTK_WRAP__
  /** All the compression options at once (the writers hand theirs over so). */
  void SetCompressionOptions(const dp::CompressionOptions& options);
  const dp::CompressionOptions& GetCompressionOptions() const;
#endif

  /** Why the last update failed (the error it reported: a frame that differs from frame 0, a
   *  point that is not finite, the codec's refusal), empty when it did not. */
  const char* GetFailureMessage() const;

#ifndef __VTK_WRAP__
  /** The compressed sequence once every frame is in, else null (before an update, after a
   *  failure, on pieces other than 0). Owned by the filter, valid until it re-executes. */
  const dp::CompressedSequence* GetCompressedSequence() const;
#endif

protected:
  vtkPCACompressFilter();
  ~vtkPCACompressFilter() override;

  void ClearTemporalState() override;
  long long NextInputFrame(std::size_t requestedFrame) override;
  int RequestFrameData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

private:
  vtkPCACompressFilter(const vtkPCACompressFilter&) = delete;
  void operator=(const vtkPCACompressFilter&) = delete;

  /** The error measure is DISTANCE_TO_DATA. */
  bool AgainstData() const;

  // RequestFrameData's steps; those returning text return the error, empty when none.
  /** Checks input frame `frame` against frame 0 and keeps its positions. */
  std::string CollectFrame(vtkPolyData* input, std::size_t frame);
  /** The frame's point array "Colors" (unsigned char, 3 or 4 components; alpha dropped), kept
   *  for the colour stream while every frame so far has it. */
  void CollectColours(vtkPolyData* input);
  /** DISTANCE_TO_DATA: the frame's data samples and reach from the input's field data. */
  std::string CollectData(vtkPolyData* input, std::size_t frame);
  /** A detail layer's frame: its base's positions and colours, its displacements. */
  std::string CollectDetail(vtkPolyData* input, std::size_t frame);
  /** The detail layer coded after the base. */
  void CompressDetail(std::size_t frames, const std::function<bool(double)>& progress);
  /** The decompressed fine mesh of `frame` with its error and colours. */
  void FillDetail(std::size_t frame, vtkPolyData* output);
  /** Compresses the frames collected and warns when the compression is weak. */
  std::string Compress();
  /** The figures of the result (field data), with the fit to the data where it was judged. */
  dp::CompressionFigures MeasureFigures(std::size_t frames) const;
  /** Warns when most of the frames' worth of components were kept (weak compression). */
  void WarnIfWeak(std::size_t frames);
  /** The reconstruction of `frame` with its error and the figures. */
  void FillOutput(std::size_t frame, vtkPolyData* output);

  struct Internals;
  Internals* Internal;
};

#endif
