// SPDX-License-Identifier: BSD-3-Clause
#include "vtkPCACompressFilter.h"

#include "dp/compress/ColourStream.h"
#include "dp/compress/CompressionFigures.h"
#include "dp/compress/CompressionOptions.h"
#include "dp/compress/DataFitCompression.h"
#include "dp/compress/DetailCoding.h"
#include "dp/compress/PcaCompression.h"
#include "dp/detail/DetailCompression.h"
#include "dp/geometry/SubdivisionMap.h"
#include "vtkDPOptions.h"
#include "vtkDPPointSetAccess.h"

#include "vtkCellArray.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <vector>

vtkStandardNewMacro(vtkPCACompressFilter);

namespace
{

// Frame `frame`'s colours of `sequence` as point array "Colors" of `output` (none without colour).
void addColours(const dp::CompressedSequence& sequence, std::size_t frame, vtkPolyData* output)
{
  if (sequence.colours.empty())
    return;
  const std::size_t n = sequence.pca.model.vertices;
  output->GetPointData()->AddArray(
      vtkDP::colorsArray(sequence.colours.data() + 3 * n * frame, static_cast<vtkIdType>(n)));
}
} // namespace

struct vtkPCACompressFilter::Internals
{
  std::vector<double> Positions;       // frames collected so far, frame-major
  vtkIdType Vertices = -1;             // of frame 0
  vtkSmartPointer<vtkCellArray> Polys; // frame 0's
  std::vector<std::int64_t> Triangles; // frame 0's, for the file
  std::unique_ptr<dp::CompressedSequence> Result;
  std::string Failure; // of the last update
  // Each frame's "Colors" (r g b), frame-major, while every frame so far had them.
  std::vector<std::uint8_t> Colours;
  bool ColoursInEveryFrame = true;
  // DISTANCE_TO_DATA: each frame's data samples and reach (the input's field data), and the fit
  // before and after.
  std::vector<dp::FrameSamples> Samples;
  double Reach = 0;
  dp::DataFit Before, After;
  bool Slid = false; // the take slid along its surface was kept
  // A detail layer (DetailLevels > 0): the fine mesh's connectivity, its map from the base
  // (Positions and Triangles then hold the base), the fitted displacements, frame-major.
  int DetailLevels = 0;
  vtkIdType FineVertices = 0;
  vtkSmartPointer<vtkCellArray> FinePolys;
  std::unique_ptr<dp::SubdivisionMap> Map;
  std::vector<double> Displacements;
  dp::DetailCompression DetailFit;
  // The properties (dp::compressionOptions() describes them); their defaults are the engine's.
  dp::CompressionOptions Options;
  dp::CompressionFigures Figures; // of Result

  std::size_t collected() const
  {
    return Vertices <= 0 ? 0 : Positions.size() / (3 * static_cast<std::size_t>(Vertices));
  }
  void clear()
  {
    Positions.clear();
    Vertices = -1;
    Polys = nullptr;
    Triangles.clear();
    Result.reset();
    Colours.clear();
    ColoursInEveryFrame = true;
    Samples.clear();
    Reach = 0;
    Before = After = dp::DataFit{};
    Slid = false;
    DetailLevels = 0;
    FineVertices = 0;
    FinePolys = nullptr;
    Map.reset();
    Displacements.clear();
    DetailFit = dp::DetailCompression{};
  }

  // A detail layer's frame 0: the base's connectivity and size, its map to the fine mesh.
  std::string startDetail(vtkPolyData* input, vtkDataArray* base, vtkDataArray* triangles,
                          const std::string& at)
  {
    Vertices = base->GetNumberOfTuples();
    Triangles.resize(3 * static_cast<std::size_t>(triangles->GetNumberOfTuples()));
    for (std::size_t i = 0; i < Triangles.size(); ++i)
      Triangles[i] = static_cast<std::int64_t>(
          triangles->GetComponent(static_cast<vtkIdType>(i / 3), static_cast<int>(i % 3)));
    try
    {
      Map = std::make_unique<dp::SubdivisionMap>(Triangles, static_cast<std::size_t>(Vertices),
                                                 DetailLevels);
    }
    catch (const std::exception& e)
    {
      return at + "the base mesh cannot be subdivided: " + e.what();
    }
    FineVertices = input->GetNumberOfPoints();
    FinePolys = input->GetPolys();
    if (static_cast<std::size_t>(FineVertices) != Map->fineVertices())
      return at + std::to_string(FineVertices) + " fine points, but " +
             std::to_string(DetailLevels) + " levels over the base make " +
             std::to_string(Map->fineVertices());
    return {};
  }

