// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkCompressedSequenceWriter
 * @brief   writes a whole temporal mesh sequence compressed: .dpz, or glTF 2.0 (.glb)
 *
 * Input: temporal vtkPolyData of fixed connectivity (the output of vtkDeformableTrackFilter, or
 * an animated mesh read from disk). Write() runs vtkPCACompressFilter on the input (which pulls
 * every time step; principal components chosen for the error target, quantised, predicted
 * over the mesh and along time, range-coded; see dp/compress/PcaCompression.h) and writes its
 * result with the engine's writers to FileName, in the format its extension names:
 *  - .dpz: DynamicPoints' compressed sequence (version, checksums), read back by
 *    vtkCompressedSequenceReader;
 *  - .glb: glTF 2.0 binary, one morph target per shape component and one animation of the
 *    weights at 24 frames per second (always the shape layout, which glTF needs).
 * Where every input frame has point array "Colors" (see vtkPCACompressFilter), the .dpz carries
 * them (its colour stream; losslessly, or within ColourTolerance levels) and the .glb as COLOR_0
 * with a colour morph target per frame (see dp/export/GltfExport.h). The file is written beside its
 * name and renamed when complete, so a failure never leaves a broken file. In ParaView this is File
 * > Save Data for .dpz and .glb.
 *
 * Under MPI only piece 0 writes (the sequence is whole there; see vtkDPTemporalFilter):
 * ParaView sets Piece and NumberOfPieces to each process's rank and count.
 * Memory and time: as vtkPCACompressFilter, which this writer runs on its input.
 */
#ifndef vtkCompressedSequenceWriter_h
#define vtkCompressedSequenceWriter_h

#include "DynamicPointsFiltersModule.h" // for export macro
#include "vtkWriter.h"

namespace dp
{
struct CompressionOptions;
}

class DYNAMICPOINTSFILTERS_EXPORT vtkCompressedSequenceWriter : public vtkWriter
{
public:
  static vtkCompressedSequenceWriter* New();
  vtkTypeMacro(vtkCompressedSequenceWriter, vtkWriter);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /** The file to write; its extension (.dpz or .glb) chooses the format. */
  vtkSetStringMacro(FileName);
  vtkGetStringMacro(FileName);
  ///@}

  ///@{
  /** The compression options, as vtkPCACompressFilter's (dp::compressionOptions() describes
   *  them) but Quantize: a file always holds the quantised, coded components. .glb is always
   *  in the SHAPES layout, which glTF needs. */
  void SetCompressionOption(const char* name, double value);
  double GetCompressionOption(const char* name);
  ///@}

  // The named accessors of the table's options that ParaView's panel shows, written by
  // build/bin/dp-option-code from the table (dp/io/OptionCode.h): edit the table, not here.
  // BEGIN generated options: compression except Quantize
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

  ///@{
  /** .glb only: store the buffers compressed by meshoptimizer (EXT_meshopt_compression, then
   *  required by the file): smaller files for web viewers (three.js, Babylon.js); Blender 3.4
   *  and VTK 9.2 cannot read them. Default off. */
  vtkSetMacro(MeshoptCompression, vtkTypeBool);
  vtkGetMacro(MeshoptCompression, vtkTypeBool);
  vtkBooleanMacro(MeshoptCompression, vtkTypeBool);
  ///@}

  ///@{
  /** The piece this writer's process asks its input for, of NumberOfPieces (defaults 0 of 1);
   *  pieces other than 0 write nothing. */
  vtkSetClampMacro(Piece, int, 0, VTK_INT_MAX);
  vtkGetMacro(Piece, int);
  vtkSetClampMacro(NumberOfPieces, int, 1, VTK_INT_MAX);
  vtkGetMacro(NumberOfPieces, int);
  ///@}

protected:
  vtkCompressedSequenceWriter();
  ~vtkCompressedSequenceWriter() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  void WriteData() override;

  char* FileName = nullptr;
  dp::CompressionOptions* Options; // the codec's; their defaults are the engine's
  vtkTypeBool MeshoptCompression;
  int Piece = 0;
  int NumberOfPieces = 1;

private:
  vtkCompressedSequenceWriter(const vtkCompressedSequenceWriter&) = delete;
  void operator=(const vtkCompressedSequenceWriter&) = delete;
};

#endif
