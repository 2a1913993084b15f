// SPDX-License-Identifier: BSD-3-Clause
// Colour as a cue along the surface: the colour field (its mean and Jacobian against finite
// differences, its coarse levels against every point), the colour term (gradient and model, only
// along the surface), the vertices' colours, and tracking a spinning ball whose only cue is a
// colour pattern fixed to its material.
#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/geometry/TriangleMesh.h"
#include "dp/track/ColourTerm.h"
#include "dp/track/Tracker.h"

#include "NumericChecks.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace
{

using dp::test::expectGradientMatches;
using dp::test::jiggle;

// A UV sphere of radius 0.5 (closed: its poles are single vertices).
struct Ball
{
  std::vector<double> positions;
  std::vector<std::int64_t> triangles;
};

Ball ball(std::size_t rings = 24, std::size_t segments = 36)
{
  Ball b;
  b.positions = {0.0, 0.0, 0.5};
  for (std::size_t i = 1; i < rings; ++i)
    for (std::size_t j = 0; j < segments; ++j)
    {
      const double theta = M_PI * static_cast<double>(i) / static_cast<double>(rings);
      const double phi = 2 * M_PI * static_cast<double>(j) / static_cast<double>(segments);
      b.positions.insert(b.positions.end(),
                         {0.5 * std::sin(theta) * std::cos(phi),
                          0.5 * std::sin(theta) * std::sin(phi), 0.5 * std::cos(theta)});
    }
  b.positions.insert(b.positions.end(), {0, 0, -0.5});
  const auto ring = [&](std::size_t i, std::size_t j)
  { return static_cast<std::int64_t>(1 + (i - 1) * segments + j % segments); };
  const auto south = static_cast<std::int64_t>(b.positions.size() / 3 - 1);
  for (std::size_t j = 0; j < segments; ++j)
  {
    b.triangles.insert(b.triangles.end(), {0, ring(1, j), ring(1, j + 1)});
    b.triangles.insert(b.triangles.end(), {south, ring(rings - 1, j + 1), ring(rings - 1, j)});
    for (std::size_t i = 1; i + 1 < rings; ++i)
    {
      b.triangles.insert(b.triangles.end(), {ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      b.triangles.insert(b.triangles.end(), {ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  }
  return b;
}

// x turned about z by `angle`.
std::vector<double> turned(const std::vector<double>& x, double angle)
{
  std::vector<double> y(x.size());
  for (std::size_t i = 0; i < x.size(); i += 3)
  {
    y[i] = std::cos(angle) * x[i] - std::sin(angle) * x[i + 1];
    y[i + 1] = std::sin(angle) * x[i] + std::cos(angle) * x[i + 1];
    y[i + 2] = x[i + 2];
  }
  return y;
}

// Points with the sampler's material colour on the ball, as floats in [0, 1].
struct ColouredPoints
{
  dp::PointCloud cloud;
  std::vector<float> colours;
};

ColouredPoints colouredBall(const Ball& b, double angle, std::size_t count, std::size_t frame)
{
  dp::SamplerOptions o;
  o.pointsPerFrame = count;
  o.colours = true;
  o.colourRest = &b.positions;
  ColouredPoints p{dp::sampleSurface(turned(b.positions, angle), b.triangles, o, frame), {}};
  for (std::uint8_t c : p.cloud.colors)
    p.colours.push_back(static_cast<float>(c) / 255.0f);
  return p;
}

double vertexRms(const std::vector<double>& a, const std::vector<double>& b)
{
  double e = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    e += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(e / static_cast<double>(a.size() / 3));
}

TEST(ColourField, MeanAndJacobianMatchFiniteDifferences)
{
  const Ball b = ball();
  const ColouredPoints p = colouredBall(b, 0, 5000, 0);
  const dp::ColourField field(p.cloud.points.data(), p.colours.data(), p.cloud.numberOfPoints(),
                              0.015, 0.01);
  const double sigma = field.kernel();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 20; ++trial)
  {
    double x[3] = {u(rng), u(rng), u(rng)};
    const double length = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    for (double& c : x)
      c *= 0.5 / length; // on the ball
    double rgb[3], J[9];
    ASSERT_GT(field.sample(x, sigma, rgb, J), 0);
    const double h = 1e-6;
    for (int k = 0; k < 3; ++k)
    {
      double plus[3] = {x[0], x[1], x[2]}, minus[3] = {x[0], x[1], x[2]}, a[3], b2[3];
      plus[k] += h;
      minus[k] -= h;
      field.sample(plus, sigma, a);
      field.sample(minus, sigma, b2);
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR((a[c] - b2[c]) / (2 * h), J[3 * c + k], 1e-4 * (1 + std::abs(J[3 * c + k])));
    }
  }
}

TEST(ColourField, AWideKernelReadsCellMeansThatAgreeWithEveryPoint)
{
  const Ball b = ball();
  const ColouredPoints p = colouredBall(b, 0, 20000, 0);
  const std::size_t n = p.cloud.numberOfPoints();
  const dp::ColourField field(p.cloud.points.data(), p.colours.data(), n, 0.01, 0.01);
  const double sigma = field.kernel(3); // read from the coarse cells
  double worst = 0;
  for (std::size_t v = 0; v < b.positions.size(); v += 37)
  {
    const double* x = &b.positions[v];
    double rgb[3];
    ASSERT_GT(field.sample(x, sigma, rgb), 0);
    // Every point within reach, weighted by the same kernel.
    double total = 0, mean[3] = {0, 0, 0};
    for (std::size_t i = 0; i < n; ++i)
    {
      double d2 = 0;
      for (int k = 0; k < 3; ++k)
        d2 += (p.cloud.points[3 * i + k] - x[k]) * (p.cloud.points[3 * i + k] - x[k]);
      if (d2 > 6.25 * sigma * sigma)
        continue;
      const double w = std::exp(-d2 / (2 * sigma * sigma));
      total += w;
      for (int c = 0; c < 3; ++c)
        mean[c] += w * p.colours[3 * i + c];
    }
    for (int c = 0; c < 3; ++c)
      worst = std::max(worst, std::abs(rgb[c] - mean[c] / total));
  }
  EXPECT_LT(worst, 0.02); // of a channel's 0..1
}

// The ball, its mesh and mass, and a colour term on a frame of it turned by `angle`.
struct TermProblem
{
  Ball shape = ball(12, 18);
  dp::TriangleMesh mesh{shape.triangles, shape.positions.size() / 3};
  std::vector<double> mass;
  ColouredPoints points;
  std::unique_ptr<dp::ColourField> field;
  std::vector<float> reference;
  std::unique_ptr<dp::ColourTerm> term;

  explicit TermProblem(double angle)
  {
    const std::size_t nv = mesh.numberOfVertices();
    mass = mesh.vertexAreas(shape.positions.data());
    double total = 0;
    for (double m : mass)
      total += m;
    for (double& m : mass)
      m /= total;
    const ColouredPoints first = colouredBall(shape, 0, 8000, 0);
    const dp::ColourField atRest(first.cloud.points.data(), first.colours.data(),
                                 first.cloud.numberOfPoints(), 0.02, 0.01);
    reference = dp::vertexColours(atRest, shape.positions.data(), nv, atRest.kernel());
    points = colouredBall(shape, angle, 8000, 1);
    field = std::make_unique<dp::ColourField>(points.cloud.points.data(), points.colours.data(),
                                              points.cloud.numberOfPoints(), 0.02, 0.01);
    term = std::make_unique<dp::ColourTerm>(*field, mesh, reference, mass, 50.0, 1.0, 0.01,
                                            field->kernel());
  }
};

TEST(ColourTerm, GradientAndModelMatchFiniteDifferences)
{
  TermProblem p(0.05);
  const std::vector<double> x = jiggle(p.shape.positions, 0.002, 5);
  // Before a linearisation the term reads the colour where the vertices are; after one, where
  // they would be moved along the surface from there: both are smooth, with exact gradients.
  for (bool linearised : {false, true})
  {
    if (linearised)
      p.term->linearise(jiggle(x, 0.001, 6).data());
    expectGradientMatches([&](const double* y, double* g) { return p.term->evaluate(y, g); }, x,
                          1e-4, 1e-7);
  }
  // The model at the linearisation: its value and gradient are the term's.
  p.term->linearise(x.data());
  dp::support::BlockSparseMatrix H(p.mesh.numberOfVertices(), {});
  std::vector<double> modelGradient(x.size(), 0.0), gradient(x.size(), 0.0);
  const double modelValue = p.term->addModel(x.data(), H, modelGradient.data());
  const double value = p.term->evaluate(x.data(), gradient.data());
  EXPECT_NEAR(modelValue, value, 1e-12 * value);
  for (std::size_t i = 0; i < x.size(); ++i)
    EXPECT_NEAR(modelGradient[i], gradient[i], 1e-9 * (1 + std::abs(gradient[i])));
  EXPECT_GT(value, 0);
}

TEST(ColourTerm, MovesVerticesAlongTheSurfaceOnly)
{
  TermProblem p(0.05);
  const std::vector<double>& x = p.shape.positions;
  p.term->linearise(x.data());
  dp::support::BlockSparseMatrix H(p.mesh.numberOfVertices(), {});
  std::vector<double> gradient(x.size(), 0.0);
  p.term->addModel(x.data(), H, gradient.data());
  std::vector<double> normals(x.size());
  p.mesh.vertexNormals(x.data(), normals.data());
  double along = 0, largest = 0;
  for (std::size_t v = 0; v < p.mesh.numberOfVertices(); ++v)
  {
    const double* g = &gradient[3 * v];
    const double* n = &normals[3 * v];
    along = std::max(along, std::abs(g[0] * n[0] + g[1] * n[1] + g[2] * n[2]));
    largest = std::max(largest, std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]));
  }
  ASSERT_GT(largest, 0);
  EXPECT_LT(along, 1e-12 * largest);
  // The model's blocks have the normal in their null space.
  const Eigen::SparseMatrix<double> full = H.matrix().selfadjointView<Eigen::Lower>();
  const Eigen::MatrixXd dense(full);
  for (std::size_t v = 0; v < p.mesh.numberOfVertices(); ++v)
  {
    const Eigen::Vector3d n(&normals[3 * v]);
    const auto at = static_cast<Eigen::Index>(3 * v);
    EXPECT_LT((dense.block<3, 3>(at, at) * n).norm(),
              1e-9 * (1 + dense.block<3, 3>(at, at).norm()));
  }
}

TEST(ColourTerm, AVertexWithoutPointsNearItKeepsItsLastColour)
{
  const Ball b = ball(12, 18);
  const ColouredPoints p = colouredBall(b, 0, 4000, 0);
  const dp::ColourField field(p.cloud.points.data(), p.colours.data(), p.cloud.numberOfPoints(),
                              0.02, 0.01);
  const std::size_t nv = b.positions.size() / 3;
  std::vector<double> far = b.positions;
  far[0] += 10; // vertex 0, far from every point
  const std::vector<float> none = dp::vertexColours(field, far.data(), nv, field.kernel());
  EXPECT_EQ(none[0], -1.0f);
  const std::vector<float> previous(3 * nv, 0.25f);
  const std::vector<float> kept =
      dp::vertexColours(field, far.data(), nv, field.kernel(), &previous);
  EXPECT_EQ(kept[0], 0.25f);
  EXPECT_NE(kept[3], 0.25f); // a vertex on the ball reads the frame's colour
  EXPECT_GE(kept[3], 0.0f);
  EXPECT_LE(kept[3], 1.0f);
}

// A ball spinning about its axis: its shape never changes, so the points' geometry cannot tell
// the tracker it turns; a colour pattern fixed to its material can.
double spinningBallError(double colourWeight, std::vector<std::uint8_t>* lastColours = nullptr)
{
  const Ball b = ball();
  const double diagonal = dp::boundingBoxDiagonal(b.positions);
  dp::TrackerOptions options;
  options.colourWeight = colourWeight;
  dp::Tracker tracker(dp::TriangleMesh(b.triangles, b.positions.size() / 3), b.positions, options);
  double worst = 0;
  for (std::size_t f = 0; f < 12; ++f)
  {
    const double angle = 0.06 * static_cast<double>(f);
    const ColouredPoints p = colouredBall(b, angle, 12000, f);
    const dp::FrameResult result =
        tracker.track(tracker.prepare(p.cloud.points.data(), p.cloud.numberOfPoints(),
                                      p.cloud.normals.data(), p.cloud.colors.data(), 3));
    worst = std::max(worst, vertexRms(result.positions, turned(b.positions, angle)) / diagonal);
    if (lastColours)
      *lastColours = result.colours;
  }
  return worst;
}

TEST(Tracker, FollowsASpinningBallByItsColour)
{
  // Without colour the mesh stays where the ball was (0.66 rad later its vertices are 0.2 of the
  // diagonal from their material); with it, each stays on its material point.
  const double withoutColour = spinningBallError(0);
  std::vector<std::uint8_t> colours;
  const double withColour = spinningBallError(50, &colours);
  EXPECT_GT(withoutColour, 0.1);
  EXPECT_LT(withColour, 0.01);
  EXPECT_EQ(colours.size(), ball().positions.size());
}

} // namespace
