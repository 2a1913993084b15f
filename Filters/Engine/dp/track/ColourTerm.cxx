// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/ColourTerm.h"

#include "dp/detail/KdTree.h"
#include "dp/track/Parallel.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace dp
{
namespace
{
// A full swing of a colour channel (0 to 1) weighs as this many voxels of distance.
constexpr double ColourLength = 10.0;
// The kernel's reach, in kernel widths.
constexpr double Reach = 3.0;
} // namespace

ColourField::ColourField(const FrameSamples& samples) : Samples(samples)
{
  if (!samples.hasColour())
    throw std::invalid_argument("a colour field needs points with colour");
  Tree = std::make_unique<detail::KdTree>(samples.colourPoints.data(),
                                          samples.colourPoints.size() / 3);
}

ColourField::~ColourField() = default;

double ColourField::sample(const double x[3], double sigma, double rgb[3], double* jacobian) const
{
  std::vector<std::pair<std::uint32_t, double>> found;
  Tree->within(x, Reach * Reach * sigma * sigma, found);
  if (found.empty())
    return 0;
  // In index order, so the sums do not depend on the tree's order of answering.
  std::sort(found.begin(), found.end());
  const double inverse2 = 1 / (2 * sigma * sigma);
  double total = 0, mean[3] = {0, 0, 0};
  for (const auto& [p, d2] : found)
  {
    const double w = std::exp(-d2 * inverse2);
    total += w;
    for (int c = 0; c < 3; ++c)
      mean[c] += w * Samples.colours[3 * p + c];
  }
  if (!(total > 0))
    return 0;
  for (int c = 0; c < 3; ++c)
    rgb[c] = mean[c] / total;
  if (jacobian)
  {
    std::fill(jacobian, jacobian + 9, 0.0);
    for (const auto& [p, d2] : found)
    {
      const double w = std::exp(-d2 * inverse2) / (total * sigma * sigma);
      const double* q = &Samples.colourPoints[3 * p];
      for (int c = 0; c < 3; ++c)
      {
        const double dc = Samples.colours[3 * p + c] - rgb[c];
        for (int k = 0; k < 3; ++k)
          jacobian[3 * c + k] += w * dc * (q[k] - x[k]);
      }
    }
  }
  return total;
}

double colourKernel(const FrameSamples& samples, double scale)
{
  return scale * std::max(1.0 * samples.spacing, samples.voxel);
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
    : Field(field), Mesh(mesh), Reference(reference), Mass(mass),
      Scale(weight * ColourLength * ColourLength * voxel / lengthScale), Sigma(sigma)
{
  if (reference.size() != 3 * mass.size())
    throw std::invalid_argument("colour term: a reference colour per vertex is needed");
}

void ColourTerm::linearise(const double* x)
{
  Normals.resize(3 * Mass.size());
  Mesh.vertexNormals(x, Normals.data());
}

double ColourTerm::vertexEnergy(const double* x, std::size_t v, double residual[3],
                                double* jacobian) const
{
  if (Reference[3 * v] < 0)
    return -1;
  double rgb[3];
  if (!(Field.sample(&x[3 * v], Sigma, rgb, jacobian) > 0))
    return -1;
  if (jacobian && !Normals.empty())
  {
    // J (I - n n^T): the colour's change along the surface.
    const double* n = &Normals[3 * v];
    for (int c = 0; c < 3; ++c)
    {
      double* row = jacobian + 3 * c;
      const double along = row[0] * n[0] + row[1] * n[1] + row[2] * n[2];
      for (int k = 0; k < 3; ++k)
        row[k] -= along * n[k];
    }
  }
  double e = 0;
  for (int c = 0; c < 3; ++c)
  {
    residual[c] = rgb[c] - Reference[3 * v + c];
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

double ColourTerm::addModel(const double* x, detail::BlockSparseMatrix& hessian,
                            double* gradient) const
{
  const std::size_t n = Mass.size();
  std::vector<double> energy(n, 0.0);
  forEachIndex(
      n,
      [&](std::size_t v)
      {
        double r[3], J[9];
        const double e = vertexEnergy(x, v, r, J);
        if (e < 0)
          return;
        energy[v] = e;
        const double c = Scale * Mass[v];
        double block[9];
        for (int i = 0; i < 3; ++i)
        {
          gradient[3 * v + i] += c * (J[i] * r[0] + J[3 + i] * r[1] + J[6 + i] * r[2]);
          for (int j = 0; j < 3; ++j)
            block[3 * i + j] = c * (J[i] * J[j] + J[3 + i] * J[3 + j] + J[6 + i] * J[6 + j]);
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
