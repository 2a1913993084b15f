// SPDX-License-Identifier: BSD-3-Clause
#include "vtkDeformableTrackFilter.h"

#include "dp/field/TemplateMesh.h"
#include "dp/geometry/MeshSurfaceSamples.h"
#include "dp/geometry/TriangleMesh.h"
#include "dp/track/Tracker.h"
#include "dp/track/TrackerOptionTable.h"
#include "vtkDPOptions.h"
#include "vtkDPPointSetAccess.h"
#include "vtkDPTrackedFrame.h"

#include "vtkCellArray.h"
#include "vtkFieldData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkObjectFactory.h"
#include "vtkPointSet.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkUnsignedCharArray.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

vtkStandardNewMacro(vtkDeformableTrackFilter);

// A frame's data under preparation (dp::Tracker::prepare, on another thread beside the frame
// before).
struct vtkDeformableTrackFilter::PendingFrame
{
  std::future<dp::PreparedFrame> data;
};

struct vtkDeformableTrackFilter::Internals
{
  dp::TrackerOptions Options;           // the properties (dp::TrackerOptionTable names them)
  std::unique_ptr<dp::Tracker> Tracker; // made at the first frame
  vtkSmartPointer<vtkCellArray> Polys;  // the template's triangles
  std::vector<dp::FrameResult> Cache;   // frames 0 .. Cache.size()-1
  std::string TemplateSummary;          // how the template was made (field data "Template")
  std::size_t ProgressFrames = 0;       // what the request under way counts its frames out of
  // The pipeline: frame Cache.size()'s data, when its input has been read (with more than one
  // thread, prepared while the frame before was tracked); and the input frame the request under
  // way reads (-1: none).
  PendingFrame Next;
  long long Reading = -1;

  vtkDP::TakeContext context() const
  {
    return {Polys, &Tracker->mesh().triangles(), &Tracker->templatePositions(),
            Tracker->options().recovery.reach * Tracker->voxelSize(), &TemplateSummary};
  }

  // Frame `frame` of the cache as the output, the time it stands for stamped on it.
  void show(vtkPolyData* output, std::size_t frame, double time) const
  {
    output->Initialize();
    vtkDP::fillTrackedFrame(output, context(), Cache[frame], frame);
    output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), time);
  }

  // The last frame tracked as the output (none: empty), while the next one's data is read.
  void showLatest(vtkPolyData* output) const
  {
    output->Initialize();
    if (!Cache.empty())
      vtkDP::fillTrackedFrame(output, context(), Cache.back(), Cache.size() - 1);
  }

  void clear()
  {
    Next = PendingFrame{}; // waits for a preparation under way: it reads the tracker
    Tracker.reset();
    Polys = nullptr;
    Cache.clear();
  }
};

vtkDeformableTrackFilter::vtkDeformableTrackFilter() : Internal(new Internals)
{
  this->SetNumberOfInputPorts(2);
  this->TemplateVertices = static_cast<int>(dp::TemplateOptions().targetVertices);
  this->TemplateSource = TEMPLATE_AUTO;
}

void vtkDeformableTrackFilter::SetTemplateVertices(int vertices)
{
  const int clamped = std::clamp(vertices, static_cast<int>(dp::MinimumTemplateVertices),
                                 static_cast<int>(dp::MaximumTemplateVertices));
  if (clamped != this->TemplateVertices)
  {
    this->TemplateVertices = clamped;
    this->Modified();
  }
}

vtkDPOptionAccessorsMacro(vtkDeformableTrackFilter, TrackerOption, dp::trackerOptions());

vtkDeformableTrackFilter::~vtkDeformableTrackFilter()
{
  delete this->Internal;
}

int vtkDeformableTrackFilter::GetNumberOfCachedFrames()
{
  return static_cast<int>(this->Internal->Cache.size());
}

int vtkDeformableTrackFilter::FillInputPortInformation(int port, vtkInformation* info)
{
  if (port == 0)
  {
    info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPointSet");
  }
  else
  {
    info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData");
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  }
  return 1;
}

void vtkDeformableTrackFilter::ClearTemporalState()
{
  // Called whenever this filter, the template or anything upstream changed: the cached frames
  // are then stale.
  this->Internal->clear();
}

long long vtkDeformableTrackFilter::NextInputFrame(std::size_t requestedFrame)
{
  // Computing: the next frame to track, or, when its data is already under preparation, the
  // frame after it (read before the frame is tracked, so that its data is prepared beside the
  // solve). Answering from the cache, or only the last frame left to track: none, so nothing
  // upstream re-executes.
  Internals& in = *this->Internal;
  const std::size_t done = in.Cache.size();
  const std::size_t wanted = done + (in.Next.data.valid() ? 1 : 0);
  in.Reading = done <= requestedFrame && wanted < this->GetNumberOfInputFrames()
                   ? static_cast<long long>(wanted)
                   : -1;
  return in.Reading;
}

