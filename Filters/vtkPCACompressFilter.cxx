// SPDX-License-Identifier: BSD-3-Clause
#include "vtkPCACompressFilter.h"

#include "dp/GltfExport.h"
#include "dp/PcaCompression.h"
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

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

vtkStandardNewMacro(vtkPCACompressFilter);

struct vtkPCACompressFilter::Internals
{
  std::vector<double> TimeSteps;       // the input's; empty for a static input
  std::vector<double> Positions;       // frames collected so far, frame-major
  vtkIdType Vertices = -1;             // of frame 0
  vtkSmartPointer<vtkCellArray> Polys; // frame 0's
  std::vector<std::int64_t> Triangles; // frame 0's, for the file
  std::unique_ptr<dp::CompressedSequence> Result;
  double LastInputTime = 0;

  std::size_t frameCount() const { return TimeSteps.empty() ? 1 : TimeSteps.size(); }
  std::size_t collected() const
  {
    return Vertices <= 0 ? 0 : Positions.size() / (3 * static_cast<std::size_t>(Vertices));
  }
  double timeOf(std::size_t frame) const { return TimeSteps.empty() ? 0.0 : TimeSteps[frame]; }
  void clear()
  {
    Positions.clear();
    Vertices = -1;
    Polys = nullptr;
    Triangles.clear();
    Result.reset();
  }

  // The properties' defaults are the engine's (one source: the plugin's XML is checked against
  // them by a test).
  static void takeDefaults(vtkPCACompressFilter& f)
  {
    const dp::PcaOptions o;
    f.Layout = o.layout == dp::PcaLayout::Shapes ? SHAPES : TRAJECTORIES;
    f.ErrorMeasure = o.measure == dp::PcaErrorMeasure::MaxVertexError ? MAX_VERTEX : KARNI_GOTSMAN;
    f.ErrorTarget = o.target;
    f.NumberOfComponents = static_cast<int>(o.components);
    f.Quantize = o.quantise;
    f.GLBMeshoptCompression = dp::GlbOptions().meshopt;
  }

  static dp::PcaOptions optionsOf(const vtkPCACompressFilter& f)
  {
    dp::PcaOptions o;
    o.layout = f.Layout == SHAPES ? dp::PcaLayout::Shapes : dp::PcaLayout::Trajectories;
    o.measure = f.ErrorMeasure == MAX_VERTEX ? dp::PcaErrorMeasure::MaxVertexError
                                             : dp::PcaErrorMeasure::KarniGotsman;
    o.target = f.ErrorTarget;
    o.components = static_cast<std::size_t>(f.NumberOfComponents);
    o.quantise = f.Quantize;
    return o;
  }
};

vtkPCACompressFilter::vtkPCACompressFilter() : Internal(new Internals)
{
  Internals::takeDefaults(*this);
}

vtkPCACompressFilter::~vtkPCACompressFilter()
{
  delete this->Internal;
  this->SetFileName(nullptr);
  this->SetGLBFileName(nullptr);
}

int vtkPCACompressFilter::RequestInformation(vtkInformation*, vtkInformationVector** inputVector,
                                             vtkInformationVector* outputVector)
{
  // Called again whenever a parameter or anything upstream changed: start over.
  this->Internal->clear();
  vtkInformation* inInfo = inputVector[0]->GetInformationObject(0);
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  this->Internal->TimeSteps = vtkDP::forwardTimeSteps(inInfo, outInfo);
  return 1;
}

int vtkPCACompressFilter::RequestUpdateExtent(vtkInformation*, vtkInformationVector** inputVector,
                                              vtkInformationVector* outputVector)
{
  Internals& in = *this->Internal;
  if (in.TimeSteps.empty() || vtkDP::isSecondaryPiece(outputVector->GetInformationObject(0)))
    return 1;
  // Collecting: ask for the next frame; done: ask for what upstream already has.
  const double time = in.Result ? in.LastInputTime : in.timeOf(in.collected());
  inputVector[0]->GetInformationObject(0)->Set(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP(),
                                               time);
  in.LastInputTime = time;
  return 1;
}

namespace
{
void addValue(vtkPolyData* output, const char* name, double value)
{
  vtkNew<vtkDoubleArray> a;
  a->SetName(name);
  a->InsertNextValue(value);
  output->GetFieldData()->AddArray(a);
}
} // namespace

