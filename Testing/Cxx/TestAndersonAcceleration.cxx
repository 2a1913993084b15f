// SPDX-License-Identifier: BSD-3-Clause
// AndersonAcceleration.

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/LocalThickness.h"
#include "dp/geometry/SurfaceLocator.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/track/AndersonAcceleration.h"
#include "dp/track/ClothEnergy.h"
#include "dp/track/CoverageTerm.h"
#include "dp/track/DeformationGraph.h"
#include "dp/track/DistanceTerm.h"
#include "dp/track/FrameData.h"
#include "dp/track/FrameQuality.h"
#include "dp/track/GraphRegistration.h"
#include "dp/track/InternalEnergyTerm.h"
#include "dp/track/Solvers.h"
#include "dp/track/TemporalTerm.h"
#include "dp/track/TracePreconditioner.h"
#include "dp/track/Tracker.h"

#include "NumericChecks.h"
#include "TrackingShapes.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <random>
#include <utility>

namespace
{

using dp::test::expectGradientMatches;
using dp::test::Frame;
using dp::test::jiggle;
using dp::test::Shape;
using dp::test::tube;

TEST(AndersonAcceleration, SolvesALinearContractionInAFewSteps)
{
  // u <- A u + b with A's eigenvalues 0.95 ... 0.3 (slow, as the coarse level's sliding is):
  // after 8 plain steps most of the error is left; accelerated steps combining 4 earlier ones
  // (the dimension: GMRES on u = A u + b) leave none.
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Matrix4d random;
  for (int i = 0; i < 16; ++i)
    random(i / 4, i % 4) = u(rng);
  const Eigen::Matrix4d q = Eigen::HouseholderQR<Eigen::Matrix4d>(random).householderQ();
  const Eigen::Matrix4d a = q * Eigen::Vector4d(0.95, 0.9, 0.6, 0.3).asDiagonal() * q.transpose();
  const Eigen::Vector4d b(u(rng), u(rng), u(rng), u(rng));
  const Eigen::Vector4d fixed = (Eigen::Matrix4d::Identity() - a).inverse() * b;
  const double start = fixed.norm();
  Eigen::VectorXd plain = Eigen::Vector4d::Zero(), accelerated = plain;
  dp::AndersonAcceleration anderson(4);
  int combined = 0;
  for (int step = 0; step < 8; ++step)
  {
    plain = a * plain + b;
    const Eigen::VectorXd image = a * accelerated + b;
    Eigen::VectorXd next;
    const bool combines = anderson.next(accelerated, image, next);
    combined += combines;
    accelerated = combines ? next : image;
  }
  EXPECT_EQ(combined, 7); // every step but the first
  EXPECT_GT((plain - fixed).norm(), 0.3 * start);
  EXPECT_LT((accelerated - fixed).norm(), 1e-9 * start);
}

TEST(AndersonAcceleration, CombinesOnlyOnceItHasAnEarlierStepAndForgetsOnReset)
{
  EXPECT_THROW(dp::AndersonAcceleration(0), std::invalid_argument);
  dp::AndersonAcceleration anderson(2);
  Eigen::VectorXd next;
  const Eigen::Vector2d u(1, 2), g(0.5, 1);
  EXPECT_FALSE(anderson.next(u, g, next));
  EXPECT_EQ(next.size(), 0);
  // u -> u / 2 in 2-D from a second point: the fixed point 0 at once.
  EXPECT_TRUE(anderson.next(g, 0.5 * g, next));
  EXPECT_LT(next.norm(), 1e-12);
  anderson.reset();
  EXPECT_FALSE(anderson.next(u, g, next));
}

} // namespace
