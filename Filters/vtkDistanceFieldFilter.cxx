// SPDX-License-Identifier: BSD-3-Clause
#include "vtkDistanceFieldFilter.h"

#include "dp/DistanceField.h"
#include "vtkDPPointSetAccess.h"

#include "vtkDataArray.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkIdTypeArray.h"
#include "vtkImageData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkSMPTools.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>
#include <cmath>
#include <vector>

vtkStandardNewMacro(vtkDistanceFieldFilter);

vtkDistanceFieldFilter::vtkDistanceFieldFilter() = default;

int vtkDistanceFieldFilter::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPointSet");
  return 1;
}

int vtkDistanceFieldFilter::RequestInformation(vtkInformation*, vtkInformationVector**,
                                               vtkInformationVector* outputVector)
{
  // Like vtkUnsignedDistance: the extent comes from Dimensions; origin and spacing from Bounds,
  // replaced in RequestData by the input's padded bounds when AdjustBounds is on.
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  const int* d = this->Dimensions;
  const int extent[6] = {0, std::max(d[0], 2) - 1, 0, std::max(d[1], 2) - 1,
                         0, std::max(d[2], 2) - 1};
  outInfo->Set(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), extent, 6);
  double origin[3], spacing[3];
  for (int k = 0; k < 3; ++k)
  {
    origin[k] = this->Bounds[2 * k];
    spacing[k] = (this->Bounds[2 * k + 1] - this->Bounds[2 * k]) / extent[2 * k + 1];
    if (spacing[k] <= 0)
      spacing[k] = 1;
  }
  outInfo->Set(vtkDataObject::ORIGIN(), origin, 3);
  outInfo->Set(vtkDataObject::SPACING(), spacing, 3);
  vtkDataObject::SetPointDataActiveScalarInfo(outInfo, VTK_FLOAT, 1);
  return 1;
}

int vtkDistanceFieldFilter::RequestUpdateExtent(vtkInformation*, vtkInformationVector**,
                                                vtkInformationVector*)
{
  return 1; // the whole point set, whatever part of the image is asked for
}

