// SPDX-License-Identifier: BSD-3-Clause
// A rig of simulated depth cameras around an animated mesh (DepthRig.h); its description and
// the sequences it writes are in DepthRigFiles.cxx.
#include "dp/geometry/DepthRig.h"

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/DeterministicRandom.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/support/Parallel.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace dp
{

namespace
{

constexpr double Pi = 3.141592653589793;
constexpr double Degree = Pi / 180.0;
// A silhouette pixel: a neighbour sees nothing, or something this much farther (metres).
constexpr double SilhouetteJump = 0.1;
// Incidence this far below the grazing limit begins to lose returns (degrees).
constexpr double GrazingRamp = 10;
// Returns fade on surfaces darker than this luminance.
constexpr double DarkLuminance = 0.25;
constexpr double FloorAlbedo = 0.45;

double dot(const double a[3], const double b[3])
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// The up direction of a name: x, y, z with an optional minus sign.
std::array<double, 3> upOf(const std::string& name)
{
  const bool negative = !name.empty() && name[0] == '-';
  const std::string axis = negative ? name.substr(1) : name;
  std::array<double, 3> up{0, 0, 0};
  if (axis != "x" && axis != "y" && axis != "z")
    throw std::invalid_argument("the rig's up axis must be x, y, z, -x, -y or -z, not '" + name +
                                "'");
  up[static_cast<std::size_t>(axis[0] - 'x')] = negative ? -1 : 1;
  return up;
}

// A rotation of `degrees` (per axis, standard deviation) as a matrix: Rodrigues' formula.
std::array<double, 9> smallRotation(DeterministicRandom& random, double degrees)
{
  double w[3] = {random.gaussian() * degrees * Degree, random.gaussian() * degrees * Degree,
                 random.gaussian() * degrees * Degree};
  const double angle = std::sqrt(dot(w, w));
  std::array<double, 9> r{1, 0, 0, 0, 1, 0, 0, 0, 1};
  if (angle < 1e-15)
    return r;
  for (double& c : w)
    c /= angle;
  const double s = std::sin(angle), c = std::cos(angle), t = 1 - c;
  r = {t * w[0] * w[0] + c,        t * w[0] * w[1] - s * w[2], t * w[0] * w[2] + s * w[1],
       t * w[0] * w[1] + s * w[2], t * w[1] * w[1] + c,        t * w[1] * w[2] - s * w[0],
       t * w[0] * w[2] - s * w[1], t * w[1] * w[2] + s * w[0], t * w[2] * w[2] + c};
  return r;
}

std::array<double, 9> multiply(const std::array<double, 9>& a, const std::array<double, 9>& b)
{
  std::array<double, 9> m{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        m[3 * i + j] += a[3 * i + k] * b[3 * k + j];
  return m;
}

// A pixel's point in the camera at depth z (pixel centres at half-integers, plus a shift).
void unproject(const DepthCamera& c, double x, double y, double z, double p[3])
{
  p[0] = (x + 0.5 - c.cx) / c.fx * z;
  p[1] = (y + 0.5 - c.cy) / c.fy * z;
  p[2] = z;
}

// Whether the sensor returns a pixel of a surface of `albedo` at depth `z`, seen at incidence
// `theta` (radians), where `behind` is the depth a silhouette pixel may mix with (0: none); `z`
// becomes the depth returned, noisy and quantised.
bool sensorReturns(const DepthSensorModel& sensor, double theta,
                   const std::array<double, 3>& albedo, double behind, DeterministicRandom& random,
                   double& z)
{
  // No return at grazing incidence (fading in over the last degrees), fewer on dark surfaces.
  const double luminance = 0.3 * albedo[0] + 0.59 * albedo[1] + 0.11 * albedo[2];
  const double grazing = (theta / Degree - (sensor.grazingLimit - GrazingRamp)) / GrazingRamp;
  const double dark = sensor.darkDropout * std::max(0.0, 1 - luminance / DarkLuminance);
  // A silhouette pixel may mix the surface with what lies behind it (a flying pixel), its
  // return then partly the background's, whatever the incidence.
  const bool mixed = behind > 0 && random.uniform() < sensor.mixedPixels;
  if (mixed)
    z += random.uniform() * (behind - z);
  else if (random.uniform() < grazing || random.uniform() < dark)
    return false;
  z = sensor.quantised(z + random.gaussian() * sensor.axialNoise(z, theta));
  return !(z < sensor.nearRange || z > sensor.farRange);
}

// The r g b bytes a camera of channel `gain`s records of a surface of `albedo` at incidence
// cosine `cosine`: shaded, with noise, appended to `colours`.
void appendColour(const std::array<double, 3>& albedo, double cosine,
                  const std::array<double, 3>& gain, DeterministicRandom& random,
                  std::vector<std::uint8_t>& colours)
{
  const double shade = 0.3 + 0.7 * cosine;
  for (int d = 0; d < 3; ++d)
  {
    const double level = 255 * albedo[d] * shade * gain[d] + 1.5 * random.gaussian();
    colours.push_back(static_cast<std::uint8_t>(std::clamp(std::round(level), 0.0, 255.0)));
  }
}

// Refuses a rig of no or too many cameras, and sizes and errors that are not positive numbers.
void checkRigOptions(const RigOptions& options)
{
  if (options.cameras < 1 || options.cameras > 64)
    throw std::invalid_argument("a rig has 1 to 64 cameras, not " +
                                std::to_string(options.cameras));
  if (!(options.subjectHeight > 0) || !(options.distance >= 0) || !(options.rotationError >= 0) ||
      !(options.translationError >= 0) || !(options.colourGain >= 0) || !(options.meshJump > 0))
    throw std::invalid_argument("the rig's sizes and errors must be positive numbers");
}

// The extent of the take's first frame `rest` along `up` (refused where it has none).
double extentAlong(const std::vector<double>& rest, const double up[3])
{
  double low = 1e300, high = -1e300;
  for (std::size_t v = 0; v + 2 < rest.size(); v += 3)
  {
    low = std::min(low, dot(&rest[v], up));
    high = std::max(high, dot(&rest[v], up));
  }
  if (!(high > low))
    throw std::invalid_argument("the take's first frame has no extent along the rig's up axis");
  return high - low;
}

// Every frame's bounding box (min xyz, max xyz) into `box`; `rest` is frame 0's positions.
void takeBox(const AnimatedMesh& take, const std::vector<double>& rest, double box[6])
{
  for (int i = 0; i < 3; ++i)
  {
    box[i] = 1e300;
    box[3 + i] = -1e300;
  }
  for (std::size_t f = 0; f < take.numberOfFrames(); ++f)
  {
    const std::vector<double> p = f == 0 ? rest : take.positions(f);
    for (std::size_t v = 0; v + 2 < p.size(); v += 3)
      for (int i = 0; i < 3; ++i)
      {
        box[i] = std::min(box[i], p[v + i]);
        box[3 + i] = std::max(box[3 + i], p[v + i]);
      }
  }
}

// The floor's 4 corners (metres): at the take's lowest point along up (its level into `level`),
// a square of the subject's height a side about the capture volume's centre.
std::vector<double> floorCorners(const double box[6], const double centre[3], const double up[3],
                                 double scale, double subjectHeight, double& level)
{
  double lowest = 1e300;
  for (int corner = 0; corner < 8; ++corner)
  {
    const double p[3] = {box[corner & 1 ? 3 : 0], box[corner & 2 ? 4 : 1], box[corner & 4 ? 5 : 2]};
    lowest = std::min(lowest, dot(p, up) * scale);
  }
  const double side[3] = {up[1] != 0 ? 1.0 : 0.0, up[1] != 0 ? 0.0 : 1.0, 0};
  double across[3] = {up[1] * side[2] - up[2] * side[1], up[2] * side[0] - up[0] * side[2],
                      up[0] * side[1] - up[1] * side[0]};
  const double h = subjectHeight, lift = lowest - dot(centre, up);
  level = lowest;
  std::vector<double> corners;
  for (int k = 0; k < 4; ++k)
  {
    const double a = (k == 1 || k == 2) ? h : -h, b = k >= 2 ? h : -h;
    for (int i = 0; i < 3; ++i)
      corners.push_back(centre[i] + lift * up[i] + a * side[i] + b * across[i]);
  }
  return corners;
}

} // namespace

// One camera's points of one frame: in the camera's (believed) frame in metres, with each
// pixel's point index (-1: none), their colours; normals are made from the image after.
struct DepthRig::Capture
{
  std::vector<double> points;
  std::vector<float> normals;
  std::vector<std::uint8_t> colours;
  std::vector<std::int32_t> pointOfPixel;
  int width = 0, height = 0;
};

DepthRig::DepthRig(const AnimatedMesh& take, const RigOptions& options)
    : Options(options), Sensor(depthSensorModel(options.sensor)), Triangles(take.triangles())
{
  checkRigOptions(options);
  const std::array<double, 3> up = upOf(options.up);
  std::copy(up.begin(), up.end(), Up);
  Rest = take.positions(0);
  RestDiagonal = boundingBoxDiagonal(Rest);
  Scale = options.subjectHeight / extentAlong(Rest, Up);
  // The capture volume: every frame's box, and a margin of 5 % of its size.
  double box[6];
  takeBox(take, Rest, box);
  double centre[3], radius2 = 0;
  for (int i = 0; i < 3; ++i)
  {
    const double margin = 0.05 * (box[3 + i] - box[i]) + 0.02 / Scale;
    Box[i] = box[i] - margin;
    Box[3 + i] = box[3 + i] + margin;
    centre[i] = 0.5 * (box[i] + box[3 + i]) * Scale;
    radius2 += 0.25 * (box[3 + i] - box[i]) * (box[3 + i] - box[i]) * Scale * Scale;
  }
  if (options.floor)
    FloorCorners = floorCorners(box, centre, Up, Scale, options.subjectHeight, FloorLevel);
  placeCameras(centre, std::sqrt(radius2));
}

void DepthRig::placeCameras(const double centre[3], double radius)
{
  const double view = std::min(Sensor.horizontalFov, Sensor.verticalFov) * Degree;
  const double distance = Options.distance > 0
                              ? Options.distance
                              : std::max(radius / std::sin(0.45 * view), Sensor.nearRange + radius);
  // Two directions across `up` for the circle.
  const double pick[3] = {std::abs(Up[2]) < 0.9 ? 0.0 : 1.0, 0, std::abs(Up[2]) < 0.9 ? 1.0 : 0.0};
  double e1[3] = {pick[0], pick[1], pick[2]};
  const double e2[3] = {Up[1] * e1[2] - Up[2] * e1[1], Up[2] * e1[0] - Up[0] * e1[2],
                        Up[0] * e1[1] - Up[1] * e1[0]};
  DeterministicRandom random(Options.seed, 0xCA3E7A);
  const std::size_t n = Options.cameras;
  for (std::size_t k = 0; k < n; ++k)
  {
    const double phi = (Options.azimuth + 360.0 * static_cast<double>(k) / n) * Degree;
    // Six cameras or more: two rings, low and high, as rigs are built; fewer, a little high.
    const double height = Options.subjectHeight * (n >= 6 ? (k % 2 ? 0.3 : -0.2) : 0.1);
    double eye[3];
    for (int i = 0; i < 3; ++i)
      eye[i] =
          centre[i] + distance * (std::cos(phi) * e1[i] + std::sin(phi) * e2[i]) + height * Up[i];
    const DepthCamera believed = DepthCamera::lookingAt(Sensor, eye, centre, Up);
    DepthCamera actual = believed;
    actual.rotation = multiply(believed.rotation, smallRotation(random, Options.rotationError));
    for (double& t : actual.translation)
      t += random.gaussian() * Options.translationError;
    Believed.push_back(believed);
    Actual.push_back(actual);
    std::array<double, 3> gain;
    for (double& g : gain)
      g = std::max(0.2, 1 + random.gaussian() * Options.colourGain);
    Gains.push_back(gain);
  }
}

// The scene in metres: the subject, then the floor's two triangles.
void DepthRig::sceneOf(const std::vector<double>& positions, std::vector<double>& scene,
                       std::vector<std::int64_t>& triangles) const
{
  scene.resize(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i)
    scene[i] = positions[i] * Scale;
  triangles = Triangles;
  if (FloorCorners.empty())
    return;
  const auto first = static_cast<std::int64_t>(scene.size() / 3);
  scene.insert(scene.end(), FloorCorners.begin(), FloorCorners.end());
  for (std::int64_t c : {0, 1, 2, 0, 2, 3})
    triangles.push_back(first + c);
}

// What pixel i of the rendered image shows: the incidence's cosine and the material's colour
// (the subject's pattern at its rest position, or the floor's grey).
DepthRig::Surface DepthRig::surfaceAt(const DepthImage& image, std::size_t i,
                                      const std::vector<double>& scene,
                                      const std::vector<std::int64_t>& triangles,
                                      const DepthCamera& camera, const double ray[3]) const
{
  const auto tri = static_cast<std::size_t>(image.triangle[i]);
  const std::int64_t* t = &triangles[3 * tri];
  const double *a = &scene[3 * t[0]], *b = &scene[3 * t[1]], *c = &scene[3 * t[2]];
  const double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double world[3] = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2],
                           ab[0] * ac[1] - ab[1] * ac[0]};
  double n[3]; // the normal in the camera: the rotation's transpose
  for (int j = 0; j < 3; ++j)
    n[j] = camera.rotation[j] * world[0] + camera.rotation[3 + j] * world[1] +
           camera.rotation[6 + j] * world[2];
  Surface s;
  s.cosine = std::min(1.0, std::abs(dot(n, ray)) / std::sqrt(dot(n, n) * dot(ray, ray)));
  s.albedo = {FloorAlbedo, FloorAlbedo, FloorAlbedo};
  if (tri < Triangles.size() / 3)
  {
    const double w1 = image.barycentric[i][0], w2 = image.barycentric[i][1], w0 = 1 - w1 - w2;
    double rest[3];
    for (int d = 0; d < 3; ++d)
      rest[d] = w0 * Rest[3 * t[0] + d] + w1 * Rest[3 * t[1] + d] + w2 * Rest[3 * t[2] + d];
    materialColour(rest, RestDiagonal, s.albedo.data());
  }
  return s;
}

