// SPDX-License-Identifier: BSD-3-Clause
#include "dp/field/TemplateMesh.h"

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/IsotropicRemesher.h"
#include "dp/geometry/NormalEstimation.h"
#include "dp/support/Vec3.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace dp
{
namespace
{
using support::Vec3;

// Vertices closer than this share of the diagonal are one vertex (split vertices of per-face
// attributes, seams of a capture's mesh).
constexpr double SameVertex = 1e-9;
// A triangle of less area than this share of the mean has none (the tracker's cloth refuses
// those).
constexpr double NoArea = 1e-6;
// A connected part of less area than this share of the largest part is dropped (strays of a
// capture: a speck of floor, a floating blob).
constexpr double SmallPart = 0.01;
// A mesh is remeshed down to the vertex count asked when it has more than this many times it.
constexpr double Oversized = 1.1;

Vec3 at(const std::vector<double>& x, std::int64_t v)
{
  return {x[3 * v], x[3 * v + 1], x[3 * v + 2]};
}

double area(const std::vector<double>& x, const std::int64_t* t)
{
  using support::operator-;
  return 0.5 * support::norm(support::cross(at(x, t[1]) - at(x, t[0]), at(x, t[2]) - at(x, t[0])));
}

// Merges vertices that coincide (within SameVertex of the diagonal): the triangles' indices move
// to the first of each group.
void mergeDuplicateVertices(const std::vector<double>& x, std::vector<std::int64_t>& triangles,
                            TemplateReport& report)
{
  const std::size_t n = x.size() / 3;
  const double cell = std::max(SameVertex * boundingBoxDiagonal(x), 1e-300);
  std::map<std::array<std::int64_t, 3>, std::int64_t> first;
  std::vector<std::int64_t> to(n);
  for (std::size_t v = 0; v < n; ++v)
  {
    std::array<std::int64_t, 3> key;
    for (int k = 0; k < 3; ++k)
      key[k] =
          static_cast<std::int64_t>(std::llround(std::clamp(x[3 * v + k] / cell, -1e15, 1e15)));
    const auto [it, added] = first.emplace(key, static_cast<std::int64_t>(v));
    to[v] = it->second;
    report.duplicateVertices += !added;
  }
  for (std::int64_t& i : triangles)
    i = to[static_cast<std::size_t>(i)];
}

// Drops triangles without area (repeated corners, or less than NoArea of the mean) and
// repeated triangles (the same three vertices, in any order).
void dropDegenerateTriangles(const std::vector<double>& x, std::vector<std::int64_t>& triangles,
                             TemplateReport& report)
{
  const std::size_t count = triangles.size() / 3;
  std::vector<double> areas(count);
  double total = 0;
  for (std::size_t t = 0; t < count; ++t)
    total += areas[t] = area(x, &triangles[3 * t]);
  const double floor = count > 0 ? NoArea * total / static_cast<double>(count) : 0;
  std::map<std::array<std::int64_t, 3>, bool> seen;
  std::vector<std::int64_t> kept;
  for (std::size_t t = 0; t < count; ++t)
  {
    const std::int64_t* c = &triangles[3 * t];
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2] || !(areas[t] > floor))
    {
      ++report.degenerateTriangles;
      continue;
    }
    std::array<std::int64_t, 3> key{c[0], c[1], c[2]};
    std::sort(key.begin(), key.end());
    if (!seen.emplace(key, true).second)
    {
      ++report.duplicateTriangles;
      continue;
    }
    kept.insert(kept.end(), c, c + 3);
  }
  triangles.swap(kept);
}

