// SPDX-License-Identifier: BSD-3-Clause
// What the tracker benchmark measures against: templates that know where each of their vertices
// sits on the true surface, the true trajectories of those vertices, and the figures a user sees
// (vertex error, surface error, the share of the true surface the tracked mesh leaves uncovered,
// jitter). VTK's cell locators do the exact point-to-surface distances.
#pragma once

#include "dp/field/SurfaceReconstruction.h"
#include "dp/field/TemplateMesh.h"
#include "dp/geometry/MeshSurfaceSamples.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"

#include "vtkCellArray.h"
#include "vtkCellArrayIterator.h"
#include "vtkGenericCell.h"
#include "vtkMath.h"
#include "vtkNew.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkQuadricDecimation.h"
#include "vtkSmartPointer.h"
#include "vtkStaticCellLocator.h"
#include "vtkStaticPointLocator.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace dp::bench
{

/** An animation with every position multiplied by one factor (e.g. a figure brought to 1.70 m). */
class ScaledAnimation : public dp::AnimatedMesh
{
public:
  ScaledAnimation(std::unique_ptr<dp::AnimatedMesh> mesh, double factor)
      : Mesh(std::move(mesh)), Factor(factor)
  {
  }
  std::size_t numberOfFrames() const override { return Mesh->numberOfFrames(); }
  std::size_t numberOfVertices() const override { return Mesh->numberOfVertices(); }
  const std::vector<std::int64_t>& triangles() const override { return Mesh->triangles(); }
  std::vector<double> positions(std::size_t frame) const override
  {
    std::vector<double> x = Mesh->positions(frame);
    for (double& v : x)
      v *= Factor;
    return x;
  }

private:
  std::unique_ptr<dp::AnimatedMesh> Mesh;
  double Factor;
};

/** The largest extent of the bounding box of x y z triples. */
inline double largestExtent(const std::vector<double>& x)
{
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (std::size_t i = 0; i < x.size(); ++i)
  {
    lo[i % 3] = std::min(lo[i % 3], x[i]);
    hi[i % 3] = std::max(hi[i % 3], x[i]);
  }
  return std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
}

inline vtkSmartPointer<vtkPolyData> toPolyData(const std::vector<double>& positions,
                                               const std::vector<std::int64_t>& triangles)
{
  auto pd = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(positions.size() / 3));
  for (std::size_t i = 0; i < positions.size(); i += 3)
    points->SetPoint(static_cast<vtkIdType>(i / 3), &positions[i]);
  vtkNew<vtkCellArray> polys;
  for (std::size_t t = 0; t < triangles.size(); t += 3)
  {
    const vtkIdType ids[3] = {triangles[t], triangles[t + 1], triangles[t + 2]};
    polys->InsertNextCell(3, ids);
  }
  pd->SetPoints(points);
  pd->SetPolys(polys);
  return pd;
}

/** Exact closest-point queries on one triangle mesh. */
class SurfaceDistance
{
public:
  SurfaceDistance(const std::vector<double>& positions, const std::vector<std::int64_t>& triangles)
      : Surface(toPolyData(positions, triangles))
  {
    Locator->SetDataSet(Surface);
    Locator->BuildLocator();
  }
  /** Squared distance from x to the surface; the closest point's triangle and position. */
  double squared(const double x[3], vtkIdType* triangle = nullptr, double* closest = nullptr)
  {
    double c[3], d2 = 0;
    vtkIdType cellId = -1;
    int subId = 0;
    double p[3] = {x[0], x[1], x[2]};
    Locator->FindClosestPoint(p, closest ? closest : c, Cell, cellId, subId, d2);
    if (triangle)
      *triangle = cellId;
    return d2;
  }

private:
  vtkSmartPointer<vtkPolyData> Surface;
  vtkNew<vtkStaticCellLocator> Locator;
  vtkNew<vtkGenericCell> Cell;
};

/** A template and, for each of its vertices, where it sits on the full-resolution mesh. */
struct Template
{
  std::vector<std::int64_t> triangles;
  std::vector<double> positions;
  std::vector<std::int64_t> onTriangle; // index into the full mesh's triangles; empty: full mesh
  std::vector<double> barycentric;      // 3 per vertex
  std::size_t vertices() const { return positions.size() / 3; }
};

enum class TemplateKind
{
  Decimated,     // frame 0 simplified (vtkQuadricDecimation), vertices on the true surface
  Reconstructed, // a surface reconstructed from frame 0's samples (what the filter does)
  Full           // frame 0 itself
};

