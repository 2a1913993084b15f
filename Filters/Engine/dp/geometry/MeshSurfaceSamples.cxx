// SPDX-License-Identifier: BSD-3-Clause
#include "dp/geometry/MeshSurfaceSamples.h"

#include "dp/support/Vec3.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace dp
{
namespace
{
using support::Vec3;
using support::operator+;
using support::operator-;
using support::operator*;

Vec3 unit(const Vec3& a)
{
  const double length = support::norm(a);
  return length > 0 ? (1 / length) * a : a;
}

Vec3 corner(const MeshSurface& mesh, std::size_t t, int k)
{
  const double* p = mesh.positions + 3 * mesh.triangles[3 * t + k];
  return {p[0], p[1], p[2]};
}

// Twice the triangle's area along its normal (the cross product of two edges).
Vec3 areaVector(const MeshSurface& mesh, std::size_t t)
{
  const Vec3 a = corner(mesh, t, 0);
  return support::cross(corner(mesh, t, 1) - a, corner(mesh, t, 2) - a);
}

void checkIndices(const MeshSurface& mesh)
{
  for (std::size_t i = 0; i < 3 * mesh.triangleCount; ++i)
    if (mesh.triangles[i] < 0 || static_cast<std::size_t>(mesh.triangles[i]) >= mesh.vertices)
      throw std::invalid_argument("triangle " + std::to_string(i / 3) + " uses vertex " +
                                  std::to_string(mesh.triangles[i]) + ", but the mesh has " +
                                  std::to_string(mesh.vertices) + " vertices");
  if (mesh.colours && mesh.colourComponents != 3 && mesh.colourComponents != 4)
    throw std::invalid_argument("mesh colours need 3 or 4 components, not " +
                                std::to_string(mesh.colourComponents));
}

// Area-weighted vertex normals (not normalised: a zero sum says they cancel out).
std::vector<Vec3> vertexNormalSums(const MeshSurface& mesh)
{
  std::vector<Vec3> sums(mesh.vertices, Vec3{0, 0, 0});
  for (std::size_t t = 0; t < mesh.triangleCount; ++t)
  {
    const Vec3 n = areaVector(mesh, t);
    for (int k = 0; k < 3; ++k)
    {
      Vec3& sum = sums[static_cast<std::size_t>(mesh.triangles[3 * t + k])];
      sum = sum + n;
    }
  }
  return sums;
}

// The k-th point of the R2 low-discrepancy sequence in the unit square.
// FNV-1a over the mesh's coordinates: where the sample sequence starts (see the header).
std::uint64_t coordinateHash(const MeshSurface& mesh)
{
  std::uint64_t h = 14695981039346656037ull;
  const auto* bytes = reinterpret_cast<const unsigned char*>(mesh.positions);
  for (std::size_t i = 0; i < 3 * mesh.vertices * sizeof(double); ++i)
    h = (h ^ bytes[i]) * 1099511628211ull;
  return h;
}

void r2Point(std::size_t k, double& u, double& v)
{
  const double g = 1.32471795724474602596; // the plastic number
  u = std::fmod(0.5 + static_cast<double>(k) / g, 1.0);
  v = std::fmod(0.5 + static_cast<double>(k) / (g * g), 1.0);
}

class SampleWriter
{
public:
  SampleWriter(const MeshSurface& mesh, PointCloud& out)
      : Mesh(mesh), Out(out), NormalSums(vertexNormalSums(mesh))
  {
    if (mesh.colours)
      Out.colorComponents = 3;
  }

  // One sample of triangle t at barycentric coordinates b.
  void add(std::size_t t, const double b[3])
  {
    Vec3 p{0, 0, 0}, n{0, 0, 0};
    double rgb[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
    {
      const auto v = static_cast<std::size_t>(Mesh.triangles[3 * t + k]);
      p = p + b[k] * corner(Mesh, t, k);
      n = n + b[k] * unit(NormalSums[v]);
      if (Mesh.colours)
        for (int c = 0; c < 3; ++c)
          rgb[c] += b[k] * Mesh.colours[static_cast<std::size_t>(Mesh.colourComponents) * v + c];
    }
    if (!(support::norm(n) > 1e-12))
      n = areaVector(Mesh, t);
    n = unit(n);
    for (int c = 0; c < 3; ++c)
    {
      Out.points.push_back(p[c]);
      Out.normals.push_back(static_cast<float>(n[c]));
      if (Mesh.colours)
        Out.colors.push_back(static_cast<std::uint8_t>(std::clamp(std::lround(rgb[c]), 0L, 255L)));
    }
  }

private:
  const MeshSurface& Mesh;
  PointCloud& Out;
  std::vector<Vec3> NormalSums;
};
} // namespace

std::vector<std::int64_t> triangleFans(const PointCloud& cloud)
{
  std::vector<std::int64_t> triangles;
  for (std::size_t f = 0; f < cloud.numberOfFaces(); ++f)
  {
    const auto first = static_cast<std::size_t>(cloud.faceOffsets[f]);
    const auto end = static_cast<std::size_t>(cloud.faceOffsets[f + 1]);
    for (std::size_t k = first + 1; k + 1 < end; ++k)
      triangles.insert(triangles.end(), {cloud.faceConnectivity[first], cloud.faceConnectivity[k],
                                         cloud.faceConnectivity[k + 1]});
  }
  return triangles;
}

MeshSurface meshSurfaceOf(const PointCloud& cloud, const std::vector<std::int64_t>& triangles)
{
  MeshSurface s;
  s.positions = cloud.points.data();
  s.vertices = cloud.numberOfPoints();
  s.triangles = triangles.data();
  s.triangleCount = triangles.size() / 3;
  if (cloud.hasColors())
  {
    s.colours = cloud.colors.data();
    s.colourComponents = cloud.colorComponents;
  }
  return s;
}

double meshSurfaceArea(const MeshSurface& mesh)
{
  checkIndices(mesh);
  double area = 0;
  for (std::size_t t = 0; t < mesh.triangleCount; ++t)
    area += 0.5 * support::norm(areaVector(mesh, t));
  return area;
}

PointCloud sampleMeshSurface(const MeshSurface& mesh, std::size_t count)
{
  const double area = meshSurfaceArea(mesh);
  PointCloud out;
  if (!(area > 0) || count == 0)
    return out;
  out.points.reserve(3 * count + 3);
  out.normals.reserve(3 * count + 3);
  SampleWriter writer(mesh, out);
  const double perArea = static_cast<double>(count) / area;
  // The fraction of a sample owed so far and the R2 index, both started where the mesh's
  // coordinates say.
  const std::uint64_t start = coordinateHash(mesh);
  double carry = static_cast<double>(start & 0xFFFFF) / 0x100000;
  std::size_t k = static_cast<std::size_t>((start >> 20) & 0xFFFFFF);
  for (std::size_t t = 0; t < mesh.triangleCount; ++t)
  {
    carry += 0.5 * support::norm(areaVector(mesh, t)) * perArea;
    for (; carry >= 1; carry -= 1, ++k)
    {
      double u, v;
      r2Point(k, u, v);
      const double s = std::sqrt(u); // uniform over the triangle's area
      const double b[3] = {1 - s, s * (1 - v), s * v};
      writer.add(t, b);
    }
  }
  return out;
}

} // namespace dp