// The depth a silhouette pixel (x, y) at depth z may mix with: the farthest neighbour that is
// empty (the far range) or beyond a jump; 0 inside a surface.
double DepthRig::behindSilhouette(const DepthImage& image, int x, int y, double z) const
{
  double behind = 0;
  for (const auto& [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}})
  {
    const int u = x + dx, v = y + dy;
    const double d = u < 0 || v < 0 || u >= image.width || v >= image.height
                         ? 0.0
                         : image.depth[static_cast<std::size_t>(v) * image.width + u];
    if (d <= 0 || d > z + SilhouetteJump)
      behind = std::max(behind, d <= 0 ? Sensor.farRange : d);
  }
  return behind;
}

DepthRig::Capture DepthRig::capture(const std::vector<double>& positions, std::size_t k,
                                    std::size_t frame) const
{
  std::vector<double> scene;
  std::vector<std::int64_t> triangles;
  sceneOf(positions, scene, triangles);
  const DepthCamera& seen = Actual[k];
  const DepthImage image = renderDepth(seen, scene, triangles);
  DeterministicRandom random(Options.seed, 1 + 4096 * static_cast<std::uint64_t>(frame) + k);
  Capture c;
  c.width = image.width;
  c.height = image.height;
  c.pointOfPixel.assign(image.depth.size(), -1);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x)
    {
      const std::size_t i = static_cast<std::size_t>(y) * image.width + x;
      double z = image.depth[i];
      if (z <= 0)
        continue;
      double ray[3];
      unproject(seen, x, y, z, ray);
      const Surface s = surfaceAt(image, i, scene, triangles, seen, ray);
      const double theta = std::acos(s.cosine);
      const double behind = behindSilhouette(image, x, y, z);
      if (!sensorReturns(Sensor, theta, s.albedo, behind, random, z))
        continue;
      const double lateral = Sensor.lateralNoise(theta);
      double p[3];
      unproject(seen, x + random.gaussian() * lateral, y + random.gaussian() * lateral, z, p);
      c.pointOfPixel[i] = static_cast<std::int32_t>(c.points.size() / 3);
      c.points.insert(c.points.end(), p, p + 3);
      appendColour(s.albedo, s.cosine, Gains[k], random, c.colours);
    }
  estimateNormals(c);
  return c;
}

