// SPDX-License-Identifier: BSD-3-Clause
#include "vtkDPTrackedFrame.h"

#include "dp/geometry/TriangleMesh.h"
#include "dp/track/FrameFigures.h"
#include "dp/track/Tracker.h"
#include "vtkDPPointSetAccess.h"

#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkStringArray.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>

namespace
{
// The tracked positions on the template's triangles.
void fillGeometry(vtkPolyData* output, vtkCellArray* polys, const dp::FrameResult& r)
{
  const auto n = static_cast<vtkIdType>(r.positions.size() / 3);
  vtkNew<vtkDoubleArray> coordinates;
  coordinates->SetNumberOfComponents(3);
  coordinates->SetNumberOfTuples(n);
  std::copy(r.positions.begin(), r.positions.end(), coordinates->GetPointer(0));
  vtkNew<vtkPoints> points;
  points->SetData(coordinates);
  output->SetPoints(points);
  output->SetPolys(polys);
}

// Per vertex: Displacement (from the template), Residual, Frozen, Rejected, Normals (the active
// normals: ParaView shades the mesh smoothly), and Colors where the points carry colour (then the
// active scalars, which ParaView shows as colours).
void fillPointData(vtkPolyData* output, const vtkDP::TakeContext& take, const dp::FrameResult& r)
{
  const std::vector<double>& rest = *take.rest;
  const auto n = static_cast<vtkIdType>(r.positions.size() / 3);
  vtkNew<vtkFloatArray> displacement;
  displacement->SetName("Displacement");
  displacement->SetNumberOfComponents(3);
  displacement->SetNumberOfTuples(n);
  vtkNew<vtkFloatArray> residual;
  residual->SetName("Residual");
  residual->SetNumberOfTuples(n);
  vtkNew<vtkUnsignedCharArray> frozen, rejected;
  frozen->SetName("Frozen");
  frozen->SetNumberOfTuples(n);
  rejected->SetName("Rejected");
  rejected->SetNumberOfTuples(n);
  for (vtkIdType i = 0; i < n; ++i)
  {
    for (int c = 0; c < 3; ++c)
      displacement->SetTypedComponent(i, c,
                                      static_cast<float>(r.positions[3 * i + c] - rest[3 * i + c]));
    residual->SetValue(i, static_cast<float>(r.residual[i]));
    frozen->SetValue(i, r.frozen[i]);
    rejected->SetValue(i, r.rejected[i]);
  }
  vtkPointData* pd = output->GetPointData();
  pd->SetVectors(displacement);
  std::vector<double> normals(r.positions.size());
  dp::vertexNormalsOf(*take.triangles, r.positions.data(), static_cast<std::size_t>(n),
                      normals.data());
  vtkNew<vtkFloatArray> shading;
  shading->SetName("Normals");
  shading->SetNumberOfComponents(3);
  shading->SetNumberOfTuples(n);
  std::copy(normals.begin(), normals.end(), shading->GetPointer(0));
  pd->SetNormals(shading);
  if (r.colours.size() == 3 * static_cast<std::size_t>(n))
  {
    pd->SetScalars(vtkDP::colorsArray(r.colours.data(), n));
    pd->AddArray(residual);
  }
  else
    pd->SetScalars(residual);
  pd->AddArray(frozen);
  pd->AddArray(rejected);
}

// Field data: the frame's figures (dp::FrameFigures), its well-spread subsample (what a
// compressor downstream judges its error by with DataReach: vtkPCACompressFilter,
// DISTANCE_TO_DATA), and how the template was made.
void fillFieldData(vtkPolyData* output, const vtkDP::TakeContext& take, const dp::FrameResult& r,
                   std::size_t frame)
{
  const dp::FrameFigures figures = dp::FrameFigures::of(r, frame, take.reach);
  for (const dp::FrameFigures::Field& field : dp::FrameFigures::fields())
    vtkDP::addFieldValue(output, field.name, figures.*field.value);
  vtkNew<vtkFloatArray> samples;
  samples->SetName("DataSamples");
  samples->SetNumberOfComponents(3);
  samples->SetNumberOfTuples(static_cast<vtkIdType>(r.samples.size()));
  std::copy(r.samples.points.begin(), r.samples.points.end(), samples->GetPointer(0));
  output->GetFieldData()->AddArray(samples);
  vtkNew<vtkStringArray> made;
  made->SetName("Template");
  made->InsertNextValue(*take.templateMade);
  output->GetFieldData()->AddArray(made);
}

} // namespace

namespace vtkDP
{
void fillTrackedFrame(vtkPolyData* output, const TakeContext& take, const dp::FrameResult& r,
                      std::size_t frame)
{
  fillGeometry(output, take.polys, r);
  fillPointData(output, take, r);
  fillFieldData(output, take, r, frame);
}
} // namespace vtkDP
