// SPDX-License-Identifier: BSD-3-Clause
// MotionPredictor: a constant velocity is continued exactly, a quadratic trajectory by the
// quadratic extrapolation, the search keeps the lowest energy of its candidates (the last shape
// when nothing lower), and the graph's states continue a constant turn and a constant
// translation; without states (or after a frame without one) it predicts none.
#include "TrackingShapes.h"

#include "dp/track/DeformationGraph.h"
#include "dp/track/MotionPredictor.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <vector>

namespace
{

// x(t) = a + b t + c t^2, coordinate by coordinate, with a, b, c fixed per coordinate.
std::vector<double> trajectory(double t, std::size_t values, double curvature)
{
  std::vector<double> x(values);
  for (std::size_t i = 0; i < values; ++i)
  {
    const double a = std::sin(1.0 + i), b = 0.1 * std::cos(3.0 * i),
                 c = curvature * std::sin(5.0 * i);
    x[i] = a + b * t + c * t * t;
  }
  return x;
}

double squaredDistance(const double* x, const std::vector<double>& y)
{
  double d = 0;
  for (std::size_t i = 0; i < y.size(); ++i)
    d += (x[i] - y[i]) * (x[i] - y[i]);
  return d;
}

void expectNear(const std::vector<double>& a, const std::vector<double>& b, double tolerance)
{
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    ASSERT_NEAR(a[i], b[i], tolerance) << "value " << i;
}

TEST(MotionPredictor, AConstantVelocityIsContinuedExactly)
{
  dp::MotionPredictor p;
  EXPECT_TRUE(p.empty());
  p.push(trajectory(0, 30, 0));
  // One frame: no motion known, the last shape.
  EXPECT_EQ(p.constantVelocity(), trajectory(0, 30, 0));
  for (int t = 1; t <= 5; ++t)
  {
    p.push(trajectory(t, 30, 0));
    expectNear(p.constantVelocity(), trajectory(t + 1, 30, 0), 1e-12);
  }
  EXPECT_EQ(p.depth(), 3u); // the last three only
  EXPECT_EQ(p.last(), trajectory(5, 30, 0));
  // Restarting forgets the motion.
  p.restartFrom(trajectory(9, 30, 0));
  EXPECT_EQ(p.depth(), 1u);
  EXPECT_EQ(p.constantVelocity(), trajectory(9, 30, 0));
  p.clear();
  EXPECT_TRUE(p.empty());
}

TEST(MotionPredictor, TheSearchKeepsTheLowestOfItsExtrapolations)
{
  // Three frames of a quadratic trajectory: its quadratic extrapolation (3 x2 - 3 x1 + x0) is the
  // next frame exactly, so an energy whose minimum is there picks it; an energy whose minimum is
  // a quarter of the linear step picks that candidate; one whose minimum is the last shape keeps
  // it.
  dp::MotionPredictor p;
  for (int t = 0; t < 3; ++t)
    p.push(trajectory(t, 24, 0.05));
  const std::vector<double> next = trajectory(3, 24, 0.05);
  int evaluations = 0;
  const std::vector<double> best = p.searchExtrapolations(
      [&](const double* x)
      {
        ++evaluations;
        return squaredDistance(x, next);
      });
  expectNear(best, next, 1e-12);
  EXPECT_EQ(evaluations, 1 + 2 * 6); // the last shape, then six steps along each extrapolation

  const std::vector<double> last = p.last(), linear = p.constantVelocity();
  std::vector<double> quarter(last.size());
  for (std::size_t i = 0; i < last.size(); ++i)
    quarter[i] = last[i] + 0.25 * (linear[i] - last[i]);
  expectNear(p.searchExtrapolations([&](const double* x) { return squaredDistance(x, quarter); }),
             quarter, 1e-12);
  EXPECT_EQ(p.searchExtrapolations([&](const double* x) { return squaredDistance(x, last); }),
            last);

  // With one frame there is nothing to extrapolate: the last shape, one evaluation.
  dp::MotionPredictor single;
  single.push(last);
  evaluations = 0;
  EXPECT_EQ(single.searchExtrapolations(
                [&](const double* x)
                {
                  ++evaluations;
                  return squaredDistance(x, next);
                }),
            last);
  EXPECT_EQ(evaluations, 1);
}

// The state of every node turned by `angle` about z and moved by `t`.
dp::DeformationGraph::State stateOf(const dp::DeformationGraph& graph, double angle,
                                    const Eigen::Vector3d& t)
{
  dp::DeformationGraph::State s;
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
  {
    s.rotation.push_back(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix());
    s.translation.push_back(t);
  }
  return s;
}

TEST(MotionPredictor, TheGraphsStatesContinueTheirTurnAndTheirMotion)
{
  const dp::test::Shape shape = dp::test::tube();
  const dp::TriangleMesh mesh(shape.triangles, shape.positions.size() / 3);
  const dp::DeformationGraph graph(mesh, shape.positions.data(), 12, 4);
  dp::MotionPredictor p;
  dp::DeformationGraph::State out;
  p.push(shape.positions);
  EXPECT_FALSE(p.predictState(graph, 1.0, out));
  EXPECT_EQ(p.lastState(), nullptr);

  const Eigen::Vector3d t0(0.1, 0, 0), t1(0.1, 0.05, 0);
  const dp::DeformationGraph::State s0 = stateOf(graph, 0.1, t0), s1 = stateOf(graph, 0.25, t1);
  p.push(shape.positions, &s0);
  EXPECT_FALSE(p.hasMotion());
  ASSERT_TRUE(p.predictState(graph, 1.0, out)); // one state: the last
  EXPECT_TRUE(out.rotation[0].isApprox(s0.rotation[0], 1e-15));
  p.push(shape.positions, &s1);
  ASSERT_TRUE(p.hasMotion());
  ASSERT_NE(p.lastState(), nullptr);
  EXPECT_TRUE(p.lastState()->translation[0].isApprox(t1));

  // A constant turn of 0.15 about z goes on to 0.4; the displacement (0, 0.05, 0) goes on, turned
  // by the step (Turning) or not (Straight); half a step goes on by half.
  const Eigen::Matrix3d step = Eigen::AngleAxisd(0.15, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d half =
      Eigen::AngleAxisd(0.075, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d turned =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  ASSERT_TRUE(p.predictState(graph, 1.0, out));
  for (std::size_t j = 0; j < graph.numberOfNodes(); ++j)
  {
    EXPECT_TRUE(out.rotation[j].isApprox(turned, 1e-12)) << "node " << j;
    EXPECT_TRUE(out.translation[j].isApprox(t1 + step * (t1 - t0), 1e-12)) << "node " << j;
  }
  ASSERT_TRUE(p.predictState(graph, 1.0, out, dp::Extrapolation::Straight));
  EXPECT_TRUE(out.translation[3].isApprox(t1 + (t1 - t0), 1e-12));
  ASSERT_TRUE(p.predictState(graph, 0.5, out));
  EXPECT_TRUE(out.rotation[3].isApprox(half * s1.rotation[3], 1e-12));
  EXPECT_TRUE(out.translation[3].isApprox(t1 + 0.5 * (half * (t1 - t0)), 1e-12));

  // Only the last two states count; a frame recorded without one forgets them.
  const dp::DeformationGraph::State s2 = stateOf(graph, 0.25, t1);
  p.push(shape.positions, &s2);
  ASSERT_TRUE(p.predictState(graph, 1.0, out));
  EXPECT_TRUE(out.rotation[0].isApprox(s1.rotation[0], 1e-12)); // no turn between s1 and s2
  EXPECT_TRUE(out.translation[0].isApprox(t1, 1e-12));
  p.push(shape.positions);
  EXPECT_FALSE(p.hasMotion());
  EXPECT_FALSE(p.predictState(graph, 1.0, out));
}

} // namespace