void DepthRig::estimateNormals(Capture& c)
{
  c.normals.assign(c.points.size(), 0.0f);
  const auto pointAt = [&](int x, int y, const double* otherwise) -> const double*
  {
    if (x < 0 || y < 0 || x >= c.width || y >= c.height)
      return otherwise;
    const std::int32_t p = c.pointOfPixel[static_cast<std::size_t>(y) * c.width + x];
    return p < 0 ? otherwise : &c.points[3 * static_cast<std::size_t>(p)];
  };
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x)
    {
      const std::int32_t index = c.pointOfPixel[static_cast<std::size_t>(y) * c.width + x];
      if (index < 0)
        continue;
      const double* p = &c.points[3 * static_cast<std::size_t>(index)];
      const double *l = pointAt(x - 1, y, p), *r = pointAt(x + 1, y, p);
      const double *u = pointAt(x, y - 1, p), *d = pointAt(x, y + 1, p);
      const double h[3] = {r[0] - l[0], r[1] - l[1], r[2] - l[2]};
      const double v[3] = {d[0] - u[0], d[1] - u[1], d[2] - u[2]};
      double n[3] = {h[1] * v[2] - h[2] * v[1], h[2] * v[0] - h[0] * v[2],
                     h[0] * v[1] - h[1] * v[0]};
      if (!(dot(n, n) > 0)) // no neighbours: facing the camera
        n[0] = -p[0], n[1] = -p[1], n[2] = -p[2];
      const double scale = (dot(n, p) > 0 ? -1 : 1) / std::sqrt(dot(n, n));
      for (int q = 0; q < 3; ++q)
        c.normals[3 * static_cast<std::size_t>(index) + q] = static_cast<float>(n[q] * scale);
    }
}

