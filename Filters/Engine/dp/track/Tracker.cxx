// SPDX-License-Identifier: BSD-3-Clause
// The tracker (Tracker.h): its construction, a frame's data made ready, a frame's course from its
// data to its result, and what the next frames remember of it. The tries at a frame (start,
// coarse level, fine solve, quality, retries) are TrackerAttempts.cxx's.
#include "dp/track/Tracker.h"

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/MeshSurfaceSamples.h"
#include "dp/track/ClothRegions.h"
#include "dp/track/ColourTerm.h"
#include "dp/track/FrameData.h"
#include "dp/track/FrameOrientation.h"
#include "dp/track/TrackerOptionTable.h"
#include "dp/track/TrackerParts.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace dp
{
namespace
{
// Checked before E_int measures the template (a NaN would only say "no area").
std::vector<double> finiteTemplate(std::vector<double> positions)
{
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (!std::isfinite(positions[i]))
      throw std::invalid_argument("the template mesh's vertex " + std::to_string(i / 3) +
                                  " has a NaN or infinite coordinate");
  return positions;
}

// Too little data to say where a surface is: fewer than a handful of points, or all of them
// within a couple of voxels. (NaN coordinates are left for FrameData's error.)
bool tooLittleData(const double* points, std::size_t count, double voxel)
{
  return count < 10 || boundingBoxDiagonal(points, count) < 2 * voxel;
}
} // namespace

Tracker::Tracker(TriangleMesh mesh, std::vector<double> templatePositions,
                 const TrackerOptions& options)
    : Mesh(std::move(mesh)), Template(finiteTemplate(std::move(templatePositions))),
      Options(options), Cloth(Mesh, Template.data(), options.cloth),
      P(std::make_unique<Parts>(options.recovery))
{
  checkTrackerOptions(options);
  TemplateRest = Cloth.restState();
  softenByRegion(Cloth, Mesh, Template.data(), options.softening, options.creases);
  Voxel = options.voxelSize > 0 ? options.voxelSize : boundingBoxDiagonal(Template) / 200.0;
  P->Fine = FineSolver::make(options, Mesh, Cloth.lengthScale());
  if (options.graph.enabled)
  {
    const std::size_t nodes = options.graph.nodes > 0
                                  ? options.graph.nodes
                                  : std::clamp<std::size_t>(Mesh.numberOfVertices() / 5, 30, 600);
    P->Graph = std::make_unique<DeformationGraph>(
        Mesh, Template.data(), nodes, std::max<std::size_t>(1, options.graph.influences));
    P->Registration = std::make_unique<GraphRegistration>(*P->Graph, Cloth.lengthScale(), Voxel);
    P->Registration->setAcceleration(options.graph.acceleration);
  }
}

Tracker::~Tracker() = default;

void Tracker::readColourReference(const FrameData& frame, const std::vector<double>& positions)
{
  if (!P->ColourFine.empty() || !frame.colourField() || Options.colourWeight <= 0)
    return;
  const ColourField& field = *frame.colourField();
  const std::size_t nv = Mesh.numberOfVertices();
  P->ColourFine = vertexColours(field, positions.data(), nv, field.kernel());
  P->ColourCoarse =
      vertexColours(field, positions.data(), nv, field.kernel(Options.colourCoarseKernel));
}

void Tracker::readVertexColours(const FrameData* frame, FrameResult& result)
{
  if (frame && frame->colourField())
  {
    const ColourField& field = *frame->colourField();
    P->LastColours = vertexColours(field, result.positions.data(), Mesh.numberOfVertices(),
                                   field.kernel(), &P->LastColours);
  }
  result.colours.clear();
  for (float c : P->LastColours)
    result.colours.push_back(
        static_cast<std::uint8_t>(std::lround(255 * std::clamp(c < 0 ? 0.5f : c, 0.0f, 1.0f))));
}

void Tracker::reset()
{
  P->ColourFine.clear();
  P->ColourCoarse.clear();
  P->LastColours.clear();
  P->Predictor.clear();
  P->Recovery.reset();
  P->LastGood.clear();
  P->LastFailed = false;
  if (P->Registration)
    P->Registration->resetReference();
}

void Tracker::restartFrom(const std::vector<double>& positions)
{
  if (P->Graph)
  {
    const DeformationGraph::State state = P->Graph->fit(positions.data());
    P->Predictor.restartFrom(positions, &state);
  }
  else
    P->Predictor.restartFrom(positions);
}

void Tracker::orientData(FrameData& frame) const
{
  orientToShape(frame, Mesh, P->Predictor.empty() ? Template : P->Predictor.last(), Voxel);
}

void Tracker::keep(Attempt&& best, FrameResult& result)
{
  result.startPositions = best.startPositions;
  result.coarsePositions = best.coarsePositions;
  result.positions = std::move(best.positions);
  result.residual = std::move(best.residual);
  result.rejected = std::move(best.rejected);
  result.frozen = std::move(best.frozen);
  result.iterations = best.iterations;
  result.solvedOn = best.solvedOn;
  result.coarseIterations = best.coarseIterations;
  result.internalEnergy = best.internalEnergy;
  result.distanceEnergy = best.distanceEnergy;
  result.unexplained = best.quality.unexplained;
  result.unsupported = best.quality.unsupported;
  result.tear = best.quality.tear;
  result.noise = best.quality.noise;
  result.timings.prediction = best.timings.prediction;
  result.timings.coarse = best.timings.coarse;
  result.timings.fine = best.timings.fine;
  result.timings.quality = best.timings.quality;
}

void Tracker::remember(const FrameResult& result)
{
  if (P->Graph)
  {
    const DeformationGraph::State state = P->Graph->fit(result.positions.data());
    // After a retry from another start, the motion before it says nothing about the motion after.
    if (result.kept == 1)
      P->Predictor.restartFrom(result.positions, &state);
    else
      P->Predictor.push(result.positions, &state);
    // A failed frame's shape may be garbage (a frame a thousand times too large): the graph's
    // reference gives way to it only once failures persist, when the take itself has changed
    // (as the quality's baseline does).
    if (Options.graph.yieldRate > 0 && P->Recovery.referencesFollow())
      P->Registration->yield(state, Options.graph.yieldRate, Options.graph.yieldLimit * Voxel);
    if (!P->Recovery.inDoubt())
      P->LastGoodState = state;
  }
  else if (result.kept == 1)
    P->Predictor.restartFrom(result.positions);
  else
    P->Predictor.push(result.positions);
  if (!P->Recovery.inDoubt())
    P->LastGood = result.positions;
  P->LastFailed = P->Recovery.inDoubt();
}

PreparedFrame::PreparedFrame() = default;
PreparedFrame::PreparedFrame(PreparedFrame&&) noexcept = default;
PreparedFrame& PreparedFrame::operator=(PreparedFrame&&) noexcept = default;
PreparedFrame::~PreparedFrame() = default;

PreparedFrame Tracker::prepare(const double* points, std::size_t count, const float* normals,
                               const std::uint8_t* colours, int colourComponents) const
{
  const auto start = std::chrono::steady_clock::now();
  FrameDataOptions dataOptions;
  dataOptions.voxelSize = Voxel;
  dataOptions.bandWidth = Options.bandWidth;
  dataOptions.surfaceArea = Cloth.lengthScale() * Cloth.lengthScale();
  const std::size_t nv = Mesh.numberOfVertices();
  dataOptions.spreadCount = Options.coverage.weight > 0 || Options.recovery.enabled
                                ? (Options.coverage.points > 0 ? Options.coverage.points : 4 * nv)
                                : 0;
  dataOptions.maxPoints = Options.maxFramePoints;
  // Point indices are 32-bit: beyond that a frame must be thinned.
  if (Options.maxFramePoints == 0 && count > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("a frame of " + std::to_string(count) +
                                " points is more than the tracker can index (2^32 - 1): set a "
                                "frame point limit (maxFramePoints) to thin it");
  PreparedFrame frame;
  frame.Count = count;
  frame.Owner = this;
  // A frame with too little data is kept like an empty one (the motion continued) and flagged:
  // fitting the mesh to a point or two would crush it.
  if (count == 0 || !tooLittleData(points, count, Voxel))
    frame.Data =
        std::make_unique<FrameData>(points, count, normals, colours, colourComponents, dataOptions);
  frame.Seconds = elapsed(start);
  return frame;
}

PreparedFrame Tracker::prepare(const MeshSurface& frame) const
{
  if (Options.meshFrameSamples == 0 || frame.triangleCount == 0)
    return prepare(frame.positions, frame.vertices, nullptr,
                   frame.colourComponents ? frame.colours : nullptr, frame.colourComponents);
  const auto start = std::chrono::steady_clock::now();
  const PointCloud samples =
      sampleMeshSurface(frame, std::max(Options.meshFrameSamples, frame.vertices));
  const double sampling = elapsed(start);
  PreparedFrame prepared = prepare(samples.points.data(), samples.numberOfPoints(),
                                   samples.normals.empty() ? nullptr : samples.normals.data(),
                                   samples.hasColors() ? samples.colors.data() : nullptr, 3);
  prepared.Seconds += sampling;
  prepared.Count = frame.vertices; // what the frame gave; pointsUsed counts the samples read
  return prepared;
}

FrameResult Tracker::track(const double* points, std::size_t count, const float* normals)
{
  return track(prepare(points, count, normals));
}

FrameResult Tracker::track(PreparedFrame prepared)
{
  // Its field's voxel and subsample are this tracker's settings.
  if (prepared.Owner != this)
    throw std::invalid_argument("a frame prepared by another tracker, or by none (use this "
                                "tracker's prepare())");
  const auto start = std::chrono::steady_clock::now();
  const std::size_t nv = Mesh.numberOfVertices();
  FrameResult result;
  result.frozen.assign(nv, 0);
  result.rejected.assign(nv, 0);
  result.residual.assign(nv, -1.0);
  P->Recovery.frameBegins();

  if (Options.restUpdate > 0)
    Cloth.setRestState(P->Predictor.empty()
                           ? TemplateRest
                           : ClothRestState::blend(TemplateRest,
                                                   Cloth.restStateOf(P->Predictor.last().data()),
                                                   Options.restUpdate));

  result.pointsGiven = prepared.Count;
  if (!prepared.Data)
  {
    trackEmptyFrame(result);
    result.failed = true;
    P->Recovery.frameWithoutData();
    readVertexColours(nullptr, result);
  }
  else
  {
    auto clock = std::chrono::steady_clock::now();
    FrameData& frame = *prepared.Data;
    result.pointsUsed = frame.size();
    result.thinned = frame.size() < frame.originalSize();
    orientData(frame);
    result.timings.data = prepared.Seconds + elapsed(clock);
    if (frame.empty())
      trackEmptyFrame(result);
    else
    {
      keep(solveWithRetries(frame, result), result);
      result.samples = frame.copySamples();
      readColourReference(frame, result.positions);
    }
    readVertexColours(&frame, result);
  }
  remember(result);
  result.seconds = prepared.Seconds + elapsed(start);
  return result;
}

} // namespace dp
