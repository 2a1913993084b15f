// SPDX-License-Identifier: BSD-3-Clause
#include "dp/io/AnimatedMesh.h"

#include "dp/io/PointCloudIO.h"

#include <cmath>
#include <stdexcept>

namespace dp
{
namespace
{
constexpr double Pi = 3.14159265358979323846;

// Phase in [0,1] of a frame in a looping animation of `frames` frames.
double phase(std::size_t frame, std::size_t frames)
{
  return frames <= 1 ? 0.0 : static_cast<double>(frame) / static_cast<double>(frames - 1);
}

void checkFrame(std::size_t frame, std::size_t frames)
{
  if (frame >= frames)
    throw std::out_of_range("frame " + std::to_string(frame) + " of an animation with " +
                            std::to_string(frames) + " frames");
}
} // namespace

PointCloud AnimatedMesh::frameMesh(std::size_t frame) const
{
  PointCloud mesh;
  mesh.points = positions(frame);
  const auto& tris = triangles();
  for (std::size_t t = 0; t < tris.size(); t += 3)
    mesh.addFace(&tris[t], 3);
  return mesh;
}

BendingTube::BendingTube(const Options& options) : Opts(options)
{
  if (Opts.rings < 2 || Opts.segments < 3 || !(Opts.radius > 0) || !(Opts.length > 0))
    throw std::invalid_argument("BendingTube needs rings >= 2, segments >= 3 and positive sizes");
  const std::size_t m = Opts.segments;
  for (std::size_t i = 0; i < Opts.rings; ++i)
  {
    const double z = Opts.length * static_cast<double>(i) / static_cast<double>(Opts.rings - 1);
    for (std::size_t j = 0; j < m; ++j)
    {
      const double a = 2 * Pi * static_cast<double>(j) / static_cast<double>(m);
      Rest.insert(Rest.end(), {Opts.radius * std::cos(a), Opts.radius * std::sin(a), z});
    }
  }
  const auto bottom = static_cast<std::int64_t>(Rest.size() / 3);
  Rest.insert(Rest.end(), {0.0, 0.0, 0.0});
  const auto top = bottom + 1;
  Rest.insert(Rest.end(), {0.0, 0.0, Opts.length});

  auto id = [m](std::size_t ring, std::size_t seg)
  { return static_cast<std::int64_t>(ring * m + seg % m); };
  // Counter-clockwise seen from outside, so face normals point out of the tube.
  for (std::size_t i = 0; i + 1 < Opts.rings; ++i)
    for (std::size_t j = 0; j < m; ++j)
    {
      const auto a = id(i, j), b = id(i, j + 1), c = id(i + 1, j + 1), d = id(i + 1, j);
      Triangles.insert(Triangles.end(), {a, b, c, a, c, d});
    }
  const std::size_t last = Opts.rings - 1;
  for (std::size_t j = 0; j < m; ++j)
  {
    Triangles.insert(Triangles.end(), {bottom, id(0, j + 1), id(0, j)});
    Triangles.insert(Triangles.end(), {top, id(last, j), id(last, j + 1)});
  }
}

std::vector<double> BendingTube::positions(std::size_t frame) const
{
  checkFrame(frame, Opts.frames);
  const double s = phase(frame, Opts.frames);
  const double bend = Opts.maxBendRadians * std::sin(2 * Pi * s);
  const double twist = Opts.maxTwistRadians * std::sin(Pi * s);
  const double curvature = bend / Opts.length;
  std::vector<double> out(Rest.size());
  for (std::size_t v = 0; v < Rest.size(); v += 3)
  {
    const double z = Rest[v + 2];
    // Twist about the axis, growing linearly along it.
    const double psi = twist * z / Opts.length;
    const double x = Rest[v] * std::cos(psi) - Rest[v + 1] * std::sin(psi);
    const double y = Rest[v] * std::sin(psi) + Rest[v + 1] * std::cos(psi);
    // Bend the axis into an arc of the given curvature in the x-z plane (length preserved).
    if (std::abs(curvature) < 1e-12)
    {
      out[v] = x, out[v + 1] = y, out[v + 2] = z;
    }
    else
    {
      const double rho = 1.0 / curvature;
      const double angle = z * curvature;
      out[v] = rho - (rho - x) * std::cos(angle);
      out[v + 1] = y;
      out[v + 2] = (rho - x) * std::sin(angle);
    }
  }
  return out;
}

WavingSheet::WavingSheet(const Options& options) : Opts(options)
{
  if (Opts.columns < 2 || Opts.rows < 2 || !(Opts.width > 0) || !(Opts.height > 0) ||
      !(Opts.wavelength > 0))
    throw std::invalid_argument("WavingSheet needs columns, rows >= 2 and positive sizes");
  const auto nx = static_cast<std::int64_t>(Opts.columns);
  for (std::int64_t r = 0; r + 1 < static_cast<std::int64_t>(Opts.rows); ++r)
    for (std::int64_t c = 0; c + 1 < nx; ++c)
    {
      const auto a = r * nx + c, b = a + 1, d = a + nx, e = d + 1;
      Triangles.insert(Triangles.end(), {a, b, e, a, e, d});
    }
}

std::vector<double> WavingSheet::positions(std::size_t frame) const
{
  checkFrame(frame, Opts.frames);
  const double s = phase(frame, Opts.frames);
  std::vector<double> out;
  out.reserve(3 * numberOfVertices());
  for (std::size_t r = 0; r < Opts.rows; ++r)
    for (std::size_t c = 0; c < Opts.columns; ++c)
    {
      const double x = Opts.width * static_cast<double>(c) / static_cast<double>(Opts.columns - 1);
      const double y = Opts.height * static_cast<double>(r) / static_cast<double>(Opts.rows - 1);
      // A travelling wave pinned at x = 0, with a slight roll across the sheet.
      const double reach = x / Opts.width;
      const double z = Opts.amplitude * reach *
                       (std::sin(2 * Pi * (x / Opts.wavelength - s)) +
                        0.3 * std::sin(Pi * y / Opts.height) * std::sin(2 * Pi * s));
      out.insert(out.end(), {x, y, z});
    }
  return out;
}

std::vector<std::int64_t> triangulateFaces(const PointCloud& mesh)
{
  std::vector<std::int64_t> tris;
  for (std::size_t f = 0; f < mesh.numberOfFaces(); ++f)
  {
    const auto begin = mesh.faceOffsets[f], end = mesh.faceOffsets[f + 1];
    if (end - begin < 3)
      throw std::invalid_argument("face " + std::to_string(f) + " has fewer than 3 vertices");
    for (auto k = begin + 1; k + 1 < end; ++k)
      tris.insert(tris.end(), {mesh.faceConnectivity[begin], mesh.faceConnectivity[k],
                               mesh.faceConnectivity[k + 1]});
  }
  return tris;
}

MeshSequenceFiles::MeshSequenceFiles(FrameSequence frames) : Frames(std::move(frames))
{
  if (Frames.empty())
    throw std::invalid_argument("MeshSequenceFiles needs at least one frame");
  const PointCloud first = readPointCloud(Frames[0].path);
  if (first.numberOfFaces() == 0)
    throw FileError(Frames[0].path, "has no faces; an animated mesh needs triangles");
  VertexCount = first.numberOfPoints();
  Triangles = triangulateFaces(first);
}

std::vector<double> MeshSequenceFiles::positions(std::size_t frame) const
{
  checkFrame(frame, Frames.size());
  ReadReport report;
  PointCloud mesh = readPointCloud(Frames[frame].path, &report);
  if (mesh.numberOfPoints() != VertexCount || report.droppedNonFinite > 0)
    throw FileError(Frames[frame].path,
                    "has " + std::to_string(mesh.numberOfPoints() + report.droppedNonFinite) +
                        " vertices (" + std::to_string(report.droppedNonFinite) +
                        " non-finite), frame 0 has " + std::to_string(VertexCount) +
                        ": not one animated mesh");
  return std::move(mesh.points);
}

} // namespace dp