namespace
{
// A frame that is a mesh, copied for the tracker to read as its surface.
struct MeshFrame
{
  dp::PointCloud vertices; // positions, and colours where the frame has them
  std::vector<std::int64_t> triangles;

  dp::MeshSurface surface() const { return dp::meshSurfaceOf(vertices, triangles); }
};

// The frame's mesh, when it has polygons and every point is finite (`why` says otherwise).
bool meshFrameOf(vtkPointSet* input, MeshFrame& frame, const char*& why)
{
  auto* mesh = vtkPolyData::SafeDownCast(input);
  if (!mesh || mesh->GetNumberOfPolys() == 0)
  {
    why = nullptr;
    return false;
  }
  if (!vtkDP::triangleMesh(mesh, frame.triangles, frame.vertices.points, why))
    return false;
  if (vtkUnsignedCharArray* colours = vtkDP::pointColours(input))
  {
    frame.vertices.colorComponents = colours->GetNumberOfComponents();
    const auto* bytes = colours->GetPointer(0);
    frame.vertices.colors.assign(bytes, bytes + colours->GetNumberOfValues());
  }
  return true;
}

// A frame's preparation, beside the solve only when there is a second thread for it (a batch
// process given one thread keeps to one); its errors come out when the frame is tracked.
template <typename Prepare>
std::future<dp::PreparedFrame> startPreparing(Prepare prepare)
{
  const bool beside =
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism) > 1;
  return std::async(beside ? std::launch::async : std::launch::deferred, std::move(prepare));
}

// The time the output request asks for, `frameTime` (the requested frame's) when it names none.
double requestedTimeOf(vtkInformation* outInfo, double frameTime)
{
  return outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP())
             ? outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP())
             : frameTime;
}
} // namespace

bool vtkDeformableTrackFilter::TemplateOf(vtkInformationVector** inputVector, vtkPointSet* frame0,
                                          std::vector<std::int64_t>& triangles,
                                          std::vector<double>& positions)
{
  // Input 1 (repaired, never remeshed); else frame 0: its polygons (repaired and remeshed to
  // TemplateVertices) or its points (a surface reconstructed from them), as TemplateSource says.
  vtkPolyData* given = vtkPolyData::GetData(inputVector[1], 0);
  vtkPointSet* source = given ? given : frame0;
  const std::string what = given ? "the template mesh (input 1)" : "frame 0's mesh";
  std::vector<std::int64_t> polygons;
  std::vector<double> corners;
  vtkPolyData* mesh = vtkPolyData::SafeDownCast(source);
  const char* why = "";
  if (mesh && mesh->GetNumberOfPolys() > 0 && !vtkDP::triangleMesh(mesh, polygons, corners, why))
  {
    vtkErrorMacro(<< what << " cannot be used: " << why);
    return false;
  }
  dp::TemplateOptions options;
  options.targetVertices = static_cast<std::size_t>(this->TemplateVertices);
  options.remesh = !given;
  options.source = given                                          ? dp::TemplateSource::Mesh
                   : this->TemplateSource == TEMPLATE_FROM_POINTS ? dp::TemplateSource::Points
                   : this->TemplateSource == TEMPLATE_FROM_MESH   ? dp::TemplateSource::Mesh
                                                                  : dp::TemplateSource::Auto;
  const vtkDP::TargetPoints points = vtkDP::finitePoints(source);
  const bool fromMesh = options.source == dp::TemplateSource::Mesh ||
                        (options.source == dp::TemplateSource::Auto && !polygons.empty());
  try
  {
    dp::TemplateMesh t =
        fromMesh
            ? dp::makeTemplate(corners.data(), corners.size() / 3, nullptr, polygons, options, what)
            : dp::makeTemplate(points.xyz.data(), points.ids.size(),
                               points.normals.empty() ? nullptr : points.normals.data(), {},
                               options, "frame 0's points");
    triangles = std::move(t.triangles);
    positions = std::move(t.positions);
    this->Internal->TemplateSummary = t.report.summary();
    return true;
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< "no template: " << e.what()
                  << (given ? "" : "; connect a template mesh to input 1, or set TemplateSource"));
    return false;
  }
}

