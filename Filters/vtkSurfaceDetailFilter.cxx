// SPDX-License-Identifier: BSD-3-Clause
#include "vtkSurfaceDetailFilter.h"

#include "dp/detail/DetailLevels.h"
#include "dp/detail/DetailOptions.h"
#include "dp/detail/DisplacementFit.h"
#include "dp/geometry/MeshSurfaceSamples.h"
#include "dp/geometry/TriangleMesh.h"
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
#include "vtkStringArray.h"
#include "vtkTypeInt64Array.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkSurfaceDetailFilter);

namespace
{
// Samples of a frame's data the automatic choice measures distances on, when the tracked mesh
// carries none ("DataSamples"): points spread over a mesh frame, or the points themselves.
constexpr std::size_t ChoiceSamples = 20000;

// One fitted frame.
struct FrameDetail
{
  std::vector<double> displacement;
  std::vector<std::uint8_t> observed;
  std::vector<float> residual;
  double seconds = 0;
};

// The input frame as the fit reads it, and how many vertices or points it has.
struct FrameInput
{
  std::optional<dp::FrameSurface> surface;
  std::size_t count = 0;
  bool mesh = false;
  dp::FrameSamples samples; // for the automatic choice
};

// `withSamples`: also the samples the automatic choice measures on (its first frame only).
FrameInput frameInputOf(vtkPointSet* input, std::string& error, bool withSamples)
{
  FrameInput d;
  auto* poly = vtkPolyData::SafeDownCast(input);
  try
  {
    if (poly && poly->GetNumberOfPolys() > 0)
    {
      std::vector<std::int64_t> triangles;
      std::vector<double> positions;
      const char* why = "";
      if (!vtkDP::triangleMesh(poly, triangles, positions, why))
      {
        error = why;
        return d;
      }
      dp::PointCloud vertices;
      vertices.points = std::move(positions);
      const dp::MeshSurface surface = dp::meshSurfaceOf(vertices, triangles);
      d.surface.emplace(dp::FrameSurface::ofMesh(surface));
      d.count = vertices.numberOfPoints();
      d.mesh = true;
      if (withSamples)
        d.samples.points = dp::sampleMeshSurface(surface, ChoiceSamples).points;
      return d;
    }
    const vtkDP::TargetPoints points = vtkDP::finitePoints(input);
    d.surface.emplace(
        dp::FrameSurface::ofPoints(points.xyz.data(), points.ids.size(),
                                   points.normals.empty() ? nullptr : points.normals.data()));
    d.count = points.ids.size();
    const std::size_t stride = std::max<std::size_t>(1, d.count / ChoiceSamples);
    for (std::size_t i = 0; withSamples && i < d.count; i += stride)
      d.samples.points.insert(d.samples.points.end(), &points.xyz[3 * i], &points.xyz[3 * i] + 3);
  }
  catch (const std::exception& e)
  {
    error = e.what();
    d.surface.reset();
  }
  return d;
}

// The tracked mesh's samples of its data ("DataSamples"), when it carries them.
bool samplesOf(vtkPolyData* base, dp::FrameSamples& samples)
{
  vtkDataArray* a = base->GetFieldData()->GetArray("DataSamples");
  if (!a || a->GetNumberOfComponents() != 3 || a->GetNumberOfTuples() == 0)
    return false;
  samples.points.resize(3 * static_cast<std::size_t>(a->GetNumberOfTuples()));
  for (vtkIdType i = 0; i < a->GetNumberOfTuples(); ++i)
    a->GetTuple(i, &samples.points[3 * static_cast<std::size_t>(i)]);
  return true;
}

template <typename Array>
vtkSmartPointer<Array> namedArray(const char* name, int components, vtkIdType tuples)
{
  auto a = vtkSmartPointer<Array>::New();
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(tuples);
  return a;
}

// The properties in world units for this take: the reach a share of the base's mean edge length.
dp::DisplacementFitOptions fitOptionsOf(const dp::DetailOptions& options,
                                        const std::vector<std::int64_t>& baseTriangles,
                                        const std::vector<double>& positions)
{
  dp::DisplacementFitOptions fit;
  fit.reach = options.reach * dp::meanEdgeLength(baseTriangles, positions.data());
  fit.smoothness = options.smoothness;
  fit.normalAngle = options.normalAngle;
  return fit;
}

// The levels the automatic choice takes, measured on the first frame's data (`choice` says what
// it measured); none when the data hold no surface (`choice` says why).
std::optional<int> chosenLevels(vtkPolyData* base, vtkPointSet* data,
                                const std::vector<std::int64_t>& baseTriangles,
                                const std::vector<double>& positions,
                                const dp::DisplacementFitOptions& fit, std::string& choice)
{
  std::string error;
  FrameInput d = frameInputOf(data, error, true);
  if (!d.surface)
  {
    // Nothing to measure detail on: the tracked mesh is given as it is.
    choice = "none: the first frame's data (input 1) hold no surface (" + error + ")";
    return std::nullopt;
  }
  dp::FrameSamples samples;
  if (!samplesOf(base, samples))
    samples = std::move(d.samples);
  const dp::DetailLevelChoice c = dp::chooseDetailLevels(
      baseTriangles, positions, *d.surface, samples, d.mesh ? d.count : d.count / 2, fit);
  choice = c.summary;
  return c.levels;
}

// Triangles (3 ids each) as VTK cells.
vtkSmartPointer<vtkCellArray> cellsOf(const std::vector<std::int64_t>& tri)
{
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  for (std::size_t t = 0; t < tri.size(); t += 3)
  {
    const vtkIdType ids[3] = {tri[t], tri[t + 1], tri[t + 2]};
    cells->InsertNextCell(3, ids);
  }
  return cells;
}

// The fine mesh's positions: the base (`basePoints`) subdivided by `map` and displaced along its
// normals as fitted; `normals` (3 per fine vertex) gets the displaced mesh's vertex normals.
vtkSmartPointer<vtkDoubleArray> finePositions(const dp::SubdivisionMap& map,
                                              const double* basePoints, const FrameDetail& detail,
                                              std::vector<double>& normals)
{
  const std::size_t n = map.fineVertices();
  std::vector<double> smooth(3 * n);
  map.subdivide(basePoints, smooth.data(), normals.data());
  auto coordinates = namedArray<vtkDoubleArray>("Points", 3, static_cast<vtkIdType>(n));
  dp::displaceAlongNormals(smooth.data(), normals.data(), detail.displacement.data(), n,
                           coordinates->GetPointer(0));
  dp::vertexNormalsOf(map.fineTriangles(), coordinates->GetPointer(0), n, normals.data());
  return coordinates;
}

// Per fine vertex (`n` of them): Normals (the active normals), Observed and Residual; the
// displacements ("Detail") are returned, for the caller to add beside the colours or as the
// active scalars.
vtkSmartPointer<vtkFloatArray> addFinePointData(vtkPointData* pd, const FrameDetail& detail,
                                                const std::vector<double>& normals, std::size_t n)
{
  const auto nv = static_cast<vtkIdType>(n);
  auto displacement = namedArray<vtkFloatArray>("Detail", 1, nv);
  auto shading = namedArray<vtkFloatArray>("Normals", 3, nv);
  auto observed = namedArray<vtkUnsignedCharArray>("Observed", 1, nv);
  auto residual = namedArray<vtkFloatArray>("Residual", 1, nv);
  std::copy(detail.residual.begin(), detail.residual.end(), residual->GetPointer(0));
  for (std::size_t i = 0; i < n; ++i)
  {
    displacement->SetValue(static_cast<vtkIdType>(i), static_cast<float>(detail.displacement[i]));
    observed->SetValue(static_cast<vtkIdType>(i), detail.observed[i]);
    for (int c = 0; c < 3; ++c)
      shading->SetTypedComponent(static_cast<vtkIdType>(i), c,
                                 static_cast<float>(normals[3 * i + c]));
  }
  pd->SetNormals(shading);
  pd->AddArray(observed);
  pd->AddArray(residual);
  return displacement;
}

// The tracked mesh's colours carried to the fine mesh by `map` (the active scalars, with
// `displacement` beside them; the base's in field data "BaseColors"); without colours,
// `displacement` is the active scalars.
void addFineColours(vtkPolyData* base, const dp::SubdivisionMap& map, vtkFloatArray* displacement,
                    vtkPolyData* output)
{
  vtkPointData* pd = output->GetPointData();
  if (vtkUnsignedCharArray* colours = vtkDP::pointColours(base))
  {
    const std::size_t nb = map.baseVertices();
    const int k = colours->GetNumberOfComponents();
    auto baseColours =
        namedArray<vtkUnsignedCharArray>("BaseColors", 3, static_cast<vtkIdType>(nb));
    for (std::size_t i = 0; i < nb; ++i)
      for (int c = 0; c < 3; ++c)
        baseColours->SetValue(static_cast<vtkIdType>(3 * i + c),
                              colours->GetValue(static_cast<vtkIdType>(k * i + c)));
    const std::vector<std::uint8_t> fine = dp::subdividedColours(map, baseColours->GetPointer(0));
    pd->SetScalars(vtkDP::colorsArray(fine.data(), static_cast<vtkIdType>(map.fineVertices())));
    pd->AddArray(displacement);
    output->GetFieldData()->AddArray(baseColours);
  }
  else
    pd->SetScalars(displacement);
}

// The frame's figures in field data: the levels, the share of the `n` fine vertices whose
// normal line met the data, the fit's seconds, and what chose the levels.
void addDetailFigures(vtkPolyData* output, int levels, const FrameDetail& detail, std::size_t n,
                      const std::string& choice)
{
  vtkDP::addFieldValue(output, "DetailLevels", levels);
  std::size_t seen = 0;
  for (std::uint8_t o : detail.observed)
    seen += o;
  vtkDP::addFieldValue(output, "DetailObserved",
                       static_cast<double>(seen) / static_cast<double>(n));
  vtkDP::addFieldValue(output, "DetailSeconds", detail.seconds);
  vtkNew<vtkStringArray> said;
  said->SetName("DetailChoice");
  said->InsertNextValue(choice);
  output->GetFieldData()->AddArray(said);
}
} // namespace