// Drops the connected parts (triangles sharing vertices) of less than SmallPart of the largest
// part's area.
void dropSmallParts(const std::vector<double>& x, std::vector<std::int64_t>& triangles,
                    TemplateReport& report)
{
  const std::size_t n = x.size() / 3, count = triangles.size() / 3;
  std::vector<std::int64_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  const auto root = [&parent](std::int64_t v)
  {
    while (parent[v] != v)
      v = parent[v] = parent[parent[v]];
    return v;
  };
  for (std::size_t t = 0; t < count; ++t)
    for (int k = 1; k < 3; ++k)
    {
      const std::int64_t a = root(triangles[3 * t]), b = root(triangles[3 * t + k]);
      if (a != b)
        parent[std::max(a, b)] = std::min(a, b);
    }
  std::unordered_map<std::int64_t, double> partArea;
  for (std::size_t t = 0; t < count; ++t)
    partArea[root(triangles[3 * t])] += area(x, &triangles[3 * t]);
  double largest = 0;
  for (const auto& [part, a] : partArea)
    largest = std::max(largest, a);
  std::vector<std::int64_t> kept;
  for (std::size_t t = 0; t < count; ++t)
    if (partArea[root(triangles[3 * t])] >= SmallPart * largest)
      kept.insert(kept.end(), &triangles[3 * t], &triangles[3 * t] + 3);
    else
      ++report.smallPartTriangles;
  triangles.swap(kept);
}

// The vertices the triangles use, in their order (a clean mesh keeps its numbering).
std::vector<double> compact(const std::vector<double>& x, std::vector<std::int64_t>& triangles,
                            TemplateReport& report)
{
  std::vector<std::int64_t> to(x.size() / 3, -1);
  for (std::int64_t i : triangles)
    to[static_cast<std::size_t>(i)] = 0;
  std::vector<double> kept;
  for (std::size_t v = 0; v < to.size(); ++v)
    if (to[v] == 0)
    {
      to[v] = static_cast<std::int64_t>(kept.size() / 3);
      kept.insert(kept.end(), &x[3 * v], &x[3 * v] + 3);
    }
  for (std::int64_t& i : triangles)
    i = to[static_cast<std::size_t>(i)];
  report.unusedVertices = x.size() / 3 - kept.size() / 3 - report.duplicateVertices;
  return kept;
}

TemplateMesh fromMesh(const double* points, std::size_t count,
                      const std::vector<std::int64_t>& triangles, const TemplateOptions& options,
                      const std::string& what)
{
  TemplateMesh m;
  TemplateReport& r = m.report;
  r.source = what;
  r.verticesGiven = count;
  r.trianglesGiven = triangles.size() / 3;
  if (triangles.size() % 3 != 0)
    throw std::invalid_argument(what + ": triangle indices are not a multiple of 3");
  for (std::int64_t i : triangles)
    if (i < 0 || static_cast<std::size_t>(i) >= count)
      throw std::invalid_argument(what + ": triangle index " + std::to_string(i) +
                                  " is out of range (" + std::to_string(count) + " vertices)");
  const std::vector<double> x(points, points + 3 * count);
  for (double v : x)
    if (!std::isfinite(v))
      throw std::invalid_argument(what + ": a vertex has a NaN or infinite coordinate");
  std::vector<std::int64_t> t = triangles;
  mergeDuplicateVertices(x, t, r);
  dropDegenerateTriangles(x, t, r);
  dropSmallParts(x, t, r);
  if (t.empty())
    throw std::invalid_argument(
        what + " has no usable triangle: all " + std::to_string(r.trianglesGiven) +
        " have no area or repeat others (give a template mesh, or track from the points)");
  m.positions = compact(x, t, r);
  m.triangles = std::move(t);
  const std::size_t vertices = m.positions.size() / 3;
  if (options.remesh &&
      static_cast<double>(vertices) > Oversized * static_cast<double>(options.targetVertices))
  {
    support::IndexedMesh fine;
    for (std::size_t v = 0; v < vertices; ++v)
      fine.positions.push_back(at(m.positions, static_cast<std::int64_t>(v)));
    for (std::size_t i = 0; i < m.triangles.size(); i += 3)
      fine.triangles.push_back({static_cast<int>(m.triangles[i]),
                                static_cast<int>(m.triangles[i + 1]),
                                static_cast<int>(m.triangles[i + 2])});
    support::RemeshedSurface coarse = support::remeshIsotropic(fine, options.targetVertices);
    m.positions = std::move(coarse.positions);
    m.triangles = std::move(coarse.triangles);
    r.remeshed = true;
  }
  return m;
}