  // A detail layer's frame: its base positions and its displacements appended.
  std::string appendDetail(vtkDataArray* base, vtkDataArray* detail, const std::string& at)
  {
    for (vtkIdType i = 0; i < Vertices; ++i)
    {
      double p[3];
      base->GetTuple(i, p);
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
        return at + "base point " + std::to_string(i) + " is not finite";
      Positions.insert(Positions.end(), p, p + 3);
    }
    for (vtkIdType i = 0; i < FineVertices; ++i)
    {
      const double d = detail->GetTuple1(i);
      if (!std::isfinite(d))
        return at + "the detail of point " + std::to_string(i) + " is not finite";
      Displacements.push_back(d);
    }
    return {};
  }

  // A detail layer's frame: its base's colours ("BaseColors") kept while every frame has them.
  void appendBaseColours(vtkFieldData* fd)
  {
    auto* colours = vtkUnsignedCharArray::SafeDownCast(fd->GetArray("BaseColors"));
    if (!ColoursInEveryFrame || !colours || colours->GetNumberOfComponents() != 3 ||
        colours->GetNumberOfTuples() != Vertices)
    {
      ColoursInEveryFrame = false;
      Colours.clear();
    }
    else
      Colours.insert(Colours.end(), colours->GetPointer(0), colours->GetPointer(0) + 3 * Vertices);
  }

  // Result: the collected take compressed so that its distance to the data grows by at most
  // the fit growth allowed (DISTANCE_TO_DATA), with its fit before and after.
  void compressAgainstData(std::size_t frames, const std::vector<double>& times,
                           const std::function<bool(double)>& progress)
  {
    std::vector<const dp::FrameSamples*> samples;
    for (const dp::FrameSamples& s : Samples)
      samples.push_back(&s);
    dp::DataFitCompression c =
        dp::compressAgainstData(dp::TriangleMesh(Triangles, static_cast<std::size_t>(Vertices)),
                                Positions.data(), frames, samples, Reach, Options.fitGrowth / 100,
                                dp::pcaOptionsOf(Options), Options.slide, times, progress);
    Before = c.tracked;
    After = c.decompressed;
    Slid = c.slid;
    Result = std::make_unique<dp::CompressedSequence>(std::move(c.sequence));
  }
};

vtkPCACompressFilter::vtkPCACompressFilter() : Internal(new Internals) {}

vtkDPOptionAccessorsMacro(vtkPCACompressFilter, CompressionOption, dp::compressionOptions());

void vtkPCACompressFilter::SetCompressionOptions(const dp::CompressionOptions& options)
{
  try
  {
    dp::compressionOptions().check(options);
  }
  catch (const std::invalid_argument& e)
  {
    vtkErrorMacro(<< e.what());
    return;
  }
  this->Internal->Options = options;
  this->Modified();
}

const dp::CompressionOptions& vtkPCACompressFilter::GetCompressionOptions() const
{
  return this->Internal->Options;
}

bool vtkPCACompressFilter::AgainstData() const
{
  return this->Internal->Options.measure == dp::CompressionMeasure::DistanceToData;
}

vtkPCACompressFilter::~vtkPCACompressFilter()
{
  delete this->Internal;
}

const char* vtkPCACompressFilter::GetFailureMessage() const
{
  return this->Internal->Failure.c_str();
}

const dp::CompressedSequence* vtkPCACompressFilter::GetCompressedSequence() const
{
  return this->Internal->Result.get();
}

void vtkPCACompressFilter::ClearTemporalState()
{
  this->Internal->clear();
}

long long vtkPCACompressFilter::NextInputFrame(std::size_t)
{
  // Collecting: the next frame; done: none (any time is answered from the result).
  const Internals& in = *this->Internal;
  return in.Result ? -1 : static_cast<long long>(in.collected());
}