inline const char* templateName(TemplateKind kind)
{
  return kind == TemplateKind::Decimated       ? "decimated"
         : kind == TemplateKind::Reconstructed ? "reconstructed"
                                               : "full";
}

/** The barycentric coordinates w of p (on or near the triangle abc) in 3D: p's projection onto
 *  the triangle's plane is w[0] a + w[1] b + w[2] c. (vtkTriangle::BarycentricCoords works in
 *  x and y only: on a triangle standing upright in z its weights are meaningless.) */
inline void barycentricCoordinates(const double p[3], const double a[3], const double b[3],
                                   const double c[3], double w[3])
{
  double ab[3], ac[3], ap[3];
  for (int k = 0; k < 3; ++k)
  {
    ab[k] = b[k] - a[k];
    ac[k] = c[k] - a[k];
    ap[k] = p[k] - a[k];
  }
  const double d00 = vtkMath::Dot(ab, ab), d01 = vtkMath::Dot(ab, ac), d11 = vtkMath::Dot(ac, ac);
  const double d20 = vtkMath::Dot(ap, ab), d21 = vtkMath::Dot(ap, ac);
  const double denominator = d00 * d11 - d01 * d01;
  if (!(denominator > 0))
  {
    w[0] = 1; // a degenerate triangle: its first corner
    w[1] = w[2] = 0;
    return;
  }
  w[1] = (d11 * d20 - d01 * d21) / denominator;
  w[2] = (d00 * d21 - d01 * d20) / denominator;
  w[0] = 1 - w[1] - w[2];
}

/** Frame 0 decimated to about `vertices` (quadric decimation, volume kept). */
inline vtkSmartPointer<vtkPolyData> decimated(vtkPolyData* input, std::size_t vertices)
{
  vtkNew<vtkQuadricDecimation> decimate;
  decimate->SetInputData(input);
  decimate->SetTargetReduction(1.0 - static_cast<double>(vertices) /
                                         static_cast<double>(input->GetNumberOfPoints()));
  decimate->VolumePreservationOn();
  // Flat regions make the quadrics singular; VTK then warns once per vertex and falls back to the
  // edge's midpoint, which is fine here.
  const int warnings = vtkObject::GetGlobalWarningDisplay();
  vtkObject::GlobalWarningDisplayOff();
  decimate->Update();
  vtkObject::SetGlobalWarningDisplay(warnings);
  return decimate->GetOutput();
}

/** Fills `t` from the template mesh `coarse`: each vertex on the true frame-0 mesh (`frame0`,
 *  `full`) with the triangle and barycentric coordinates that carry it through the frames, and
 *  the template's triangles. */
inline void placeOnTruth(vtkPolyData& coarse, TemplateKind kind, const std::vector<double>& frame0,
                         const std::vector<std::int64_t>& full, Template& t)
{
  SurfaceDistance truth(frame0, full);
  for (vtkIdType i = 0; i < coarse.GetNumberOfPoints(); ++i)
  {
    double p[3], closest[3];
    coarse.GetPoint(i, p);
    vtkIdType cellId = -1;
    truth.squared(p, &cellId, closest);
    const std::int64_t* v = &full[3 * cellId];
    double a[3], b[3], c[3], w[3];
    for (int k = 0; k < 3; ++k)
    {
      a[k] = frame0[3 * v[0] + k];
      b[k] = frame0[3 * v[1] + k];
      c[k] = frame0[3 * v[2] + k];
    }
    barycentricCoordinates(closest, a, b, c, w);
    // A decimated vertex sits on the surface; a reconstructed one up to half a voxel off it,
    // where it stays (projecting it could fold thin triangles flat): its error at frame 0 is then
    // that offset.
    const double* at = kind == TemplateKind::Reconstructed ? p : closest;
    t.positions.insert(t.positions.end(), at, at + 3);
    t.onTriangle.push_back(cellId);
    t.barycentric.insert(t.barycentric.end(), w, w + 3);
  }
  const vtkIdType* ids = nullptr;
  vtkIdType count = 0;
  auto polys = vtk::TakeSmartPointer(coarse.GetPolys()->NewIterator());
  for (polys->GoToFirstCell(); !polys->IsDoneWithTraversal(); polys->GoToNextCell())
  {
    polys->GetCurrentCell(count, ids);
    if (count == 3)
      t.triangles.insert(t.triangles.end(), {ids[0], ids[1], ids[2]});
  }
}

