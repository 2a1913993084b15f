// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/ColourTerm.h"

#include "dp/support/KdTree.h"
#include "dp/support/Parallel.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>
#include <utility>

namespace dp
{
namespace
{
// A full swing of a colour channel (0 to 1) weighs as this many voxels of distance.
constexpr double ColourLength = 10.0;
// The kernel's reach, in kernel widths (the weight there: 4 % of the centre's).
constexpr double Reach = 2.5;
// The coarser levels' cells, in fine kernels (ColourField::kernel()): for kernels from 2 and 3
// fine kernels wide.
constexpr double CoarseCells[] = {2.0, 3.0};
} // namespace

// The field's points at one resolution: the frame's own, or their means over grid cells (with
// each cell's count as its weight), so a wide kernel reads a few hundred cells, not thousands of
// points.
struct ColourField::Level
{
  const double* points = nullptr;
  const float* colours = nullptr;
  const float* counts = nullptr; // null: 1 each
  double cell = 0;               // 0: the frame's own points
  std::vector<double> ownPoints;
  std::vector<float> ownColours, ownCounts;
  std::unique_ptr<support::KdTree> tree;

  Level(const double* p, const float* c, std::size_t count) : points(p), colours(c)
  {
    tree = std::make_unique<support::KdTree>(points, count);
  }
  // The means of `finest`'s points over cells of size `size`, in the cells' order (sorted keys:
  // the same on any platform).
  Level(const Level& finest, std::size_t count, double size) : cell(size)
  {
    struct Sum
    {
      double p[3] = {0, 0, 0};
      double c[3] = {0, 0, 0};
      double n = 0;
    };
    std::unordered_map<std::uint64_t, Sum> cells;
    for (std::size_t i = 0; i < count; ++i)
    {
      std::uint64_t key = 0;
      for (int k = 0; k < 3; ++k)
      {
        const double u = std::clamp(finest.points[3 * i + k] / size, -1e15, 1e15);
        key = (key << 21) | (static_cast<std::uint64_t>(std::floor(u)) & 0x1FFFFF);
      }
      Sum& sum = cells[key];
      for (int k = 0; k < 3; ++k)
      {
        sum.p[k] += finest.points[3 * i + k];
        sum.c[k] += finest.colours[3 * i + k];
      }
      sum.n += 1;
    }
    std::vector<std::uint64_t> keys;
    keys.reserve(cells.size());
    for (const auto& entry : cells)
      keys.push_back(entry.first);
    std::sort(keys.begin(), keys.end());
    for (std::uint64_t key : keys)
    {
      const Sum& sum = cells[key];
      for (int k = 0; k < 3; ++k)
      {
        ownPoints.push_back(sum.p[k] / sum.n);
        ownColours.push_back(static_cast<float>(sum.c[k] / sum.n));
      }
      ownCounts.push_back(static_cast<float>(sum.n));
    }
    points = ownPoints.data();
    colours = ownColours.data();
    counts = ownCounts.data();
    tree = std::make_unique<support::KdTree>(points, ownCounts.size());
  }
};

ColourField::ColourField(const double* points, const float* colours, std::size_t count,
                         double spacing, double voxel)
    : Spacing(spacing), Voxel(voxel)
{
  Levels.push_back(std::make_unique<Level>(points, colours, count));
  for (double cells : CoarseCells)
    Levels.push_back(std::make_unique<Level>(*Levels[0], count, cells * kernel()));
}

double ColourField::kernel(double scale) const
{
  return scale * std::max(Spacing, Voxel);
}

ColourField::~ColourField() = default;

double ColourField::sample(const double x[3], double sigma, double rgb[3], double* jacobian) const
{
  // The coarsest level whose cells are at most the kernel wide (a cell's mean blurs by its
  // width / sqrt(12): the kernel grows by 4 % at most).
  const Level* level = Levels[0].get();
  for (const auto& l : Levels)
    if (l->cell > 0 && l->cell <= sigma)
      level = l.get();
  // nanoflann answers in the same order for the same tree and query: the sums below are the
  // same on any thread.
  std::vector<std::pair<std::uint32_t, double>> found;
  level->tree->within(x, Reach * Reach * sigma * sigma, found);
  if (found.empty())
    return 0;
  const double inverse2 = 1 / (2 * sigma * sigma);
  std::vector<double> weights(found.size());
  double total = 0, mean[3] = {0, 0, 0};
  for (std::size_t j = 0; j < found.size(); ++j)
  {
    const std::uint32_t p = found[j].first;
    const double w = std::exp(-found[j].second * inverse2) * (level->counts ? level->counts[p] : 1);
    weights[j] = w;
    total += w;
    for (int c = 0; c < 3; ++c)
      mean[c] += w * level->colours[3 * p + c];
  }
  if (!(total > 0))
    return 0;
  for (int c = 0; c < 3; ++c)
    rgb[c] = mean[c] / total;
  if (jacobian)
  {
    std::fill(jacobian, jacobian + 9, 0.0);
    for (std::size_t j = 0; j < found.size(); ++j)
    {
      const std::uint32_t p = found[j].first;
      const double w = weights[j] / (total * sigma * sigma);
      const double* q = &level->points[3 * p];
      for (int c = 0; c < 3; ++c)
      {
        const double dc = level->colours[3 * p + c] - rgb[c];
        for (int k = 0; k < 3; ++k)
          jacobian[3 * c + k] += w * dc * (q[k] - x[k]);
      }
    }
  }
  return total;
}

std::vector<float> vertexColours(const ColourField& field, const double* positions,
                                 std::size_t vertices, double sigma,
                                 const std::vector<float>* previous)
{
  std::vector<float> out(3 * vertices, -1.0f);
  forEachIndex(vertices,
               [&](std::size_t v)
               {
                 double rgb[3];
                 if (field.sample(&positions[3 * v], sigma, rgb) > 0)
                   for (int c = 0; c < 3; ++c)
                     out[3 * v + c] = static_cast<float>(rgb[c]);
                 else if (previous && previous->size() == out.size())
                   std::copy(previous->begin() + 3 * v, previous->begin() + 3 * v + 3,
                             out.begin() + 3 * v);
               });
  return out;
}

ColourTerm::ColourTerm(const ColourField& field, const TriangleMesh& mesh,
                       const std::vector<float>& reference, const std::vector<double>& mass,
                       double weight, double lengthScale, double voxel, double sigma)
    : Field(field), Mesh(mesh), Reference(&reference), Mass(mass),
      Scale(weight * ColourLength * ColourLength * voxel / lengthScale), Sigma(sigma)
{
  setKernel(sigma, reference);
}

void ColourTerm::setKernel(double sigma, const std::vector<float>& reference)
{
  if (reference.size() != 3 * Mass.size())
    throw std::invalid_argument("colour term: a reference colour per vertex is needed");
  Sigma = sigma;
  Reference = &reference;
}

void ColourTerm::linearise(const double* x)
{
  const std::size_t n = Mass.size();
  Normals.resize(3 * n);
  Mesh.vertexNormals(x, Normals.data());
  LinearisedAt.assign(x, x + 3 * n);
  // The model at x, which the solvers build next (addModel at the same x).
  Linearised.assign(n, VertexModel{});
  forEachIndex(n,
               [&](std::size_t v)
               {
                 VertexModel& m = Linearised[v];
                 m.energy = vertexEnergy(x, v, m.residual, m.jacobian);
               });
}

double ColourTerm::vertexEnergy(const double* x, std::size_t v, double residual[3],
                                double* jacobian) const
{
  if ((*Reference)[3 * v] < 0)
    return -1;
  // Where the colour is read: the vertex moved along the surface only, from where the term was
  // linearised (x0 + (I - n n^T)(x - x0)), so that J (I - n n^T) is the exact Jacobian.
  const bool along = !Normals.empty();
  const double* n = along ? &Normals[3 * v] : nullptr;
  double at[3] = {x[3 * v], x[3 * v + 1], x[3 * v + 2]};
  if (along)
  {
    const double* x0 = &LinearisedAt[3 * v];
    const double across = (at[0] - x0[0]) * n[0] + (at[1] - x0[1]) * n[1] + (at[2] - x0[2]) * n[2];
    for (int k = 0; k < 3; ++k)
      at[k] -= across * n[k];
  }
  double rgb[3];
  if (!(Field.sample(at, Sigma, rgb, jacobian) > 0))
    return -1;
  if (jacobian && along)
    for (int c = 0; c < 3; ++c)
    {
      double* row = jacobian + 3 * c;
      const double normal = row[0] * n[0] + row[1] * n[1] + row[2] * n[2];
      for (int k = 0; k < 3; ++k)
        row[k] -= normal * n[k];
    }
  double e = 0;
  for (int c = 0; c < 3; ++c)
  {
    residual[c] = rgb[c] - (*Reference)[3 * v + c];
    e += residual[c] * residual[c];
  }
  return 0.5 * Scale * Mass[v] * e;
}

double ColourTerm::evaluate(const double* x, double* gradient) const
{
  const std::size_t n = Mass.size();
  std::vector<double> energy(n, 0.0);
  forEachIndex(n,
               [&](std::size_t v)
               {
                 double r[3], J[9];
                 const double e = vertexEnergy(x, v, r, gradient ? J : nullptr);
                 if (e < 0)
                   return;
                 energy[v] = e;
                 if (!gradient)
                   return;
                 const double c = Scale * Mass[v];
                 for (int k = 0; k < 3; ++k)
                   gradient[3 * v + k] += c * (J[k] * r[0] + J[3 + k] * r[1] + J[6 + k] * r[2]);
               });
  double total = 0;
  for (double e : energy)
    total += e;
  return total;
}

double ColourTerm::addModel(const double* x, support::BlockSparseMatrix& hessian,
                            double* gradient) const
{
  const std::size_t n = Mass.size();
  std::vector<double> energy(n, 0.0);
  const bool cached =
      LinearisedAt.size() == 3 * n && std::equal(x, x + 3 * n, LinearisedAt.begin());
  forEachIndex(
      n,
      [&](std::size_t v)
      {
        VertexModel fresh;
        if (!cached)
          fresh.energy = vertexEnergy(x, v, fresh.residual, fresh.jacobian);
        const VertexModel& m = cached ? Linearised[v] : fresh;
        if (m.energy < 0)
          return;
        energy[v] = m.energy;
        const double *r = m.residual, *J = m.jacobian;
        const double c = Scale * Mass[v];
        double block[9];
        for (int i = 0; i < 3; ++i)
        {
          gradient[3 * v + i] += c * (J[i] * r[0] + J[3 + i] * r[1] + J[6 + i] * r[2]);
          for (int k = 0; k < 3; ++k)
            block[3 * i + k] = c * (J[i] * J[k] + J[3 + i] * J[3 + k] + J[6 + i] * J[6 + k]);
        }
        hessian.addBlock(hessian.slotOf(static_cast<std::int64_t>(v), static_cast<std::int64_t>(v)),
                         block);
      });
  double total = 0;
  for (double e : energy)
    total += e;
  return total;
}

} // namespace dp