std::string vtkPCACompressFilter::CollectFrame(vtkPolyData* input, std::size_t frame)
{
  Internals& in = *this->Internal;
  if (!input || input->GetNumberOfPoints() == 0)
    return "frame " + std::to_string(frame) + ": the input has no points";
  vtkDataArray* levels = input->GetFieldData()->GetArray("DetailLevels");
  if (frame == 0)
    in.DetailLevels =
        levels && levels->GetNumberOfTuples() > 0 ? static_cast<int>(levels->GetTuple1(0)) : 0;
  if (in.DetailLevels > 0)
  {
    const std::string error = this->CollectDetail(input, frame);
    if (!error.empty() || !this->AgainstData())
      return error;
    return this->CollectData(input, frame);
  }
  if (frame == 0)
  {
    std::vector<double> positions;
    const char* why = "";
    in.Triangles.clear();
    if (input->GetNumberOfPolys() > 0 && !vtkDP::triangleMesh(input, in.Triangles, positions, why))
      return std::string("frame 0: ") + why;
    in.Vertices = input->GetNumberOfPoints();
    in.Polys = input->GetPolys();
    if (input->GetNumberOfPolys() == 0)
    {
      // A raw point sequence has the same count each frame but not the same points.
      vtkWarningMacro(<< "frame 0 has no polygons: PCA Compress expects one mesh moving (point "
                         "i the same surface point in every frame); the points of a scanned "
                         "sequence are not, and compress poorly. Track them first "
                         "(Deformable Track)");
    }
  }
  else if (input->GetNumberOfPoints() != in.Vertices ||
           input->GetNumberOfPolys() != in.Polys->GetNumberOfCells())
    return "frame " + std::to_string(frame) + " has " + std::to_string(input->GetNumberOfPoints()) +
           " points and " + std::to_string(input->GetNumberOfPolys()) + " polygons, frame 0 " +
           std::to_string(in.Vertices) + " and " + std::to_string(in.Polys->GetNumberOfCells()) +
           ": PCA needs one connectivity through the sequence";
  for (vtkIdType i = 0; i < in.Vertices; ++i)
  {
    double p[3];
    input->GetPoint(i, p);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      return "frame " + std::to_string(frame) + ": point " + std::to_string(i) + " is not finite";
    in.Positions.insert(in.Positions.end(), p, p + 3);
  }
  this->CollectColours(input);
  return this->AgainstData() ? this->CollectData(input, frame) : std::string();
}

std::string vtkPCACompressFilter::CollectDetail(vtkPolyData* input, std::size_t frame)
{
  Internals& in = *this->Internal;
  const std::string at = "frame " + std::to_string(frame) + ": ";
  vtkFieldData* fd = input->GetFieldData();
  vtkDataArray* base = fd->GetArray("BasePoints");
  vtkDataArray* triangles = fd->GetArray("BaseTriangles");
  vtkDataArray* detail = input->GetPointData()->GetArray("Detail");
  if (!base || base->GetNumberOfComponents() != 3 || !triangles ||
      triangles->GetNumberOfComponents() != 3 || !detail ||
      detail->GetNumberOfTuples() != input->GetNumberOfPoints())
    return at + "a detail layer needs field data BasePoints and BaseTriangles and point data "
                "Detail (Surface Detail's output carries them)";
  if (frame == 0)
  {
    const std::string error = in.startDetail(input, base, triangles, at);
    if (!error.empty())
      return error;
  }
  else if (base->GetNumberOfTuples() != in.Vertices ||
           input->GetNumberOfPoints() != in.FineVertices)
    return at + "its base or fine mesh differs in size from frame 0's: the detail layer needs "
                "one connectivity through the take";
  const std::string error = in.appendDetail(base, detail, at);
  if (!error.empty())
    return error;
  in.appendBaseColours(fd);
  return {};
}

void vtkPCACompressFilter::CompressDetail(std::size_t frames,
                                          const std::function<bool(double)>& progress)
{
  Internals& in = *this->Internal;
  const dp::FittedDetail fitted{*in.Map, in.Positions.data(), in.Displacements.data(), frames};
  if (this->AgainstData())
  {
    std::vector<const dp::FrameSamples*> samples;
    for (const dp::FrameSamples& s : in.Samples)
      samples.push_back(&s);
    in.DetailFit = dp::compressDetailAgainstData(*in.Result, fitted, samples, in.Reach,
                                                 in.Options.fitGrowth / 100, progress);
  }
  else
    dp::compressDetailAtDeviation(*in.Result, fitted, std::max(in.Result->report.rmsError, 1e-12));
}

void vtkPCACompressFilter::CollectColours(vtkPolyData* input)
{
  Internals& in = *this->Internal;
  auto* colours = vtkUnsignedCharArray::SafeDownCast(input->GetPointData()->GetArray("Colors"));
  const int components = colours ? colours->GetNumberOfComponents() : 0;
  if (!in.ColoursInEveryFrame || (components != 3 && components != 4) ||
      colours->GetNumberOfTuples() != in.Vertices)
  {
    // Colour in some frames only is not a colour stream: none is kept.
    in.ColoursInEveryFrame = false;
    in.Colours.clear();
    return;
  }
  const unsigned char* c = colours->GetPointer(0);
  for (vtkIdType i = 0; i < in.Vertices; ++i, c += components)
    in.Colours.insert(in.Colours.end(), c, c + 3); // alpha dropped
}