bool vtkDeformableTrackFilter::MakeTracker(vtkInformationVector** inputVector, vtkPointSet* frame0)
{
  Internals& in = *this->Internal;
  std::vector<std::int64_t> triangles;
  std::vector<double> positions;
  if (!this->TemplateOf(inputVector, frame0, triangles, positions))
    return false;
  try
  {
    const std::size_t vertices = positions.size() / 3;
    in.Tracker = std::make_unique<dp::Tracker>(dp::TriangleMesh(triangles, vertices), positions,
                                               this->Internal->Options);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< "cannot track: " << e.what());
    return false;
  }
  // Slivers slide flat without the shear terms: say so once, with the remedy.
  const double slivers = in.Tracker->mesh().poorlyShapedShare(positions.data());
  if (this->Internal->Options.cloth.shear == 0 && slivers > 0.002)
  {
    vtkWarningMacro(<< 100 * slivers
                    << "% of the template's triangles are slivers (nearly flat): with "
                       "ShearStiffness 0 they can fold; set ShearStiffness to about 0.05, "
                       "or give a better-shaped template (e.g. leave the template input "
                       "empty to reconstruct one from frame 0's points)");
  }
  in.Polys = vtkSmartPointer<vtkCellArray>::New();
  for (std::size_t t = 0; t < triangles.size(); t += 3)
  {
    const vtkIdType ids[3] = {triangles[t], triangles[t + 1], triangles[t + 2]};
    in.Polys->InsertNextCell(3, ids);
  }
  return true;
}

vtkDeformableTrackFilter::PendingFrame vtkDeformableTrackFilter::PrepareFrame(std::size_t frame,
                                                                              vtkPointSet* input)
{
  MeshFrame mesh;
  const char* why = nullptr;
  if (this->Internal->Options.meshFrameSamples > 0)
  {
    if (meshFrameOf(input, mesh, why))
      return {startPreparing([&tracker = *this->Internal->Tracker, mesh = std::move(mesh)]
                             { return tracker.prepare(mesh.surface()); })};
    if (why)
      vtkWarningMacro(<< "frame " << frame << ": its polygons are not read as a surface (" << why
                      << "); its points are tracked instead");
  }
  vtkDP::TargetPoints points = vtkDP::finitePoints(input);
  if (points.dropped > 0)
  {
    vtkWarningMacro(<< "frame " << frame << ": dropped " << points.dropped
                    << " point(s) with NaN or infinite coordinates");
  }
  return {startPreparing(
      [&tracker = *this->Internal->Tracker, points = std::move(points)]
      {
        return tracker.prepare(points.xyz.data(), points.ids.size(),
                               points.normals.empty() ? nullptr : points.normals.data(),
                               points.colours.empty() ? nullptr : points.colours.data(), 3);
      })};
}

bool vtkDeformableTrackFilter::TrackFrame(std::size_t frame, PendingFrame pending)
{
  Internals& in = *this->Internal;
  try
  {
    // The frame's data, once its preparation is done: what of it ran beside the frame before
    // cost no waiting.
    const auto waitStart = std::chrono::steady_clock::now();
    dp::PreparedFrame data = pending.data.get();
    const double waited =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - waitStart).count();
    in.Cache.push_back(in.Tracker->track(std::move(data)));
    in.Cache.back().overlapped = std::max(0.0, in.Cache.back().timings.data - waited);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< "frame " << frame << ": " << e.what());
    return false;
  }
  const dp::FrameResult& done = in.Cache.back();
  // Said once per run of thinned frames.
  if (done.thinned && (frame == 0 || !in.Cache[frame - 1].thinned))
  {
    vtkWarningMacro(<< "frame " << frame << " has " << done.pointsGiven
                    << " points: the tracker used " << done.pointsUsed
                    << " of them, spread evenly (its frame point limit; the distance field "
                       "resolves nothing finer)");
  }
  if (done.emptyFrame)
  {
    vtkWarningMacro(<< "frame " << frame << " has no points: the mesh continues its motion");
  }
  else if (done.failed)
  {
    vtkWarningMacro(<< "frame " << frame << " failed after " << done.retries
                    << " retries: " << 100 * done.unexplained << "% of its points are far from "
                    << "the mesh and " << 100 * done.unsupported
                    << "% of the mesh is far from them, and its stiffest edges grew by "
                    << done.tear << " mean edge lengths (a limb torn beyond 2); it is flagged in "
                    << "the field \"Failed\"");
  }
  return true;
}