// A capture in the take's units, in the world where the rig believes the camera stands: only
// the points inside the capture volume (and each pixel's index among those kept).
PointCloud DepthRig::toWorld(Capture& c, std::size_t k) const
{
  PointCloud cloud;
  cloud.colorComponents = 3;
  std::vector<std::int32_t> kept(c.points.size() / 3, -1);
  const DepthCamera& believed = Believed[k];
  for (std::size_t p = 0; p < kept.size(); ++p)
  {
    double w[3], n[3];
    believed.toWorld(&c.points[3 * p], w);
    bool inside = true;
    for (int i = 0; i < 3; ++i)
    {
      w[i] /= Scale;
      inside = inside && w[i] >= Box[i] && w[i] <= Box[3 + i];
    }
    // Outside the volume: dropped, but for the floor where there is one (its patch kept).
    if (!inside && (FloorCorners.empty() || std::abs(dot(w, Up) * Scale - FloorLevel) > 0.05))
      continue;
    const double local[3] = {c.normals[3 * p], c.normals[3 * p + 1], c.normals[3 * p + 2]};
    for (int i = 0; i < 3; ++i)
      n[i] = believed.rotation[3 * i] * local[0] + believed.rotation[3 * i + 1] * local[1] +
             believed.rotation[3 * i + 2] * local[2];
    kept[p] = static_cast<std::int32_t>(cloud.numberOfPoints());
    cloud.points.insert(cloud.points.end(), w, w + 3);
    for (int i = 0; i < 3; ++i)
      cloud.normals.push_back(static_cast<float>(n[i]));
    cloud.colors.insert(cloud.colors.end(), c.colours.begin() + 3 * p,
                        c.colours.begin() + 3 * p + 3);
  }
  for (std::int32_t& p : c.pointOfPixel)
    p = p < 0 ? -1 : kept[static_cast<std::size_t>(p)];
  return cloud;
}

