// SPDX-License-Identifier: BSD-3-Clause
#include "vtkDPPointSetAccess.h"

#include "vtkCellArray.h"
#include "vtkCellArrayIterator.h"
#include "vtkDataArray.h"
#include "vtkDataObject.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkInformation.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPointSet.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>
#include <cmath>

namespace vtkDP
{

vtkUnsignedCharArray* pointColours(vtkPointSet* input)
{
  if (!input)
    return nullptr;
  vtkPointData* pd = input->GetPointData();
  for (vtkDataArray* candidate :
       {pd->GetArray("RGB"), pd->GetArray("RGBA"), pd->GetArray("Colors"), pd->GetScalars()})
  {
    auto* bytes = vtkUnsignedCharArray::FastDownCast(candidate);
    if (bytes && (bytes->GetNumberOfComponents() == 3 || bytes->GetNumberOfComponents() == 4) &&
        bytes->GetNumberOfTuples() == input->GetNumberOfPoints())
      return bytes;
  }
  return nullptr;
}

TargetPoints finitePoints(vtkPointSet* input)
{
  TargetPoints t;
  if (!input || !input->GetPoints())
    return t;
  const vtkIdType n = input->GetNumberOfPoints();
  vtkDataArray* normals = input->GetPointData()->GetNormals();
  if (!normals)
    normals = input->GetPointData()->GetArray("Normals");
  if (normals && normals->GetNumberOfComponents() != 3)
    normals = nullptr;
  vtkUnsignedCharArray* colours = pointColours(input);
  // Straight from the array when it holds doubles (a million points: a virtual call each
  // otherwise).
  vtkDoubleArray* doubles = vtkDoubleArray::FastDownCast(input->GetPoints()->GetData());
  t.xyz.resize(3 * static_cast<std::size_t>(n));
  t.ids.reserve(static_cast<std::size_t>(n));
  std::size_t kept = 0;
  for (vtkIdType i = 0; i < n; ++i)
  {
    double p[3];
    if (doubles)
      std::copy_n(doubles->GetPointer(3 * i), 3, p);
    else
      input->GetPoint(i, p);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
    {
      ++t.dropped;
      continue;
    }
    std::copy_n(p, 3, &t.xyz[3 * kept++]);
    t.ids.push_back(i);
    if (normals)
    {
      double nrm[3];
      normals->GetTuple(i, nrm);
      t.normals.insert(t.normals.end(), {static_cast<float>(nrm[0]), static_cast<float>(nrm[1]),
                                         static_cast<float>(nrm[2])});
    }
    if (colours)
      for (int c = 0; c < 3; ++c)
        t.colours.push_back(colours->GetTypedComponent(i, c));
  }
  t.xyz.resize(3 * kept);
  return t;
}

bool triangleMesh(vtkPolyData* mesh, std::vector<std::int64_t>& triangles,
                  std::vector<double>& positions, const char*& why)
{
  triangles.clear();
  positions.clear();
  if (!mesh || mesh->GetNumberOfPolys() == 0)
  {
    why = "it has no polygons";
    return false;
  }
  const vtkIdType n = mesh->GetNumberOfPoints();
  positions.resize(3 * n);
  for (vtkIdType i = 0; i < n; ++i)
  {
    mesh->GetPoint(i, &positions[3 * i]);
    if (!std::isfinite(positions[3 * i]) || !std::isfinite(positions[3 * i + 1]) ||
        !std::isfinite(positions[3 * i + 2]))
    {
      why = "a point has a NaN or infinite coordinate";
      return false;
    }
  }
  auto cells = vtk::TakeSmartPointer(mesh->GetPolys()->NewIterator());
  for (cells->GoToFirstCell(); !cells->IsDoneWithTraversal(); cells->GoToNextCell())
  {
    vtkIdType count = 0;
    const vtkIdType* ids = nullptr;
    cells->GetCurrentCell(count, ids);
    for (vtkIdType k = 1; k + 1 < count; ++k)
      triangles.insert(triangles.end(), {ids[0], ids[k], ids[k + 1]});
  }
  if (triangles.empty())
  {
    why = "its polygons have fewer than 3 points";
    return false;
  }
  return true;
}

std::vector<double> forwardTimeSteps(vtkInformation* inInfo, vtkInformation* outInfo)
{
  using SDDP = vtkStreamingDemandDrivenPipeline;
  if (!inInfo->Has(SDDP::TIME_STEPS()))
  {
    outInfo->Remove(SDDP::TIME_STEPS());
    outInfo->Remove(SDDP::TIME_RANGE());
    return {};
  }
  const int n = inInfo->Length(SDDP::TIME_STEPS());
  const double* t = inInfo->Get(SDDP::TIME_STEPS());
  outInfo->Set(SDDP::TIME_STEPS(), t, n);
  if (n > 0)
  {
    const double range[2] = {t[0], t[n - 1]};
    outInfo->Set(SDDP::TIME_RANGE(), range, 2);
  }
  return std::vector<double>(t, t + n);
}

std::size_t frameAtTime(const std::vector<double>& steps, double t)
{
  const auto it =
      std::upper_bound(steps.begin(), steps.end(), t + 1e-9 * std::max(1.0, std::abs(t)));
  return it == steps.begin() ? 0 : static_cast<std::size_t>(it - steps.begin()) - 1;
}
std::size_t requestedFrame(const std::vector<double>& steps, vtkInformation* outInfo)
{
  if (steps.empty() || !outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
    return 0;
  return frameAtTime(steps, outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()));
}

vtkSmartPointer<vtkUnsignedCharArray> colorsArray(const std::uint8_t* rgb, vtkIdType n)
{
  auto colours = vtkSmartPointer<vtkUnsignedCharArray>::New();
  colours->SetName("Colors");
  colours->SetNumberOfComponents(3);
  colours->SetNumberOfTuples(n);
  std::copy(rgb, rgb + 3 * n, colours->GetPointer(0));
  return colours;
}

vtkSmartPointer<vtkFloatArray> distancesArray(const char* name, const double* a, const double* b,
                                              vtkIdType n)
{
  auto out = vtkSmartPointer<vtkFloatArray>::New();
  out->SetName(name);
  out->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i)
    out->SetValue(i, static_cast<float>(std::sqrt(std::pow(a[3 * i] - b[3 * i], 2) +
                                                  std::pow(a[3 * i + 1] - b[3 * i + 1], 2) +
                                                  std::pow(a[3 * i + 2] - b[3 * i + 2], 2))));
  return out;
}

void addFieldValue(vtkDataObject* data, const char* name, double value)
{
  vtkNew<vtkDoubleArray> a;
  a->SetName(name);
  a->InsertNextValue(value);
  data->GetFieldData()->AddArray(a);
}

bool isSecondaryPiece(vtkInformation* outInfo)
{
  return outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER()) &&
         outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER()) > 0;
}

} // namespace vtkDP
