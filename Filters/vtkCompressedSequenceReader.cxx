// SPDX-License-Identifier: BSD-3-Clause
#include "vtkCompressedSequenceReader.h"

#include "dp/compress/DetailCoding.h"
#include "dp/compress/PcaCompression.h"
#include "dp/geometry/SubdivisionMap.h"
#include "dp/geometry/TriangleMesh.h"
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
#include <cstring>
#include <fstream>
#include <memory>

vtkStandardNewMacro(vtkCompressedSequenceReader);

namespace
{
// Frame `frame`'s colours as the active scalars "Colors" (bytes: ParaView shows them as they are)
// and their size in the file as field data "ColourBytes"; nothing for a file without colour.
void addColours(const dp::CompressedSequence& sequence, std::size_t frame, vtkPolyData* output)
{
  if (sequence.colours.empty())
    return;
  const std::size_t n = sequence.pca.model.vertices;
  output->GetPointData()->SetScalars(
      vtkDP::colorsArray(sequence.colours.data() + 3 * n * frame, static_cast<vtkIdType>(n)));
  vtkDP::addFieldValue(output, "ColourBytes", static_cast<double>(sequence.report.colourBytes));
}

// Triangles as VTK cells.
vtkSmartPointer<vtkCellArray> cellsOf(const std::vector<std::int64_t>& triangles)
{
  auto polys = vtkSmartPointer<vtkCellArray>::New();
  for (std::size_t t = 0; t < triangles.size(); t += 3)
  {
    const vtkIdType ids[3] = {triangles[t], triangles[t + 1], triangles[t + 2]};
    polys->InsertNextCell(3, ids);
  }
  return polys;
}
} // namespace

struct vtkCompressedSequenceReader::Internals
{
  std::unique_ptr<dp::CompressedSequence> Sequence;
  vtkSmartPointer<vtkCellArray> Polys;
  std::unique_ptr<dp::SubdivisionMap> Map; // the fine mesh's, when it is read

  // Frame `frame` of the fine mesh: positions, normals, colours, the layer's figures.
  void fillDetail(std::size_t frame, vtkPolyData* output) const
  {
    const std::size_t n = Map->fineVertices(), nb = Map->baseVertices();
    vtkNew<vtkDoubleArray> coordinates;
    coordinates->SetNumberOfComponents(3);
    coordinates->SetNumberOfTuples(static_cast<vtkIdType>(n));
    dp::detailedFrame(*Sequence, *Map, frame, coordinates->GetPointer(0));
    vtkNew<vtkPoints> points;
    points->SetData(coordinates);
    output->SetPoints(points);
    output->SetPolys(Polys);
    std::vector<double> normals(3 * n);
    dp::vertexNormalsOf(Map->fineTriangles(), coordinates->GetPointer(0), n, normals.data());
    vtkNew<vtkFloatArray> shading;
    shading->SetName("Normals");
    shading->SetNumberOfComponents(3);
    shading->SetNumberOfTuples(static_cast<vtkIdType>(n));
    std::copy(normals.begin(), normals.end(), shading->GetPointer(0));
    output->GetPointData()->SetNormals(shading);
    if (!Sequence->colours.empty())
    {
      const std::vector<std::uint8_t> fine =
          dp::subdividedColours(*Map, Sequence->colours.data() + 3 * nb * frame);
      output->GetPointData()->SetScalars(
          vtkDP::colorsArray(fine.data(), static_cast<vtkIdType>(n)));
      vtkDP::addFieldValue(output, "ColourBytes",
                           static_cast<double>(Sequence->report.colourBytes));
    }
    vtkDP::addFieldValue(output, "DetailLevels", Sequence->detail.levels);
    vtkDP::addFieldValue(output, "DetailBytes", static_cast<double>(Sequence->report.detailBytes));
  }
};

vtkCompressedSequenceReader::vtkCompressedSequenceReader() : Internal(new Internals)
{
  this->SetNumberOfInputPorts(0);
}

vtkCompressedSequenceReader::~vtkCompressedSequenceReader()
{
  delete this->Internal;
  this->SetFileName(nullptr);
}

int vtkCompressedSequenceReader::CanReadFile(const char* name)
{
  std::ifstream in(name ? name : "", std::ios::binary);
  char magic[4] = {};
  return in.read(magic, 4) && std::memcmp(magic,
                                          "\x89"
                                          "DPZ",
                                          4) == 0
             ? 1
             : 0;
}

int vtkCompressedSequenceReader::RequestInformation(vtkInformation*, vtkInformationVector**,
                                                    vtkInformationVector* outputVector)
{
  Internals& in = *this->Internal;
  in.Sequence.reset();
  in.Polys = nullptr;
  in.Map.reset();
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  outInfo->Remove(vtkStreamingDemandDrivenPipeline::TIME_STEPS());
  outInfo->Remove(vtkStreamingDemandDrivenPipeline::TIME_RANGE());
  if (!this->FileName || !*this->FileName)
  {
    vtkErrorMacro(<< "no FileName set");
    return 0;
  }
  try
  {
    in.Sequence =
        std::make_unique<dp::CompressedSequence>(dp::readCompressedSequence(this->FileName));
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  if (this->ReadDetail && in.Sequence->detail.levels > 0)
  {
    in.Map = std::make_unique<dp::SubdivisionMap>(
        in.Sequence->triangles, in.Sequence->pca.model.vertices, in.Sequence->detail.levels);
    in.Polys = cellsOf(in.Map->fineTriangles());
  }
  else
    in.Polys = cellsOf(in.Sequence->triangles);
  const std::vector<double>& times = in.Sequence->times;
  outInfo->Set(vtkStreamingDemandDrivenPipeline::TIME_STEPS(), times.data(),
               static_cast<int>(times.size()));
  const double range[2] = {times.front(), times.back()};
  outInfo->Set(vtkStreamingDemandDrivenPipeline::TIME_RANGE(), range, 2);
  return 1;
}

int vtkCompressedSequenceReader::RequestData(vtkInformation*, vtkInformationVector**,
                                             vtkInformationVector* outputVector)
{
  Internals& in = *this->Internal;
  if (!in.Sequence)
    return 0;
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkPolyData* output = vtkPolyData::GetData(outInfo);
  const std::vector<double>& times = in.Sequence->times;
  std::size_t frame = 0;
  if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
  {
    frame = vtkDP::frameAtTime(times,
                               outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()));
  }
  const dp::PcaModel& model = in.Sequence->pca.model;
  output->Initialize();
  if (in.Map)
    in.fillDetail(frame, output);
  else
  {
    vtkNew<vtkDoubleArray> coordinates;
    coordinates->SetNumberOfComponents(3);
    coordinates->SetNumberOfTuples(static_cast<vtkIdType>(model.vertices));
    model.frame(frame, coordinates->GetPointer(0));
    vtkNew<vtkPoints> points;
    points->SetData(coordinates);
    output->SetPoints(points);
    output->SetPolys(in.Polys);
    addColours(*in.Sequence, frame, output);
  }
  vtkDP::addFieldValue(output, "Components", static_cast<double>(model.components()));
  output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), times[frame]);
  return 1;
}

void vtkCompressedSequenceReader::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
  os << indent << "ReadDetail: " << this->ReadDetail << "\n";
}
