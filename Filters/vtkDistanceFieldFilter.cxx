// SPDX-License-Identifier: BSD-3-Clause
#include "vtkDistanceFieldFilter.h"

#include "dp/field/DistanceField.h"
#include "dp/field/DistanceImage.h"
#include "dp/geometry/NormalEstimation.h"
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
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <type_traits>
#include <vector>

vtkStandardNewMacro(vtkDistanceFieldFilter);

vtkDistanceFieldFilter::vtkDistanceFieldFilter()
{
  // The engine's defaults, not a copy of them.
  const dp::DistanceFieldOptions engine;
  this->BandWidth = engine.bandWidth;
  this->MaximumNumberOfVoxels = static_cast<vtkIdType>(engine.maxActiveVoxels);
}

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

namespace
{
// The bounds of the finite points and their diagonal (a small positive length for one point).
double boundsOf(const std::vector<double>& xyz, double box[6])
{
  box[0] = box[1] = xyz[0];
  box[2] = box[3] = xyz[1];
  box[4] = box[5] = xyz[2];
  for (std::size_t i = 0; i < xyz.size(); i += 3)
    for (int k = 0; k < 3; ++k)
    {
      box[2 * k] = std::min(box[2 * k], xyz[i + k]);
      box[2 * k + 1] = std::max(box[2 * k + 1], xyz[i + k]);
    }
  const double diagonal =
      std::sqrt((box[1] - box[0]) * (box[1] - box[0]) + (box[3] - box[2]) * (box[3] - box[2]) +
                (box[5] - box[4]) * (box[5] - box[4]));
  return diagonal > 0
             ? diagonal
             : std::max(1.0, std::abs(box[0]) + std::abs(box[2]) + std::abs(box[4])) * 1e-3;
}
// The output's arrays the engine writes into directly (nothing is copied): the distance, its
// gradient (the unit vector away from the nearest point) and the band flag; the nearest point's
// index is the engine's, turned into the input's ids afterwards.
struct OutputArrays
{
  vtkNew<vtkFloatArray> distance;
  vtkNew<vtkUnsignedCharArray> inBand;
  vtkNew<vtkFloatArray> gradient;
  std::unique_ptr<std::uint32_t[]> nearestIndex; // every entry written by the engine
  std::size_t samples;