ReconstructedMesh reconstruct(const double* points, std::size_t count, const float* normals,
                              const TemplateOptions& options, const std::string& what)
{
  ReconstructionOptions reconstruction = options.reconstruction;
  reconstruction.targetVertices = options.targetVertices;
  try
  {
    const std::vector<float> estimated =
        normals ? std::vector<float>{} : estimateNormals(points, count);
    return reconstructSurface(points, normals ? normals : estimated.data(), count, reconstruction);
  }
  catch (const std::exception& e)
  {
    throw std::invalid_argument("a surface could not be reconstructed from " + what + " (" +
                                std::to_string(count) + "): " + e.what());
  }
}

TemplateMesh fromPoints(const double* points, std::size_t count, const float* normals,
                        const TemplateOptions& options, const std::string& what)
{
  ReconstructedMesh surface = reconstruct(points, count, normals, options, what);
  TemplateMesh m;
  m.positions = std::move(surface.positions);
  m.triangles = std::move(surface.triangles);
  m.report.source = "frame 0's points";
  m.report.verticesGiven = count;
  m.report.reconstructed = true;
  m.report.noise = surface.noise;
  m.report.smoothedForNoise = surface.smoothedForNoise;
  m.report.smoothingVoxel = surface.voxelSize;
  m.report.strayPoints = surface.strayPoints;
  return m;
}
} // namespace

std::string TemplateReport::summary() const
{
  std::ostringstream s;
  s << source << ": ";
  if (reconstructed)
  {
    s << "a surface of " << vertices << " vertices reconstructed from " << verticesGiven
      << " points";
    if (smoothedForNoise)
      s << std::setprecision(3) << " (a noisy layer " << noise.thickness
        << " thick, smoothed over voxels of " << smoothingVoxel << "; " << strayPoints
        << " stray points left out)";
    return s.str();
  }
  std::vector<std::string> done;
  const auto count = [&done](std::size_t n, const char* what)
  {
    if (n > 0)
      done.push_back(std::to_string(n) + " " + what);
  };
  count(duplicateVertices, "duplicate vertices merged");
  count(degenerateTriangles, "triangles without area removed");
  count(duplicateTriangles, "repeated triangles removed");
  count(smallPartTriangles, "triangles of small stray parts removed");
  count(unusedVertices, "unused vertices dropped");
  for (std::size_t i = 0; i < done.size(); ++i)
    s << (i ? ", " : "") << done[i];
  if (remeshed)
    s << (done.empty() ? "" : ", ") << "remeshed from " << verticesGiven << " to " << vertices
      << " vertices";
  else if (done.empty())
    s << "used as it is (" << vertices << " vertices)";
  else
    s << " (" << vertices << " vertices)";
  return s.str();
}

TemplateMesh makeTemplate(const double* points, std::size_t count, const float* normals,
                          const std::vector<std::int64_t>& triangles,
                          const TemplateOptions& options, const std::string& what)
{
  const bool mesh = options.source == TemplateSource::Mesh ||
                    (options.source == TemplateSource::Auto && !triangles.empty());
  if (mesh && triangles.empty())
    throw std::invalid_argument(what + " has no triangles (track from the points instead)");
  TemplateMesh m = mesh ? fromMesh(points, count, triangles, options, what)
                        : fromPoints(points, count, normals, options, what);
  m.report.vertices = m.positions.size() / 3;
  m.report.triangles = m.triangles.size() / 3;
  return m;
}

} // namespace dp