vtkDeformableTrackFilter::PipelineStep
vtkDeformableTrackFilter::StepPipeline(std::size_t frame, vtkInformationVector** inputVector)
{
  // The input read now is the frame after the one to track, whose data has been prepared since;
  // it is prepared in turn while that frame is tracked. The first frame of a run is only
  // prepared, and the next pass reads the one after it.
  Internals& in = *this->Internal;
  vtkPointSet* input = vtkPointSet::GetData(inputVector[0], 0);
  long long reading = std::exchange(in.Reading, -1);
  PendingFrame current = std::move(in.Next);
  if (!current.data.valid() && reading < 0)
    reading = static_cast<long long>(frame); // the input holds the frame to track
  const bool unreadable = input && input->GetFieldData()->GetAbstractArray("UnreadableFrame");
  if (!current.data.valid() && unreadable)
  {
    vtkErrorMacro(<< "frame " << frame << " could not be read (the reader says why): tracking "
                  << "stops before it"
                  << (frame > 0 ? ", frames 0-" + std::to_string(frame - 1) + " are kept" : ""));
    return PipelineStep::Failed;
  }
  if (!in.Tracker && !this->MakeTracker(inputVector, input))
    return PipelineStep::Failed;
  // A frame after it that could not be read is not prepared: asked for, it stops the run.
  PendingFrame arriving = reading >= 0 && !unreadable
                              ? this->PrepareFrame(static_cast<std::size_t>(reading), input)
                              : PendingFrame{};
  if (!current.data.valid() && reading + 1 < static_cast<long long>(this->GetNumberOfInputFrames()))
  {
    in.Next = std::move(arriving);
    return PipelineStep::Prepared;
  }
  if (!current.data.valid())
    current = std::move(arriving); // the take's last frame: nothing to read beside it
  else
    in.Next = std::move(arriving);
  if (!this->TrackFrame(frame, std::move(current)))
  {
    in.Next = PendingFrame{};
    return PipelineStep::Failed;
  }
  return PipelineStep::Tracked;
}

int vtkDeformableTrackFilter::RequestFrameData(vtkInformation* request,
                                               vtkInformationVector** inputVector,
                                               vtkInformationVector* outputVector)
{
  Internals& in = *this->Internal;
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkPolyData* output = vtkPolyData::GetData(outInfo);
  // A new request (not this filter's own continuation): an abort of an earlier run is over.
  if (!request->Has(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING()))
    this->SetAbortExecute(0);
  const std::size_t target = this->GetRequestedFrame(outInfo);
  const double requestedTime = requestedTimeOf(outInfo, this->GetInputFrameTime(target));
  if (in.Cache.size() <= target)
  {
    const std::size_t frame = in.Cache.size();
    if (!request->Has(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING()))
      in.ProgressFrames = frame == target ? this->GetNumberOfInputFrames() : target + 1;
    this->ShowProgressOf(frame, false);
    this->UpdateProgress(0.0); // the new text while the frame is under way
    const PipelineStep step = this->StepPipeline(frame, inputVector);
    if (step == PipelineStep::Failed)
    {
      ContinueExecuting(request, false);
      return 0;
    }
    if (step == PipelineStep::Prepared)
    {
      ContinueExecuting(request, !this->GetAbortExecute());
      in.showLatest(output);
      return 1;
    }
    this->ShowProgressOf(frame, true);
    this->UpdateProgress(1.0); // the whole work's (frame + 1) / needed
    ContinueExecuting(request, in.Cache.size() <= target && !this->GetAbortExecute());
  }
  else
  {
    // Answered from the cache: the last frame's progress scale stays, so a consumer's walk
    // does not flash 100 % each time it asks again for a frame already done.
    ContinueExecuting(request, false);
  }
  const std::size_t shown = std::min(target, in.Cache.size() - 1);
  // Stopped short of the request (aborted): the output says which frame it is. The executive
  // does not run a request for the same time twice; a request for another time goes on from
  // the frames kept (a change of properties starts the take over).
  in.show(output, shown, shown == target ? requestedTime : this->GetInputFrameTime(shown));
  return 1;
}

void vtkDeformableTrackFilter::SetAbortExecute(vtkTypeBool abort)
{
  this->AbortExecute = abort;
}

void vtkDeformableTrackFilter::ShowProgressOf(std::size_t frame, bool done)
{
  // Progress over what the request needs (ProgressFrames): up to the requested frame, or, when a
  // consumer walks the take one new frame per request (a writer, the compressor, playing), over
  // the whole take.
  // While the frame runs, the shift and scale map its own 0..1 (and the executive's) onto its
  // share, so the bar rises instead of reading 100 % after every frame. Once it is done, every
  // later event (the executive's around the next request, an answer from the cache) holds the
  // bar at the frame's end instead of dipping back to its start.
  const std::size_t needed = std::max(this->Internal->ProgressFrames, frame + 1);
  const std::string text =
      "Deformable Track: frame " + std::to_string(frame + 1) + " of " + std::to_string(needed);
  this->SetProgressText(text.c_str());
  const double total = static_cast<double>(needed);
  if (done)
    this->SetProgressShiftScale(static_cast<double>(frame + 1) / total, 0.0);
  else
    this->SetProgressShiftScale(static_cast<double>(frame) / total, 1.0 / total);
}

void vtkDeformableTrackFilter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  for (const dp::TrackerOptionDescription& option : dp::trackerOptions())
    os << indent << option.name << ": " << option.get(this->Internal->Options) << "\n";
  os << indent << "TemplateVertices: " << this->TemplateVertices << "\n";
  os << indent << "TemplateSource: " << this->TemplateSource << "\n";
  os << indent << "CachedFrames: " << this->Internal->Cache.size() << "\n";
}