PointCloud DepthRig::fusedCloud(const std::vector<double>& positions, std::size_t frame) const
{
  std::vector<PointCloud> views(cameras());
  forEachIndex(cameras(),
               [&](std::size_t k)
               {
                 Capture c = capture(positions, k, frame);
                 views[k] = toWorld(c, k);
               });
  PointCloud fused;
  fused.colorComponents = 3;
  for (const PointCloud& v : views)
  {
    fused.points.insert(fused.points.end(), v.points.begin(), v.points.end());
    fused.normals.insert(fused.normals.end(), v.normals.begin(), v.normals.end());
    fused.colors.insert(fused.colors.end(), v.colors.begin(), v.colors.end());
  }
  const std::size_t n = fused.numberOfPoints();
  if (Options.points == 0 || n <= Options.points)
    return fused;
  // Thinned to a random subset, in the order the cameras gave them.
  DeterministicRandom random(Options.seed, 0x7417 + 4096 * static_cast<std::uint64_t>(frame));
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i)
    order[i] = i;
  for (std::size_t i = 0; i < Options.points; ++i)
    std::swap(order[i], order[i + static_cast<std::size_t>(random.uniform() * (n - i))]);
  order.resize(Options.points);
  std::sort(order.begin(), order.end());
  PointCloud thin;
  thin.colorComponents = 3;
  for (std::size_t i : order)
  {
    thin.points.insert(thin.points.end(), &fused.points[3 * i], &fused.points[3 * i] + 3);
    thin.normals.insert(thin.normals.end(), &fused.normals[3 * i], &fused.normals[3 * i] + 3);
    thin.colors.insert(thin.colors.end(), &fused.colors[3 * i], &fused.colors[3 * i] + 3);
  }
  return thin;
}