/**
 * A template of about `vertices` vertices of the kind asked for; `frame0Samples` are the points
 * a reconstruction starts from (the data of frame 0, with its noise and holes; their normals
 * are estimated, as the filter does without normals), `reconstruction` how (its target count is
 * `vertices`). The ground truth of a template vertex is
 * the barycentric position of its closest point on the frame-0 mesh, carried through the frames.
 */
inline Template makeTemplate(const dp::AnimatedMesh& mesh, TemplateKind kind, std::size_t vertices,
                             const dp::PointCloud& frame0Samples,
                             dp::ReconstructionOptions reconstruction = {})
{
  Template t;
  const std::vector<double> frame0 = mesh.positions(0);
  const auto& full = mesh.triangles();
  if (kind == TemplateKind::Full)
  {
    t.triangles = full;
    t.positions = frame0;
    return t;
  }
  auto input = toPolyData(frame0, full);
  vtkSmartPointer<vtkPolyData> coarse;
  if (kind == TemplateKind::Reconstructed)
  {
    // As the main job and the filter make it (dp::makeTemplate): from frame 0's mesh (repaired
    // and remeshed) where the data are meshes, else from its points.
    const std::vector<std::int64_t> triangles = dp::triangleFans(frame0Samples);
    dp::TemplateOptions options;
    options.source = triangles.empty() ? dp::TemplateSource::Points : dp::TemplateSource::Mesh;
    options.targetVertices = vertices;
    options.reconstruction = reconstruction;
    const dp::TemplateMesh r = dp::makeTemplate(
        frame0Samples.points.data(), frame0Samples.numberOfPoints(),
        frame0Samples.hasNormals() ? frame0Samples.normals.data() : nullptr, triangles, options,
        triangles.empty() ? "frame 0's points" : "frame 0's mesh");
    coarse = toPolyData(r.positions, r.triangles);
  }
  else
    coarse = decimated(input, vertices);
  placeOnTruth(*coarse, kind, frame0, full, t);
  return t;
}

/** Where the template's vertices truly are in a frame of the full mesh. */
inline std::vector<double> groundTruth(const Template& t, const std::vector<double>& frame,
                                       const std::vector<std::int64_t>& full)
{
  if (t.onTriangle.empty())
    return frame;
  std::vector<double> out(t.positions.size());
  for (std::size_t i = 0; i < t.onTriangle.size(); ++i)
    for (int k = 0; k < 3; ++k)
    {
      double value = 0;
      for (int c = 0; c < 3; ++c)
        value += t.barycentric[3 * i + c] * frame[3 * full[3 * t.onTriangle[i] + c] + k];
      out[3 * i + k] = value;
    }
  return out;
}

/** The true surface's unit normal at each template vertex's truth in a frame of the full mesh:
 *  its triangle's (the frame's vertex normals for a full template). */
inline std::vector<double> groundTruthNormals(const Template& t, const std::vector<double>& frame,
                                              const std::vector<std::int64_t>& full)
{
  const auto normalOf = [&](std::int64_t a, std::int64_t b, std::int64_t c, double n[3])
  {
    double u[3], v[3];
    for (int k = 0; k < 3; ++k)
    {
      u[k] = frame[3 * b + k] - frame[3 * a + k];
      v[k] = frame[3 * c + k] - frame[3 * a + k];
    }
    vtkMath::Cross(u, v, n);
  };
  std::vector<double> normals(t.positions.size(), 0.0);
  if (t.onTriangle.empty())
    for (std::size_t i = 0; i < full.size(); i += 3)
    {
      double n[3];
      normalOf(full[i], full[i + 1], full[i + 2], n);
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k)
          normals[3 * full[i + c] + k] += n[k];
    }
  else
    for (std::size_t v = 0; v < t.onTriangle.size(); ++v)
    {
      const std::int64_t* f = &full[3 * t.onTriangle[v]];
      normalOf(f[0], f[1], f[2], &normals[3 * v]);
    }
  for (std::size_t i = 0; i < normals.size(); i += 3)
  {
    const double length = vtkMath::Norm(&normals[i]);
    for (int k = 0; k < 3 && length > 0; ++k)
      normals[i + k] /= length;
  }
  return normals;
}