struct vtkSurfaceDetailFilter::Internals
{
  // The properties (dp::detailOptions() describes them); their defaults are the engine's.
  dp::DetailOptions Options;
  std::vector<double> TimeSteps;
  double LastDataTime = 0;
  std::vector<std::int64_t> BaseTriangles;
  std::unique_ptr<dp::SubdivisionMap> Map;
  std::unique_ptr<dp::DisplacementFitter> Fitter;
  vtkSmartPointer<vtkCellArray> FinePolys;
  dp::DisplacementFitOptions FitOptions; // the properties in world units, for this take
  std::string Choice;                    // what the automatic choice measured
  std::vector<std::optional<FrameDetail>> Cache;

  void clear()
  {
    BaseTriangles.clear();
    Fitter.reset();
    Map.reset();
    FinePolys = nullptr;
    Choice.clear();
    Cache.clear();
  }
  bool cached(std::size_t frame) const { return frame < Cache.size() && Cache[frame]; }
};

vtkSurfaceDetailFilter::vtkSurfaceDetailFilter() : Internal(new Internals)
{
  this->SetNumberOfInputPorts(2);
}

vtkDPOptionAccessorsMacro(vtkSurfaceDetailFilter, DetailOption, dp::detailOptions());

vtkSurfaceDetailFilter::~vtkSurfaceDetailFilter()
{
  delete this->Internal;
}