namespace
{

// The points that `used` marks, with the faces (triangles of the old indices) renumbered.
PointCloud compacted(const PointCloud& all, const std::vector<std::int64_t>& faces,
                     const std::vector<char>& used)
{
  PointCloud mesh;
  mesh.colorComponents = all.colorComponents;
  std::vector<std::int64_t> index(used.size(), -1);
  for (std::size_t p = 0; p < used.size(); ++p)
  {
    if (!used[p])
      continue;
    index[p] = static_cast<std::int64_t>(mesh.numberOfPoints());
    mesh.points.insert(mesh.points.end(), &all.points[3 * p], &all.points[3 * p] + 3);
    mesh.normals.insert(mesh.normals.end(), &all.normals[3 * p], &all.normals[3 * p] + 3);
    mesh.colors.insert(mesh.colors.end(), &all.colors[3 * p], &all.colors[3 * p] + 3);
  }
  for (std::size_t f = 0; f + 2 < faces.size(); f += 3)
  {
    const std::int64_t ids[3] = {index[static_cast<std::size_t>(faces[f])],
                                 index[static_cast<std::size_t>(faces[f + 1])],
                                 index[static_cast<std::size_t>(faces[f + 2])]};
    mesh.addFace(ids, 3);
  }
  return mesh;
}

} // namespace

PointCloud DepthRig::depthMesh(const std::vector<double>& positions, std::size_t k,
                               std::size_t frame) const
{
  if (k >= cameras())
    throw std::invalid_argument("the rig has no camera " + std::to_string(k));
  Capture c = capture(positions, k, frame);
  const std::vector<std::int32_t> captured = c.pointOfPixel; // indices into c.points
  const PointCloud all = toWorld(c, k);                      // c.pointOfPixel: into all
  // Each quad of neighbouring pixels whose four points were kept and lie within a depth step
  // becomes two triangles facing the camera.
  std::vector<std::int64_t> faces;
  std::vector<char> used(all.numberOfPoints(), 0);
  for (int y = 0; y + 1 < c.height; ++y)
    for (int x = 0; x + 1 < c.width; ++x)
    {
      const std::size_t pixel[4] = {static_cast<std::size_t>(y) * c.width + x,
                                    static_cast<std::size_t>(y) * c.width + x + 1,
                                    static_cast<std::size_t>(y + 1) * c.width + x,
                                    static_cast<std::size_t>(y + 1) * c.width + x + 1};
      double low = 1e300, high = -1e300;
      bool complete = true;
      for (std::size_t i : pixel)
      {
        complete = complete && c.pointOfPixel[i] >= 0;
        if (!complete)
          break;
        const double z = c.points[3 * static_cast<std::size_t>(captured[i]) + 2];
        low = std::min(low, z);
        high = std::max(high, z);
      }
      if (!complete || high - low > Options.meshJump)
        continue;
      for (int corner : {0, 2, 1, 1, 2, 3})
      {
        const std::int32_t v = c.pointOfPixel[pixel[corner]];
        faces.push_back(v);
        used[static_cast<std::size_t>(v)] = 1;
      }
    }
  return compacted(all, faces, used);
}

} // namespace dp