/** The figures of one tracked frame against the truth. */
struct FrameFigures
{
  double vertexSquaredSum = 0; // sum over vertices of |tracked - true|^2
  double normalSquaredSum = 0; // the same, of the error's component along the true normal
  double largestVertexError = 0;
  double surfaceSquaredSum = 0; // sum over tracked vertices of their squared distance to the truth
  double uncovered = 0;         // share of the true surface farther than the limit from the mesh
  // Vertices whose truth the frame's data see (a data point within the seen limit): their
  // count and summed squared error. With a partial view, the error where data can tell it.
  std::size_t seenVertices = 0;
  double seenSquaredSum = 0;
  double uncoveredSeen = 0; // the uncovered share of the true surface the data see
  double folded = 0;        // share of interior edges whose triangles turn more than 120 degrees
  // Shares of edges longer than twice (stretched) and three times (torn) their template length
  // and than the template's mean edge (addMeshShape).
  double stretched = 0, torn = 0;
};

/** Fills `f`'s seen figures: the vertices whose truth lies within `seenLimit` of a data point
 *  (x y z triples) and their error; the share of the seen `truthSamples` farther than
 *  `uncoveredLimit` from the tracked surface (`tracked`, `trackedTriangles`). */
inline void addSeenFigures(const std::vector<double>& tracked,
                           const std::vector<std::int64_t>& trackedTriangles,
                           const std::vector<double>& truth,
                           const std::vector<double>& truthSamples, const std::vector<double>& data,
                           double seenLimit, double uncoveredLimit, FrameFigures& f)
{
  if (data.empty())
    return;
  const vtkSmartPointer<vtkPolyData> cloud = toPolyData(data, {});
  vtkNew<vtkStaticPointLocator> locator;
  locator->SetDataSet(cloud);
  locator->BuildLocator();
  const auto seen = [&](const double* x)
  {
    double d2 = 0;
    return locator->FindClosestPointWithinRadius(seenLimit, x, d2) >= 0;
  };
  for (std::size_t i = 0; i < truth.size(); i += 3)
  {
    if (!seen(&truth[i]))
      continue;
    ++f.seenVertices;
    for (int k = 0; k < 3; ++k)
      f.seenSquaredSum += (tracked[i + k] - truth[i + k]) * (tracked[i + k] - truth[i + k]);
  }
  SurfaceDistance mesh(tracked, trackedTriangles);
  std::size_t seenSamples = 0, far = 0;
  for (std::size_t i = 0; i < truthSamples.size(); i += 3)
    if (seen(&truthSamples[i]))
    {
      ++seenSamples;
      far += mesh.squared(&truthSamples[i]) > uncoveredLimit * uncoveredLimit;
    }
  f.uncoveredSeen = seenSamples ? static_cast<double>(far) / static_cast<double>(seenSamples) : 0;
}

/** Fills `f`'s shape figures: folded interior edges (their two triangles' normals more than 120
 *  degrees apart), stretched and torn edges (longer than two and three times their length in the
 *  template, `rest`, and than its mean edge: a sliver's short edge doubling is no tear; no skin
 *  stretches threefold), as shares. */
inline void addMeshShape(const std::vector<double>& x, const std::vector<double>& rest,
                         const std::vector<std::int64_t>& triangles, FrameFigures& f)
{
  const auto normal = [&](std::size_t t)
  {
    const std::int64_t* v = &triangles[t];
    double u[3], w[3], n[3];
    for (int k = 0; k < 3; ++k)
    {
      u[k] = x[3 * v[1] + k] - x[3 * v[0] + k];
      w[k] = x[3 * v[2] + k] - x[3 * v[0] + k];
    }
    vtkMath::Cross(u, w, n);
    vtkMath::Normalize(n);
    return std::array<double, 3>{n[0], n[1], n[2]};
  };
  std::map<std::pair<std::int64_t, std::int64_t>, std::vector<std::size_t>> edges;
  for (std::size_t t = 0; t < triangles.size(); t += 3)
    for (int c = 0; c < 3; ++c)
    {
      const std::int64_t a = triangles[t + c], b = triangles[t + (c + 1) % 3];
      edges[{std::min(a, b), std::max(a, b)}].push_back(t);
    }
  const auto length = [](const std::vector<double>& p, std::int64_t a, std::int64_t b)
  { return std::sqrt(vtkMath::Distance2BetweenPoints(&p[3 * a], &p[3 * b])); };
  double meanLength = 0;
  for (const auto& entry : edges)
    meanLength += length(rest, entry.first.first, entry.first.second);
  meanLength /= static_cast<double>(std::max<std::size_t>(1, edges.size()));
  std::size_t interior = 0, folded = 0, stretched = 0, torn = 0;
  for (const auto& [edge, faces] : edges)
  {
    const double now = length(x, edge.first, edge.second);
    const double ratio = now / std::max(length(rest, edge.first, edge.second), 1e-300);
    stretched += ratio > 2 && now > meanLength;
    torn += ratio > 3 && now > meanLength;
    if (faces.size() != 2)
      continue;
    ++interior;
    const std::array<double, 3> n = normal(faces[0]), m = normal(faces[1]);
    folded += n[0] * m[0] + n[1] * m[1] + n[2] * m[2] < -0.5;
  }
  f.folded = interior ? static_cast<double>(folded) / static_cast<double>(interior) : 0.0;
  const double all = static_cast<double>(std::max<std::size_t>(1, edges.size()));
  f.stretched = static_cast<double>(stretched) / all;
  f.torn = static_cast<double>(torn) / all;
}