int vtkSurfaceDetailFilter::FillInputPortInformation(int port, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), port == 0 ? "vtkPolyData" : "vtkPointSet");
  return 1;
}

int vtkSurfaceDetailFilter::RequestInformation(vtkInformation*, vtkInformationVector** inputVector,
                                               vtkInformationVector* outputVector)
{
  // Called when a property, an input or anything upstream changed: what was fitted is stale.
  this->Internal->clear();
  this->LevelsUsed = -1;
  this->Internal->TimeSteps = vtkDP::forwardTimeSteps(inputVector[0]->GetInformationObject(0),
                                                      outputVector->GetInformationObject(0));
  return 1;
}

int vtkSurfaceDetailFilter::RequestUpdateExtent(vtkInformation*, vtkInformationVector** inputVector,
                                                vtkInformationVector* outputVector)
{
  // The tracked mesh at the time asked for; the data too, unless that frame is fitted already
  // (then upstream stays where it is and reads nothing).
  Internals& in = *this->Internal;
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  if (!outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
    return 1;
  const double time = outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
  inputVector[0]->GetInformationObject(0)->Set(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP(),
                                               time);
  const std::size_t frame = vtkDP::requestedFrame(in.TimeSteps, outInfo);
  const bool reuse = in.cached(frame) || this->LevelsUsed == 0;
  if (!reuse)
    in.LastDataTime = time;
  inputVector[1]->GetInformationObject(0)->Set(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP(),
                                               in.LastDataTime);
  return 1;
}

bool vtkSurfaceDetailFilter::Prepare(vtkPolyData* base, vtkPointSet* data)
{
  Internals& in = *this->Internal;
  std::vector<double> positions;
  const char* why = "";
  if (base->GetNumberOfPolys() == 0 || !vtkDP::triangleMesh(base, in.BaseTriangles, positions, why))
  {
    vtkErrorMacro(<< "the tracked mesh (input 0) cannot be subdivided: "
                  << (base->GetNumberOfPolys() == 0 ? "it has no polygons" : why));
    return false;
  }
  in.FitOptions = fitOptionsOf(in.Options, in.BaseTriangles, positions);
  try
  {
    int levels = in.Options.levels;
    if (levels == AUTOMATIC)
    {
      const std::optional<int> chosen =
          chosenLevels(base, data, in.BaseTriangles, positions, in.FitOptions, in.Choice);
      if (!chosen)
      {
        vtkWarningMacro(<< "no detail layer: " << in.Choice);
        this->LevelsUsed = 0;
        return true;
      }
      levels = *chosen;
    }
    else
      in.Choice = std::to_string(levels) + " level(s), as asked";
    this->LevelsUsed = levels;
    if (levels == 0)
      return true;
    in.Map = std::make_unique<dp::SubdivisionMap>(in.BaseTriangles, positions.size() / 3, levels);
    in.Fitter = std::make_unique<dp::DisplacementFitter>(*in.Map);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< "no detail layer: " << e.what());
    return false;
  }
  in.FinePolys = cellsOf(in.Map->fineTriangles());
  return true;
}