int vtkDistanceFieldFilter::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                        vtkInformationVector* outputVector)
{
  vtkPointSet* input = vtkPointSet::GetData(inputVector[0], 0);
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkImageData* output = vtkImageData::GetData(outInfo);
  if (!input || !output)
    return 0;

  if (this->VoxelSize < 0 || !std::isfinite(this->VoxelSize))
  {
    vtkErrorMacro("VoxelSize must be positive, or 0 for automatic; got " << this->VoxelSize);
    return 0;
  }
  if (this->BandWidth < 0 || !std::isfinite(this->BandWidth))
  {
    vtkErrorMacro("BandWidth must be positive, or 0 for 3 voxels; got " << this->BandWidth);
    return 0;
  }
  const vtkDP::TargetPoints target = vtkDP::finitePoints(input);
  const vtkIdType dropped = target.dropped;
  if (dropped > 0)
  {
    vtkWarningMacro("dropped " << dropped << " input point(s) with NaN or infinite coordinates");
  }
  if (target.ids.empty())
  {
    vtkErrorMacro("the input has no points: a distance field needs at least one");
    return 0;
  }

  // Bounds of the finite points; the automatic voxel size is the paper's 1/200 of the diagonal.
  double box[6] = {target.xyz[0], target.xyz[0], target.xyz[1],
                   target.xyz[1], target.xyz[2], target.xyz[2]};
  for (std::size_t i = 0; i < target.ids.size(); ++i)
    for (int k = 0; k < 3; ++k)
    {
      box[2 * k] = std::min(box[2 * k], target.xyz[3 * i + k]);
      box[2 * k + 1] = std::max(box[2 * k + 1], target.xyz[3 * i + k]);
    }
  double diagonal =
      std::sqrt((box[1] - box[0]) * (box[1] - box[0]) + (box[3] - box[2]) * (box[3] - box[2]) +
                (box[5] - box[4]) * (box[5] - box[4]));
  if (diagonal <= 0)
    diagonal = std::max(1.0, std::abs(box[0]) + std::abs(box[2]) + std::abs(box[4])) * 1e-3;
  const double voxel = this->VoxelSize > 0 ? this->VoxelSize : diagonal / 200.0;

  int extent[6];
  outInfo->Get(vtkStreamingDemandDrivenPipeline::WHOLE_EXTENT(), extent);
  const vtkIdType samples =
      static_cast<vtkIdType>(extent[1] + 1) * (extent[3] + 1) * (extent[5] + 1);
  if (samples > this->MaximumNumberOfVoxels)
  {
    vtkErrorMacro("Dimensions ask for " << samples
                                        << " output samples, over MaximumNumberOfVoxels ("
                                        << this->MaximumNumberOfVoxels << ")");
    return 0;
  }

  dp::DistanceField field;
  dp::DistanceFieldOptions options;
  options.voxelSize = voxel;
  options.bandWidth = this->BandWidth;
  options.maxActiveVoxels = static_cast<std::size_t>(this->MaximumNumberOfVoxels);
  this->UpdateProgress(0.05);
  try
  {
    field.build(target.xyz.data(), target.ids.size(), options);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  this->UpdateProgress(0.4);
  if (this->GetAbortExecute())
    return 1;

  std::vector<float> normals = target.normals;
  if (normals.empty() && this->ComputeNormals)
    normals = dp::estimateNormals(target.xyz.data(), target.ids.size());
  this->UpdateProgress(0.5);

  double bounds[6];
  std::copy(this->Bounds, this->Bounds + 6, bounds);
  if (this->AdjustBounds)
    for (int k = 0; k < 3; ++k)
    {
      bounds[2 * k] = box[2 * k] - this->AdjustDistance * diagonal;
      bounds[2 * k + 1] = box[2 * k + 1] + this->AdjustDistance * diagonal;
    }
  double origin[3], spacing[3];
  for (int k = 0; k < 3; ++k)
  {
    origin[k] = bounds[2 * k];
    spacing[k] = (bounds[2 * k + 1] - bounds[2 * k]) / extent[2 * k + 1];
    if (!(spacing[k] > 0))
      spacing[k] = voxel;
  }
  output->SetExtent(extent);
  output->SetOrigin(origin);
  output->SetSpacing(spacing);

  vtkNew<vtkFloatArray> distance;
  distance->SetName("Distance");
  distance->SetNumberOfTuples(samples);
  vtkNew<vtkFloatArray> gradient;
  gradient->SetName("Gradient");
  gradient->SetNumberOfComponents(3);
  gradient->SetNumberOfTuples(samples);
  vtkNew<vtkIdTypeArray> nearest;
  nearest->SetName("NearestPointId");
  nearest->SetNumberOfTuples(samples);
  vtkNew<vtkUnsignedCharArray> inBand;
  inBand->SetName("InBand");
  inBand->SetNumberOfTuples(samples);
  vtkNew<vtkFloatArray> nearestNormal;
  nearestNormal->SetName("NearestNormal");
  nearestNormal->SetNumberOfComponents(3);
  if (!normals.empty())
    nearestNormal->SetNumberOfTuples(samples);

  const int nx = extent[1] + 1, ny = extent[3] + 1;
  vtkSMPTools::For(0, samples,
                   [&](vtkIdType begin, vtkIdType end)
                   {
                     for (vtkIdType id = begin; id < end; ++id)
                     {
                       const vtkIdType i = id % nx, j = (id / nx) % ny,
                                       k = id / (static_cast<vtkIdType>(nx) * ny);
                       const double x[3] = {origin[0] + i * spacing[0], origin[1] + j * spacing[1],
                                            origin[2] + k * spacing[2]};
                       const dp::DistanceSample s = field.sample(x);
                       distance->SetValue(id, static_cast<float>(s.distance));
                       for (int c = 0; c < 3; ++c)
                         gradient->SetTypedComponent(id, c, static_cast<float>(s.gradient[c]));
                       nearest->SetValue(id, target.ids[static_cast<std::size_t>(s.nearest)]);
                       inBand->SetValue(id, s.inBand ? 1 : 0);
                       if (!normals.empty())
                         for (int c = 0; c < 3; ++c)
                           nearestNormal->SetTypedComponent(id, c, normals[3 * s.nearest + c]);
                     }
                   });
  output->GetPointData()->SetScalars(distance);
  output->GetPointData()->SetVectors(gradient);
  output->GetPointData()->AddArray(nearest);
  output->GetPointData()->AddArray(inBand);
  if (!normals.empty())
    output->GetPointData()->AddArray(nearestNormal);

  auto addValue = [output](const char* name, double value)
  {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name);
    a->InsertNextValue(value);
    output->GetFieldData()->AddArray(a);
  };
  addValue("ActiveVoxels", static_cast<double>(field.activeVoxelCount()));
  addValue("VoxelSize", field.voxelSize());
  addValue("BandWidth", field.bandWidth());
  addValue("FieldMemoryBytes", static_cast<double>(field.memoryBytes()));
  this->UpdateProgress(1.0);
  return 1;
}

void vtkDistanceFieldFilter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "VoxelSize: " << this->VoxelSize << "\n";
  os << indent << "BandWidth: " << this->BandWidth << "\n";
  os << indent << "Dimensions: " << this->Dimensions[0] << " " << this->Dimensions[1] << " "
     << this->Dimensions[2] << "\n";
  os << indent << "Bounds: " << this->Bounds[0] << " " << this->Bounds[1] << " " << this->Bounds[2]
     << " " << this->Bounds[3] << " " << this->Bounds[4] << " " << this->Bounds[5] << "\n";
  os << indent << "AdjustBounds: " << this->AdjustBounds << "\n";
  os << indent << "AdjustDistance: " << this->AdjustDistance << "\n";
  os << indent << "ComputeNormals: " << this->ComputeNormals << "\n";
  os << indent << "MaximumNumberOfVoxels: " << this->MaximumNumberOfVoxels << "\n";
}
