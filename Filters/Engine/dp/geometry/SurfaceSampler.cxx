// SPDX-License-Identifier: BSD-3-Clause
#include "dp/geometry/SurfaceSampler.h"

#include "dp/geometry/DeterministicRandom.h"

#include "dp/io/PointCloudIO.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>

namespace fs = std::filesystem;

namespace dp
{
namespace
{

using Random = DeterministicRandom;

struct Vec3
{
  double x, y, z;
};
Vec3 operator-(Vec3 a, Vec3 b)
{
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
Vec3 cross(Vec3 a, Vec3 b)
{
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double norm(Vec3 a)
{
  return std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
}

Vec3 vertex(const std::vector<double>& p, std::int64_t i)
{
  return {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
}

// A point on the surface: triangle index and barycentric weights of its corners.
struct SurfacePoint
{
  std::size_t triangle;
  double w0, w1, w2;
};

class AreaTable
{
public:
  AreaTable(const std::vector<double>& positions, const std::vector<std::int64_t>& triangles)
  {
    const auto nv = static_cast<std::int64_t>(positions.size() / 3);
    double total = 0;
    Cumulative.reserve(triangles.size() / 3);
    for (std::size_t t = 0; t + 2 < triangles.size(); t += 3)
    {
      for (int k = 0; k < 3; ++k)
        if (triangles[t + k] < 0 || triangles[t + k] >= nv)
          throw std::invalid_argument("triangle " + std::to_string(t / 3) +
                                      " uses a vertex index out of range");
      const Vec3 a = vertex(positions, triangles[t]), b = vertex(positions, triangles[t + 1]),
                 c = vertex(positions, triangles[t + 2]);
      total += 0.5 * norm(cross(b - a, c - a));
      Cumulative.push_back(total);
    }
    if (!(total > 0) || !std::isfinite(total))
      throw std::invalid_argument("the mesh has no surface area to sample");
  }
  SurfacePoint draw(Random& random) const
  {
    const double target = random.uniform() * Cumulative.back();
    const auto it = std::upper_bound(Cumulative.begin(), Cumulative.end(), target);
    const std::size_t t = std::min<std::size_t>(it - Cumulative.begin(), Cumulative.size() - 1);
    return inTriangle(t, random);
  }
  // A point of a triangle chosen by index alone, so the same random numbers pick the same
  // material point in every frame, however the areas change.
  SurfacePoint drawMaterialPoint(Random& random) const
  {
    const auto t =
        static_cast<std::size_t>(random.uniform() * static_cast<double>(Cumulative.size()));
    return inTriangle(std::min(t, Cumulative.size() - 1), random);
  }

private:
  static SurfacePoint inTriangle(std::size_t t, Random& random)
  {
    // Uniform in the triangle: the square-root warp of two uniforms.
    const double r1 = std::sqrt(random.uniform()), r2 = random.uniform();
    return {t, 1 - r1, r1 * (1 - r2), r1 * r2};
  }
  std::vector<double> Cumulative;
};

Vec3 evaluate(const std::vector<double>& field, const std::vector<std::int64_t>& triangles,
              const SurfacePoint& s)
{
  const Vec3 a = vertex(field, triangles[3 * s.triangle]),
             b = vertex(field, triangles[3 * s.triangle + 1]),
             c = vertex(field, triangles[3 * s.triangle + 2]);
  return {s.w0 * a.x + s.w1 * b.x + s.w2 * c.x, s.w0 * a.y + s.w1 * b.y + s.w2 * c.y,
          s.w0 * a.z + s.w1 * b.z + s.w2 * c.z};
}

// Area-weighted vertex normals (sum of unnormalised face normals).
std::vector<double> vertexNormals(const std::vector<double>& positions,
                                  const std::vector<std::int64_t>& triangles)
{
  std::vector<double> normals(positions.size(), 0.0);
  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3)
  {
    const Vec3 a = vertex(positions, triangles[t]), b = vertex(positions, triangles[t + 1]),
               c = vertex(positions, triangles[t + 2]);
    const Vec3 n = cross(b - a, c - a);
    for (int k = 0; k < 3; ++k)
    {
      normals[3 * triangles[t + k]] += n.x;
      normals[3 * triangles[t + k] + 1] += n.y;
      normals[3 * triangles[t + k] + 2] += n.z;
    }
  }
  return normals;
}

// Holes: material points drawn from their own stream, so they do not depend on the sampling;
// with fixed holes the stream is the same in every frame, so a hole stays on the same material.
std::vector<Vec3> drawHoles(const AreaTable& areas, const std::vector<double>& positions,
                            const std::vector<std::int64_t>& triangles,
                            const SamplerOptions& options, std::size_t frame)
{
  std::vector<Vec3> centres;
  Random holeRandom(options.seed, options.holesMove ? 2 * frame + 2 : 0);
  for (std::size_t h = 0; h < options.holes; ++h)
    centres.push_back(evaluate(positions, triangles, areas.drawMaterialPoint(holeRandom)));
  return centres;
}

double restDiagonal(const std::vector<double>& rest)
{
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (std::size_t i = 0; i + 2 < rest.size(); i += 3)
    for (int k = 0; k < 3; ++k)
    {
      lo[k] = std::min(lo[k], rest[i + k]);
      hi[k] = std::max(hi[k], rest[i + k]);
    }
  return std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                   (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

std::uint8_t toByte(double v)
{
  return static_cast<std::uint8_t>(std::lround(255 * std::clamp(v, 0.0, 1.0)));
}

} // namespace

void materialColour(const double p[3], double diagonal, double rgb[3])
{
  // Per channel: two plane waves, long and short, in fixed directions (unit vectors) and phases.
  static const double Direction[6][3] = {{0.62, 0.51, 0.59},   {-0.21, 0.93, 0.30},
                                         {0.44, -0.35, 0.83},  {0.90, 0.17, -0.40},
                                         {-0.57, -0.66, 0.49}, {0.12, 0.71, -0.69}};
  static const double Phase[6] = {0.3, 1.9, 4.1, 2.6, 5.2, 0.9};
  const double TwoPi = 6.283185307179586;
  const double scale = diagonal > 0 ? 1 / diagonal : 1;
  for (int c = 0; c < 3; ++c)
  {
    double v = 0.5;
    for (int w = 0; w < 2; ++w)
    {
      const double* d = Direction[2 * c + w];
      const double along = scale * (p[0] * d[0] + p[1] * d[1] + p[2] * d[2]);
      v += 0.24 * std::sin(TwoPi * along / (w == 0 ? 0.12 : 0.04) + Phase[2 * c + w]);
    }
    rgb[c] = v;
  }
}

std::vector<double> holeCentres(const std::vector<double>& positions,
                                const std::vector<std::int64_t>& triangles,
                                const SamplerOptions& options, std::size_t frame)
{
  std::vector<double> out;
  for (const Vec3& c :
       drawHoles(AreaTable(positions, triangles), positions, triangles, options, frame))
    out.insert(out.end(), {c.x, c.y, c.z});
  return out;
}

namespace
{
// The rest positions the colours are drawn from (null: no colours); throws when colours are
// asked for without them, or with another vertex count than the mesh's.
const std::vector<double>* colourRestOf(const std::vector<double>& positions,
                                        const SamplerOptions& options)
{
  const std::vector<double>* rest = options.colours ? options.colourRest : nullptr;
  if (options.colours && !rest)
    throw std::invalid_argument("colours asked for without the mesh's rest positions");
  if (rest && rest->size() != positions.size())
    throw std::invalid_argument("the colour's rest positions have " +
                                std::to_string(rest->size() / 3) + " vertices; the mesh has " +
                                std::to_string(positions.size() / 3));
  return rest;
}

bool inAnyHole(const Vec3& p, const std::vector<Vec3>& holes, double r2)
{
  return std::any_of(holes.begin(), holes.end(),
                     [&](const Vec3& c)
                     {
                       const Vec3 d = p - c;
                       return d.x * d.x + d.y * d.y + d.z * d.z < r2;
                     });
}

// The unit normal at s (the vertex normals interpolated), appended to the cloud's normals.
void appendNormal(const std::vector<double>& normals, const std::vector<std::int64_t>& triangles,
                  const SurfacePoint& s, PointCloud& cloud)
{
  Vec3 n = evaluate(normals, triangles, s);
  const double length = norm(n);
  if (length > 0)
    n = {n.x / length, n.y / length, n.z / length};
  cloud.normals.insert(cloud.normals.end(),
                       {static_cast<float>(n.x), static_cast<float>(n.y), static_cast<float>(n.z)});
}

// The material's colour at s (from its rest position), appended to the cloud's colours.
void appendColour(const std::vector<double>& rest, const std::vector<std::int64_t>& triangles,
                  const SurfacePoint& s, double diagonal, PointCloud& cloud)
{
  const Vec3 r = evaluate(rest, triangles, s);
  const double at[3] = {r.x, r.y, r.z};
  double rgb[3];
  materialColour(at, diagonal, rgb);
  cloud.colors.insert(cloud.colors.end(), {toByte(rgb[0]), toByte(rgb[1]), toByte(rgb[2])});
}
} // namespace

PointCloud sampleSurface(const std::vector<double>& positions,
                         const std::vector<std::int64_t>& triangles, const SamplerOptions& options,
                         std::size_t frame)
{
  if (triangles.size() % 3 != 0)
    throw std::invalid_argument("triangle indices are not a multiple of 3");
  if (options.noiseStdDev < 0 || options.holeRadius < 0)
    throw std::invalid_argument("noise and hole radius must not be negative");
  const AreaTable areas(positions, triangles);
  Random random(options.seed, 2 * frame + 1);
  const std::vector<Vec3> holes = drawHoles(areas, positions, triangles, options, frame);
  const double r2 = options.holeRadius * options.holeRadius;

  const std::vector<double> normals =
      options.normals ? vertexNormals(positions, triangles) : std::vector<double>{};
  const std::vector<double>* rest = colourRestOf(positions, options);
  const double diagonal = rest ? restDiagonal(*rest) : 0;
  PointCloud cloud;
  cloud.colorComponents = rest ? 3 : 0;
  cloud.points.reserve(3 * options.pointsPerFrame);
  for (std::size_t i = 0; i < options.pointsPerFrame; ++i)
  {
    const SurfacePoint s = areas.draw(random);
    Vec3 p = evaluate(positions, triangles, s);
    // Draw the noise even for points dropped later, so the stream does not depend on holes.
    const Vec3 noise{random.gaussian(), random.gaussian(), random.gaussian()};
    if (inAnyHole(p, holes, r2))
      continue;
    p.x += options.noiseStdDev * noise.x;
    p.y += options.noiseStdDev * noise.y;
    p.z += options.noiseStdDev * noise.z;
    cloud.points.insert(cloud.points.end(), {p.x, p.y, p.z});
    if (options.normals)
      appendNormal(normals, triangles, s, cloud);
    if (rest)
      appendColour(*rest, triangles, s, diagonal, cloud);
  }
  return cloud;
}

std::string writeFrameSequence(
    const AnimatedMesh& mesh, const std::string& outDir, const SequenceWriteOptions& writing,
    const std::function<PointCloud(const std::vector<double>&, std::size_t)>& makeFrame)
{
  std::error_code ec;
  fs::create_directories(outDir, ec);
  if (ec)
    throw FileError(outDir, "cannot create folder (" + ec.message() + ")");
  if (writing.writeGroundTruth)
  {
    fs::create_directories(fs::path(outDir) / "truth", ec);
    if (ec)
      throw FileError(outDir + "/truth", "cannot create folder (" + ec.message() + ")");
  }
  nlohmann::json series;
  series["file-series-version"] = "1.0";
  series["files"] = nlohmann::json::array();
  for (std::size_t f = 0; f < mesh.numberOfFrames(); ++f)
  {
    char number[32];
    std::snprintf(number, sizeof(number), "%04zu", f);
    const std::string name = writing.filePrefix + number + "." + writing.extension;
    PointCloud frame = makeFrame(mesh.positions(f), f);
    if (writing.transform)
      frame = writing.transform(std::move(frame), f);
    writePointCloud((fs::path(outDir) / name).string(), frame);
    if (writing.writeGroundTruth)
    {
      PointCloud truth = mesh.frameMesh(f);
      writePLY((fs::path(outDir) / "truth" / (writing.filePrefix + number + ".ply")).string(),
               truth);
    }
    series["files"].push_back(
        {{"name", name}, {"time", static_cast<double>(f) * writing.frameInterval}});
  }
  const std::string seriesPath = (fs::path(outDir) / "points.series").string();
  std::ofstream out(seriesPath);
  out << series.dump(2) << "\n";
  if (!out)
    throw FileError(seriesPath, "cannot write the .series file");
  return seriesPath;
}

std::string writeSampledSequence(const AnimatedMesh& mesh, const SamplerOptions& sampling,
                                 const std::string& outDir, const SequenceWriteOptions& writing)
{
  // A colour fixed to the material: the pattern over the first frame's shape.
  const std::vector<double> rest = sampling.colours ? mesh.positions(0) : std::vector<double>{};
  SamplerOptions options = sampling;
  options.colourRest = &rest;
  return writeFrameSequence(mesh, outDir, writing,
                            [&](const std::vector<double>& positions, std::size_t f)
                            { return sampleSurface(positions, mesh.triangles(), options, f); });
}

} // namespace dp