bool vtkSurfaceDetailFilter::FitFrame(std::size_t frame, vtkPolyData* base, vtkPointSet* data)
{
  Internals& in = *this->Internal;
  const auto started = std::chrono::steady_clock::now();
  const std::size_t n = in.Map->fineVertices();
  if (static_cast<std::size_t>(base->GetNumberOfPoints()) != in.Map->baseVertices())
  {
    vtkErrorMacro(<< "frame " << frame << ": the tracked mesh has " << base->GetNumberOfPoints()
                  << " points, frame 0 " << in.Map->baseVertices()
                  << ": the detail layer needs one connectivity through the take");
    return false;
  }
  std::vector<double> positions(3 * in.Map->baseVertices()), fine(3 * n), normals(3 * n);
  for (vtkIdType i = 0; i < base->GetNumberOfPoints(); ++i)
    base->GetPoint(i, &positions[3 * static_cast<std::size_t>(i)]);
  in.Map->subdivide(positions.data(), fine.data(), normals.data());
  FrameDetail detail;
  std::string error;
  FrameInput d = frameInputOf(data, error, false);
  if (d.surface)
  {
    d.surface->orientAgainst(fine.data(), normals.data(), n, in.FitOptions.reach);
    dp::DisplacementFit fit =
        in.Fitter->fit(fine.data(), normals.data(), *d.surface, in.FitOptions);
    detail.displacement = std::move(fit.displacement);
    detail.observed = std::move(fit.met);
    detail.residual.assign(fit.residual.begin(), fit.residual.end());
  }
  else
  {
    // A frame without data (an empty frame, one the tracker continued through): no detail.
    vtkWarningMacro(<< "frame " << frame << ": no detail (" << error
                    << "); the subdivided tracked mesh is given");
    detail.displacement.assign(n, 0.0);
    detail.observed.assign(n, 0);
    detail.residual.assign(n, -1.0f);
  }
  detail.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (in.Cache.size() <= frame)
    in.Cache.resize(frame + 1);
  in.Cache[frame] = std::move(detail);
  return true;
}