std::string vtkPCACompressFilter::CollectData(vtkPolyData* input, std::size_t frame)
{
  Internals& in = *this->Internal;
  vtkDataArray* samples = input->GetFieldData()->GetArray("DataSamples");
  vtkDataArray* reach = input->GetFieldData()->GetArray("DataReach");
  if (!samples || samples->GetNumberOfComponents() != 3 || !reach || reach->GetNumberOfTuples() < 1)
    return "frame " + std::to_string(frame) +
           " has no DataSamples and DataReach: the distance to the data needs the points the "
           "mesh was tracked to (Deformable Track's output carries them)";
  dp::FrameSamples s;
  for (vtkIdType i = 0; i < samples->GetNumberOfTuples(); ++i)
  {
    double p[3];
    samples->GetTuple(i, p);
    s.points.insert(s.points.end(), p, p + 3);
  }
  in.Samples.push_back(std::move(s));
  in.Reach = reach->GetTuple1(0);
  return {};
}

std::string vtkPCACompressFilter::Compress()
{
  Internals& in = *this->Internal;
  const std::size_t frames = this->GetNumberOfInputFrames();
  std::vector<double> times(frames);
  for (std::size_t t = 0; t < frames; ++t)
    times[t] = this->GetInputFrameTime(t);
  this->SetProgressText("PCA Compress: compressing");
  const std::function<bool(double)> progress = [this](double f)
  {
    this->UpdateProgress(0.5 + 0.5 * f);
    return !this->GetAbortExecute();
  };
  try
  {
    if (this->AgainstData())
      in.compressAgainstData(frames, times, progress);
    else
      in.Result = std::make_unique<dp::CompressedSequence>(
          dp::compressSequence(in.Positions.data(), static_cast<std::size_t>(in.Vertices), frames,
                               dp::pcaOptionsOf(in.Options), in.Triangles, times, progress));
    if (in.ColoursInEveryFrame && !in.Colours.empty())
      dp::setColours(*in.Result, std::move(in.Colours), in.Options.colourTolerance);
    if (in.DetailLevels > 0)
    {
      this->SetProgressText("PCA Compress: compressing the detail layer");
      this->CompressDetail(frames, progress);
    }
  }
  catch (const std::exception& e)
  {
    in.Result.reset();
    return std::string("cannot compress: ") + e.what();
  }
  in.Figures = this->MeasureFigures(frames);
  if (!this->AgainstData()) // against the data, the data decide the bits
    this->WarnIfWeak(frames);
  return {};
}

dp::CompressionFigures vtkPCACompressFilter::MeasureFigures(std::size_t frames) const
{
  const Internals& in = *this->Internal;
  dp::CompressionFigures f = dp::CompressionFigures::of(*in.Result, frames);
  if (in.Before.samples > 0)
  {
    f.distanceToDataInput = in.Before.rms;
    f.distanceToDataDecompressed = in.After.rms;
    f.distanceToDataGrowth = 100 * (in.After.rms / in.Before.rms - 1);
    f.slid = in.Slid ? 1 : 0;
  }
  if (in.DetailLevels > 0 && in.DetailFit.fitted.samples > 0)
  {
    f.detailDistanceToDataInput = in.DetailFit.fitted.rms;
    f.detailDistanceToDataDecompressed = in.DetailFit.decompressed.rms;
    f.detailDistanceToDataGrowth = 100 * in.DetailFit.growth;
  }
  return f;
}

void vtkPCACompressFilter::FillOutput(std::size_t frame, vtkPolyData* output)
{
  const Internals& in = *this->Internal;
  const dp::CompressedSequence& result = *in.Result;
  output->Initialize();
  if (in.DetailLevels > 0)
    this->FillDetail(frame, output);
  else
  {
    const auto n = in.Vertices;
    vtkNew<vtkDoubleArray> coordinates;
    coordinates->SetNumberOfComponents(3);
    coordinates->SetNumberOfTuples(n);
    result.pca.model.frame(frame, coordinates->GetPointer(0));
    const double* original = in.Positions.data() + 3 * static_cast<std::size_t>(n) * frame;
    vtkNew<vtkPoints> points;
    points->SetData(coordinates);
    output->SetPoints(points);
    output->SetPolys(in.Polys);
    output->GetPointData()->SetScalars(
        vtkDP::distancesArray("CompressionError", original, coordinates->GetPointer(0), n));
    addColours(result, frame, output);
  }
  for (const auto& field : dp::CompressionFigures::fields())
  {
    const double value = this->Internal->Figures.*field.value;
    if (!std::isnan(value))
      vtkDP::addFieldValue(output, field.name, value);
  }
}