int vtkPCACompressFilter::RequestData(vtkInformation* request, vtkInformationVector** inputVector,
                                      vtkInformationVector* outputVector)
{
  Internals& in = *this->Internal;
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkPolyData* output = vtkPolyData::GetData(outInfo);
  if (vtkDP::isSecondaryPiece(outInfo))
  {
    // Under MPI the whole sequence is on process 0 (see vtkDP::isSecondaryPiece).
    request->Remove(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING());
    output->Initialize();
    return 1;
  }
  auto fail = [&](const std::string& message)
  {
    request->Remove(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING());
    vtkErrorMacro(<< message);
    in.clear();
    return 0;
  };

  if (!in.Result)
  {
    const std::size_t frame = in.collected();
    vtkPolyData* input = vtkPolyData::GetData(inputVector[0], 0);
    if (!input || input->GetNumberOfPoints() == 0)
      return fail("frame " + std::to_string(frame) + ": the input has no points");
    if (frame == 0)
    {
      std::vector<double> positions;
      const char* why = "";
      in.Triangles.clear();
      if (input->GetNumberOfPolys() > 0 &&
          !vtkDP::triangleMesh(input, in.Triangles, positions, why))
        return fail(std::string("frame 0: ") + why);
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
      return fail(
          "frame " + std::to_string(frame) + " has " + std::to_string(input->GetNumberOfPoints()) +
          " points and " + std::to_string(input->GetNumberOfPolys()) + " polygons, frame 0 " +
          std::to_string(in.Vertices) + " and " + std::to_string(in.Polys->GetNumberOfCells()) +
          ": PCA needs one connectivity through the sequence");
    for (vtkIdType i = 0; i < in.Vertices; ++i)
    {
      double p[3];
      input->GetPoint(i, p);
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
        return fail("frame " + std::to_string(frame) + ": point " + std::to_string(i) +
                    " is not finite");
      in.Positions.insert(in.Positions.end(), p, p + 3);
    }
    const std::size_t frames = in.frameCount();
    const std::string progress =
        "PCA Compress: frame " + std::to_string(in.collected()) + " of " + std::to_string(frames);
    this->SetProgressText(progress.c_str());
    this->UpdateProgress(0.5 * static_cast<double>(in.collected()) / static_cast<double>(frames));
    if (this->GetAbortExecute())
      return fail("aborted while reading frame " + std::to_string(frame));
    if (in.collected() < frames)
    {
      request->Set(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING(), 1);
      return 1;
    }
    request->Remove(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING());

    const dp::PcaOptions options = Internals::optionsOf(*this);
    std::vector<double> times = in.TimeSteps;
    if (times.empty())
      times.push_back(0.0);
    this->SetProgressText("PCA Compress: compressing");
    try
    {
      in.Result = std::make_unique<dp::CompressedSequence>(
          dp::compressSequence(in.Positions.data(), static_cast<std::size_t>(in.Vertices), frames,
                               options, in.Triangles, times,
                               [this](double f)
                               {
                                 this->UpdateProgress(0.5 + 0.5 * f);
                                 return !this->GetAbortExecute();
                               }));
    }
    catch (const std::exception& e)
    {
      return fail(std::string("cannot compress: ") + e.what());
    }
    this->WarnIfWeak(frames);
    // Files: written beside and renamed, so a failure never leaves a broken file behind.
    try
    {
      if (this->FileName && *this->FileName)
        dp::writeCompressedSequence(this->FileName, *in.Result);
    }
    catch (const std::exception& e)
    {
      vtkErrorMacro(<< e.what());
    }
    try
    {
      if (this->GLBFileName && *this->GLBFileName)
      {
        dp::GlbOptions glb;
        glb.meshopt = this->GLBMeshoptCompression;
        dp::writeGlb(this->GLBFileName, *in.Result, glb);
      }
    }
    catch (const std::exception& e)
    {
      vtkErrorMacro(<< e.what());
    }
  }

  const std::size_t frame =
      std::min(vtkDP::requestedFrame(in.TimeSteps, outInfo), in.frameCount() - 1);
  const dp::CompressedSequence& result = *in.Result;
  const auto n = in.Vertices;
  vtkNew<vtkDoubleArray> coordinates;
  coordinates->SetNumberOfComponents(3);
  coordinates->SetNumberOfTuples(n);
  result.pca.model.frame(frame, coordinates->GetPointer(0));
  vtkNew<vtkFloatArray> error;
  error->SetName("CompressionError");
  error->SetNumberOfTuples(n);
  const double* original = in.Positions.data() + 3 * static_cast<std::size_t>(n) * frame;
  const double* rebuilt = coordinates->GetPointer(0);
  for (vtkIdType i = 0; i < n; ++i)
    error->SetValue(
        i, static_cast<float>(std::sqrt(std::pow(original[3 * i] - rebuilt[3 * i], 2) +
                                        std::pow(original[3 * i + 1] - rebuilt[3 * i + 1], 2) +
                                        std::pow(original[3 * i + 2] - rebuilt[3 * i + 2], 2))));
  output->Initialize();
  vtkNew<vtkPoints> points;
  points->SetData(coordinates);
  output->SetPoints(points);
  output->SetPolys(in.Polys);
  output->GetPointData()->SetScalars(error);
  const dp::PcaReport& r = result.report;
  addValue(output, "Components", static_cast<double>(r.components));
  addValue(output, "PaperD0", r.paperD0);
  addValue(output, "PaperD1", r.paperD1);
  addValue(output, "PaperRatio", r.paperRatio);
  addValue(output, "BitsPerVertexFrame", r.bitsPerVertexFrame);
  addValue(output, "QuantizedPlainBitsPerVertexFrame", r.quantisedPlainBits);
  addValue(output, "KGError", r.kgError);
  addValue(output, "MaxError", r.maxError);
  addValue(output, "MaxErrorRelative", r.maxErrorRelative);
  addValue(output, "ComponentsPerFrame",
           static_cast<double>(r.components) / static_cast<double>(in.frameCount()));
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
  const dp::PcaReport& r = this->Internal->Result->report;
  if (frames >= 8 && 2 * r.components > frames)
  {
    vtkWarningMacro(<< "kept " << r.components << " of " << frames
                    << " components for the error target: the motion is not low-rank, or the "
                       "tracking shakes; the compression is weak ("
                    << r.bitsPerVertexFrame << " bits per vertex per frame)");
  }
}

void vtkPCACompressFilter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "Layout: " << this->Layout << "\n";
  os << indent << "ErrorMeasure: " << this->ErrorMeasure << "\n";
  os << indent << "ErrorTarget: " << this->ErrorTarget << "\n";
  os << indent << "NumberOfComponents: " << this->NumberOfComponents << "\n";
  os << indent << "Quantize: " << this->Quantize << "\n";
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
  os << indent << "GLBFileName: " << (this->GLBFileName ? this->GLBFileName : "(none)") << "\n";
  os << indent << "GLBMeshoptCompression: " << this->GLBMeshoptCompression << "\n";
}