void vtkSurfaceDetailFilter::FillOutput(std::size_t frame, vtkPolyData* base, vtkPolyData* output)
{
  Internals& in = *this->Internal;
  const FrameDetail& detail = *in.Cache[frame];
  const std::size_t nb = in.Map->baseVertices(), n = in.Map->fineVertices();
  auto basePoints = namedArray<vtkDoubleArray>("BasePoints", 3, static_cast<vtkIdType>(nb));
  for (std::size_t i = 0; i < nb; ++i)
    base->GetPoint(static_cast<vtkIdType>(i), basePoints->GetPointer(0) + 3 * i);
  std::vector<double> normals(3 * n);
  vtkNew<vtkPoints> points;
  points->SetData(finePositions(*in.Map, basePoints->GetPointer(0), detail, normals));
  output->SetPoints(points);
  output->SetPolys(in.FinePolys);
  const vtkSmartPointer<vtkFloatArray> displacement =
      addFinePointData(output->GetPointData(), detail, normals, n);
  vtkFieldData* fd = output->GetFieldData();
  fd->ShallowCopy(base->GetFieldData());
  addFineColours(base, *in.Map, displacement, output);
  fd->AddArray(basePoints);
  auto triangles = namedArray<vtkTypeInt64Array>(
      "BaseTriangles", 3, static_cast<vtkIdType>(in.BaseTriangles.size() / 3));
  std::copy(in.BaseTriangles.begin(), in.BaseTriangles.end(), triangles->GetPointer(0));
  fd->AddArray(triangles);
  addDetailFigures(output, this->LevelsUsed, detail, n, in.Choice);
}

int vtkSurfaceDetailFilter::RequestData(vtkInformation*, vtkInformationVector** inputVector,
                                        vtkInformationVector* outputVector)
{
  Internals& in = *this->Internal;
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkPolyData* output = vtkPolyData::GetData(outInfo);
  vtkPolyData* base = vtkPolyData::GetData(inputVector[0], 0);
  vtkPointSet* data = vtkPointSet::GetData(inputVector[1], 0);
  output->Initialize();
  if (!base || base->GetNumberOfPoints() == 0 || vtkDP::isSecondaryPiece(outInfo))
    return 1;
  const std::size_t frame = vtkDP::requestedFrame(in.TimeSteps, outInfo);
  if (this->LevelsUsed < 0 && !this->Prepare(base, data))
    return 0;
  if (this->LevelsUsed > 0 && !in.cached(frame) && !this->FitFrame(frame, base, data))
    return 0;
  if (this->LevelsUsed == 0)
  {
    output->ShallowCopy(base);
    vtkDP::addFieldValue(output, "DetailLevels", 0);
    vtkNew<vtkStringArray> choice;
    choice->SetName("DetailChoice");
    choice->InsertNextValue(in.Choice);
    output->GetFieldData()->AddArray(choice);
  }
  else
    this->FillOutput(frame, base, output);
  if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
    output->GetInformation()->Set(
        vtkDataObject::DATA_TIME_STEP(),
        outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()));
  return 1;
}

void vtkSurfaceDetailFilter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  for (const auto& option : dp::detailOptions())
    os << indent << option.name << ": " << option.said(option.get(this->Internal->Options)) << "\n";
  os << indent << "LevelsUsed: " << this->LevelsUsed << "\n";
}