void vtkPCACompressFilter::FillDetail(std::size_t frame, vtkPolyData* output)
{
  const Internals& in = *this->Internal;
  const dp::CompressedSequence& result = *in.Result;
  const dp::SubdivisionMap& map = *in.Map;
  const std::size_t n = map.fineVertices(), nb = map.baseVertices();
  vtkNew<vtkDoubleArray> coordinates;
  coordinates->SetNumberOfComponents(3);
  coordinates->SetNumberOfTuples(static_cast<vtkIdType>(n));
  dp::detailedFrame(result, map, frame, coordinates->GetPointer(0));
  // The input's fine positions: its tracked base subdivided and displaced as fitted.
  std::vector<double> smooth(3 * n), normals(3 * n), fitted(3 * n);
  map.subdivide(in.Positions.data() + 3 * nb * frame, smooth.data(), normals.data());
  dp::displaceAlongNormals(smooth.data(), normals.data(), in.Displacements.data() + n * frame, n,
                           fitted.data());
  vtkNew<vtkPoints> points;
  points->SetData(coordinates);
  output->SetPoints(points);
  output->SetPolys(in.FinePolys);
  output->GetPointData()->SetScalars(vtkDP::distancesArray(
      "CompressionError", fitted.data(), coordinates->GetPointer(0), static_cast<vtkIdType>(n)));
  if (!result.colours.empty())
  {
    const std::vector<std::uint8_t> fine =
        dp::subdividedColours(map, result.colours.data() + 3 * nb * frame);
    output->GetPointData()->AddArray(vtkDP::colorsArray(fine.data(), static_cast<vtkIdType>(n)));
  }
}

int vtkPCACompressFilter::RequestFrameData(vtkInformation* request,
                                           vtkInformationVector** inputVector,
                                           vtkInformationVector* outputVector)
{
  Internals& in = *this->Internal;
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  auto fail = [&](const std::string& message)
  {
    ContinueExecuting(request, false);
    in.clear();
    in.Failure = message;
    vtkErrorMacro(<< message);
    return 0;
  };
  if (!in.Result)
  {
    if (in.collected() == 0)
      in.Failure.clear();
    // Collecting: one frame per pass, then the compression.
    const std::size_t frame = in.collected();
    const std::string error = this->CollectFrame(vtkPolyData::GetData(inputVector[0], 0), frame);
    if (!error.empty())
      return fail(error);
    const std::size_t frames = this->GetNumberOfInputFrames();
    const std::string progress =
        "PCA Compress: frame " + std::to_string(in.collected()) + " of " + std::to_string(frames);
    this->SetProgressText(progress.c_str());
    this->UpdateProgress(0.5 * static_cast<double>(in.collected()) / static_cast<double>(frames));
    if (this->GetAbortExecute())
      return fail("aborted while reading frame " + std::to_string(frame));
    ContinueExecuting(request, in.collected() < frames);
    if (in.collected() < frames)
      return 1;
    const std::string failure = this->Compress();
    if (!failure.empty())
      return fail(failure);
  }
  vtkPolyData* output = vtkPolyData::GetData(outInfo);
  this->FillOutput(std::min(this->GetRequestedFrame(outInfo), this->GetNumberOfInputFrames() - 1),
                   output);
  if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
    output->GetInformation()->Set(
        vtkDataObject::DATA_TIME_STEP(),
        outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()));
  return 1;
}

void vtkPCACompressFilter::WarnIfWeak(std::size_t frames)
{
  // PCA pays off when a few shapes explain the take; keeping most of the frames' worth of
  // components means the motion is not low-rank, or the tracking shakes.
  const dp::CompressionFigures& f = this->Internal->Figures;
  if (frames >= 8 && f.componentsPerFrame > 0.5)
  {
    vtkWarningMacro(<< "kept " << f.components << " of " << f.components / f.componentsPerFrame
                    << " possible components for the error target: the motion is not low-rank, "
                       "or the tracking shakes; the compression is weak ("
                    << f.bitsPerVertexFrame << " bits per vertex per frame)");
  }
}

void vtkPCACompressFilter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  for (const auto& option : dp::compressionOptions())
    os << indent << option.name << ": " << option.said(option.get(this->Internal->Options)) << "\n";
}