/**
 * Compares a tracked frame with the truth: vertex errors (and their part along the true
 * surface's normal, `truthNormals`, the rest lying along the surface), the distance of each tracked
 * vertex to the true surface, and the share of `truthSamples` (area-uniform points of the true
 * surface) farther than `uncoveredLimit` from the tracked surface: the parts the mesh has lost.
 */
inline FrameFigures
compareFrame(const std::vector<double>& tracked, const std::vector<std::int64_t>& trackedTriangles,
             const std::vector<double>& truthVertices, const std::vector<double>& truthNormals,
             const std::vector<double>& truthMesh, const std::vector<std::int64_t>& truthTriangles,
             const std::vector<double>& truthSamples, double uncoveredLimit)
{
  FrameFigures f;
  for (std::size_t i = 0; i < tracked.size(); i += 3)
  {
    double e2 = 0;
    for (int k = 0; k < 3; ++k)
      e2 += (tracked[i + k] - truthVertices[i + k]) * (tracked[i + k] - truthVertices[i + k]);
    f.vertexSquaredSum += e2;
    f.largestVertexError = std::max(f.largestVertexError, std::sqrt(e2));
    double along = 0;
    for (int k = 0; k < 3; ++k)
      along += (tracked[i + k] - truthVertices[i + k]) * truthNormals[i + k];
    f.normalSquaredSum += along * along;
  }
  SurfaceDistance truth(truthMesh, truthTriangles);
  for (std::size_t i = 0; i < tracked.size(); i += 3)
    f.surfaceSquaredSum += truth.squared(&tracked[i]);
  SurfaceDistance mesh(tracked, trackedTriangles);
  std::size_t far = 0;
  const double limit2 = uncoveredLimit * uncoveredLimit;
  for (std::size_t i = 0; i < truthSamples.size(); i += 3)
    far += mesh.squared(&truthSamples[i]) > limit2;
  f.uncovered = static_cast<double>(far) / static_cast<double>(truthSamples.size() / 3);
  return f;
}

/** Sums of squared accelerations (x[t+1] - 2 x[t] + x[t-1]) of the tracked and the true vertices:
 *  their ratio's square root is the jitter the tracking adds to the motion. */
class Jitter
{
public:
  void add(const std::vector<double>& tracked, const std::vector<double>& truth)
  {
    Tracked.push_back(tracked);
    Truth.push_back(truth);
    if (Tracked.size() > 3)
    {
      Tracked.erase(Tracked.begin());
      Truth.erase(Truth.begin());
    }
    if (Tracked.size() == 3)
    {
      TrackedSum += acceleration2(Tracked);
      TruthSum += acceleration2(Truth);
    }
  }
  /** RMS acceleration of the tracked vertices over the true one's (1: as smooth as the truth). */
  double ratio() const { return TruthSum > 0 ? std::sqrt(TrackedSum / TruthSum) : 0.0; }

private:
  static double acceleration2(const std::vector<std::vector<double>>& x)
  {
    double s = 0;
    for (std::size_t i = 0; i < x[0].size(); ++i)
    {
      const double a = x[2][i] - 2 * x[1][i] + x[0][i];
      s += a * a;
    }
    return s;
  }
  std::vector<std::vector<double>> Tracked, Truth;
  double TrackedSum = 0, TruthSum = 0;
};

} // namespace dp::bench