  explicit OutputArrays(vtkIdType count)
      : nearestIndex(new std::uint32_t[static_cast<std::size_t>(count)]),
        samples(static_cast<std::size_t>(count))
  {
    distance->SetName("Distance");
    distance->SetNumberOfTuples(count);
    inBand->SetName("InBand");
    inBand->SetNumberOfTuples(count);
    gradient->SetName("Gradient");
    gradient->SetNumberOfComponents(3);
    gradient->SetNumberOfTuples(count);
  }
  dp::DistanceImageView view()
  {
    return {samples, distance->GetPointer(0), nearestIndex.get(), inBand->GetPointer(0),
            gradient->GetPointer(0)};
  }
};

// The output's point arrays from the engine's image: its own, and the nearest point's id and
// normal.
void fillArrays(vtkImageData* output, const std::vector<vtkIdType>& ids,
                const std::vector<float>& normals, OutputArrays& field)
{
  const auto samples = static_cast<vtkIdType>(field.samples);
  const dp::DistanceImageView image = field.view();
  vtkNew<vtkIdTypeArray> nearest;
  nearest->SetName("NearestPointId");
  nearest->SetNumberOfTuples(samples);
  static_assert(std::is_same<vtkIdType, long long>::value, "vtkIdType is 64-bit here");
  dp::gatherNearest(image, ids.data(), nearest->GetPointer(0));
  output->GetPointData()->SetScalars(field.distance);
  output->GetPointData()->SetVectors(field.gradient);
  output->GetPointData()->AddArray(nearest);
  output->GetPointData()->AddArray(field.inBand);
  if (!normals.empty())
  {
    vtkNew<vtkFloatArray> nearestNormal;
    nearestNormal->SetName("NearestNormal");
    nearestNormal->SetNumberOfComponents(3);
    nearestNormal->SetNumberOfTuples(samples);
    dp::gatherNearest(image, normals.data(), 3, nearestNormal->GetPointer(0));
    output->GetPointData()->AddArray(nearestNormal);
  }
}

// The image's bounds: the filter's, or with `adjust` the points' padded by `padding` times their
// diagonal on every side; returns the points' diagonal.
double imageBounds(const std::vector<double>& xyz, const double filterBounds[6], bool adjust,
                   double padding, double bounds[6])
{
  double box[6];
  const double diagonal = boundsOf(xyz, box);
  std::copy(filterBounds, filterBounds + 6, bounds);
  if (adjust)
    for (int k = 0; k < 3; ++k)
    {
      bounds[2 * k] = box[2 * k] - padding * diagonal;
      bounds[2 * k + 1] = box[2 * k + 1] + padding * diagonal;
    }
  return diagonal;
}

// The image's grid: the extent's dimensions over `bounds`, where a flat axis (no extent, or
// bounds of zero width) gets a spacing of a 200th of the points' diagonal.
dp::ImageGrid gridOver(const int extent[6], const double bounds[6], double diagonal)
{
  dp::ImageGrid grid;
  for (int k = 0; k < 3; ++k)
  {
    grid.dimensions[k] = extent[2 * k + 1] + 1;
    grid.origin[k] = bounds[2 * k];
    grid.spacing[k] = (bounds[2 * k + 1] - bounds[2 * k]) / extent[2 * k + 1];
    if (!(grid.spacing[k] > 0))
      grid.spacing[k] = diagonal / 200.0;
  }
  return grid;
}

void addFieldValue(vtkImageData* output, const char* name, double value)
{
  vtkNew<vtkDoubleArray> a;
  a->SetName(name);
  a->InsertNextValue(value);
  output->GetFieldData()->AddArray(a);
}

// The input's finite points (a warning for any dropped); false, with the error reported for
// `filter`, for a negative or non-finite band width or no point left.
bool targetPoints(vtkAlgorithm* filter, vtkPointSet* input, double bandWidth,
                  vtkDP::TargetPoints& target)
{
  if (bandWidth < 0 || !std::isfinite(bandWidth))
  {
    vtkErrorWithObjectMacro(filter,
                            "BandWidth must be positive, or 0 for 3 voxels; got " << bandWidth);
    return false;
  }
  target = vtkDP::finitePoints(input);
  if (target.dropped > 0)
  {
    vtkWarningWithObjectMacro(
        filter, "dropped " << target.dropped << " input point(s) with NaN or infinite coordinates");
  }
  if (target.ids.empty())
  {
    vtkErrorWithObjectMacro(filter, "the input has no points: a distance field needs at least one");
    return false;
  }
  return true;
}

// The engine's distance image of the points over `grid` into `field` (a band of `bandWidth`, or
// 0 for 3 of the largest spacing); false, with the error reported for `filter`, if it failed.
bool computeImage(vtkAlgorithm* filter, const vtkDP::TargetPoints& target,
                  const dp::ImageGrid& grid, double bandWidth, OutputArrays& field,
                  dp::DistanceImageBand& band)
{
  const double largestSpacing = std::max({grid.spacing[0], grid.spacing[1], grid.spacing[2]});
  try
  {
    band = dp::computeDistanceImage(target.xyz.data(), target.ids.size(), grid,
                                    bandWidth > 0 ? bandWidth : 3 * largestSpacing, field.view());
  }
  catch (const std::exception& e)
  {
    vtkErrorWithObjectMacro(filter, << e.what());
    return false;
  }
  return true;
}

// The points' normals: the input's, else estimated when `compute` (else none).
std::vector<float> normalsOf(const vtkDP::TargetPoints& target, bool compute)
{
  std::vector<float> normals = target.normals;
  if (normals.empty() && compute)
    normals = dp::estimateNormals(target.xyz.data(), target.ids.size());
  return normals;
}

// The output image: its geometry, the point arrays and the band's figures in the field data.
void fillOutput(vtkImageData* output, int extent[6], const dp::ImageGrid& grid,
                const std::vector<vtkIdType>& ids, const std::vector<float>& normals,
                OutputArrays& field, const dp::DistanceImageBand& band)
{
  output->SetExtent(extent);
  output->SetOrigin(grid.origin.data());
  output->SetSpacing(grid.spacing.data());
  fillArrays(output, ids, normals, field);
  addFieldValue(output, "BandWidth", band.bandWidth);
  addFieldValue(output, "BandVoxels", static_cast<double>(band.bandVoxels));
}
} // namespace

int vtkDistanceFieldFilter::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                        vtkInformationVector* outputVector)
{
  vtkPointSet* input = vtkPointSet::GetData(inputVector[0], 0);
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkImageData* output = vtkImageData::GetData(outInfo);
  if (!input || !output)
    return 0;

  vtkDP::TargetPoints target;
  if (!targetPoints(this, input, this->BandWidth, target))
    return 0;

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

  double bounds[6];
  const double diagonal =
      imageBounds(target.xyz, this->Bounds, this->AdjustBounds, this->AdjustDistance, bounds);
  const dp::ImageGrid grid = gridOver(extent, bounds, diagonal);
  this->SetProgressText("Point Distance Field");
  this->UpdateProgress(0.05);
  OutputArrays field(samples);
  dp::DistanceImageBand band;
  if (!computeImage(this, target, grid, this->BandWidth, field, band))
    return 0;
  this->UpdateProgress(0.6);
  if (this->GetAbortExecute())
    return 1;

  const std::vector<float> normals = normalsOf(target, this->ComputeNormals);
  this->UpdateProgress(0.8);

  fillOutput(output, extent, grid, target.ids, normals, field, band);
  this->UpdateProgress(1.0);
  return 1;
}

void vtkDistanceFieldFilter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
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
