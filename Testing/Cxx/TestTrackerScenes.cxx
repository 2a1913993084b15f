// SPDX-License-Identifier: BSD-3-Clause
// Scenes that defeat simpler trackers: a part the paper's energy loses, a frame that cannot be
// explained, a leg that passes another.
#include "dp/field/SurfaceReconstruction.h"
#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/SurfaceLocator.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/geometry/TriangleMesh.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/track/ClothEnergy.h"
#include "dp/track/Tracker.h"

#include "NumericChecks.h"

#include <gtest/gtest.h>
#include <memory>
#include <tbb/global_control.h>

#include "TrackingShapes.h"
#include <cmath>
#include <future>
#include <map>
#include <random>
#include <string>

namespace
{

using dp::test::expectGradientMatches;
using dp::test::jiggle;
using dp::test::makeSequence;
using dp::test::Sequence;
using dp::test::Shape;
using dp::test::tube;
using dp::test::tubeOptions;
using dp::test::vertexRms;

// Two tubes of radius 0.08 along z from 0 to 1, the second moved by (dx, dy): the legs of the
// scenes below, which say in positions() how the second one moves.
class TwoLegs : public dp::AnimatedMesh
{
public:
  TwoLegs(double dx, double dy, std::size_t frames) : Frames(frames)
  {
    dp::BendingTube::Options o;
    o.rings = 20;
    o.segments = 12;
    o.radius = 0.08;
    const dp::BendingTube tube(o);
    const std::vector<double> one = tube.positions(0);
    Rest = one;
    for (std::size_t i = 0; i < one.size(); i += 3)
      Rest.insert(Rest.end(), {one[i] + dx, one[i + 1] + dy, one[i + 2]});
    Triangles = tube.triangles();
    const auto offset = static_cast<std::int64_t>(one.size() / 3);
    for (std::int64_t t : tube.triangles())
      Triangles.push_back(t + offset);
  }
  std::size_t numberOfFrames() const override { return Frames; }
  std::size_t numberOfVertices() const override { return Rest.size() / 3; }
  const std::vector<std::int64_t>& triangles() const override { return Triangles; }

protected:
  // The rest pose with the second leg turned by `angle` about its base (x = `base`, z = 0) in
  // the x-z plane, away from the first.
  std::vector<double> secondTurned(double base, double angle) const
  {
    std::vector<double> x = Rest;
    for (std::size_t i = x.size() / 2; i < x.size(); i += 3)
    {
      const double u = Rest[i] - base, w = Rest[i + 2];
      x[i] = base + std::cos(angle) * u + std::sin(angle) * w;
      x[i + 2] = -std::sin(angle) * u + std::cos(angle) * w;
    }
    return x;
  }

  std::size_t Frames;
  std::vector<double> Rest;
  std::vector<std::int64_t> Triangles;
};

// Two legs: capped tubes side by side, one standing, the other swinging about its base away
// from it in the x-z plane, faster every frame (angle = rate t^2).
class SwingingLeg : public TwoLegs
{
public:
  SwingingLeg(double rate, std::size_t frames) : TwoLegs(Gap, 0.0, frames), Rate(rate) {}
  std::vector<double> positions(std::size_t frame) const override
  {
    return secondTurned(Gap, Rate * static_cast<double>(frame * frame));
  }

private:
  static constexpr double Gap = 0.22;
  double Rate;
};

// Two legs: one standing, the other swinging slowly about its base in the x-z plane, until at
// frame `jumpFrame` it is suddenly `jump` radians further on (a forearm raised within one
// frame's time), then swinging slowly again.
class JerkedLeg : public TwoLegs
{
public:
  JerkedLeg(double jump, std::size_t jumpFrame, std::size_t frames)
      : TwoLegs(Gap, 0.0, frames), Jump(jump), JumpFrame(jumpFrame)
  {
  }
  std::vector<double> positions(std::size_t frame) const override
  {
    return secondTurned(Gap, 0.03 * static_cast<double>(frame) + (frame >= JumpFrame ? Jump : 0.0));
  }

private:
  static constexpr double Gap = 0.22;
  double Jump;
  std::size_t JumpFrame;
};

// Two legs (tubes of radius 0.08) hanging from hips 0.5 apart, 2 cm apart sideways; the hind
// one stands, the front one swings back past it, its foot moving about `step` a frame: as a
// galloping horse's hoof passes another.
class PassingLegs : public TwoLegs
{
public:
  // The legs run along z from 0 (foot) to 1 (hip).
  PassingLegs(double step, std::size_t frames) : TwoLegs(HipApart, Side, frames), Step(step) {}
  std::vector<double> positions(std::size_t frame) const override
  {
    // The front leg turns about its hip (x = HipApart, z = 1), foot from ahead to behind.
    std::vector<double> x = Rest;
    turn(x, x.size() / 2, x.size(), HipApart, 0.25 - Step * static_cast<double>(frame));
    return x;
  }

private:
  void turn(std::vector<double>& x, std::size_t begin, std::size_t end, double hip,
            double angle) const
  {
    for (std::size_t i = begin; i < end; i += 3)
    {
      const double u = Rest[i] - hip, w = Rest[i + 2] - 1.0;
      x[i] = hip + std::cos(angle) * u - std::sin(angle) * w;
      x[i + 2] = 1.0 + std::sin(angle) * u + std::cos(angle) * w;
    }
  }
  static constexpr double HipApart = 0.5, Side = 0.18;
  double Step;
};

// The share of the true surface (area-uniform samples) farther than `limit` from the mesh.
double uncoveredShare(const dp::AnimatedMesh& truth, std::size_t frame,
                      const dp::TriangleMesh& mesh, const std::vector<double>& x, double limit)
{
  dp::SamplerOptions o;
  o.pointsPerFrame = 4000;
  o.seed = 77;
  const dp::PointCloud samples = dp::sampleSurface(truth.positions(frame), truth.triangles(), o, 0);
  const dp::SurfaceLocator locator(mesh, x.data());
  std::size_t far = 0;
  for (std::size_t i = 0; i < samples.numberOfPoints(); ++i)
    far += locator.closest(&samples.points[3 * i], limit).triangle < 0;
  return static_cast<double>(far) / static_cast<double>(samples.numberOfPoints());
}

TEST(Tracker, KeepsAPartThePapersEnergyLoses)
{
  // The paper's energy only measures mesh -> points: when a part moves away faster than its
  // width, its vertices settle on whatever data is near and the part is lost at no cost (here
  // 18% of the surface in the last frame). The points -> mesh term and the coarse level keep it.
  // By frame 9 the leg turns 0.68 rad a frame: its foot moves four leg widths.
  const SwingingLeg tubes(0.04, 10);
  const dp::TriangleMesh mesh(tubes.triangles(), tubes.numberOfVertices());
  dp::SamplerOptions sampling;
  sampling.pointsPerFrame = 8000;
  dp::TrackerOptions paper;
  paper.coverage.weight = 0;
  paper.graph.enabled = false;
  paper.recovery.enabled = false;
  double worst[2] = {0, 0};
  int run = 0;
  for (const dp::TrackerOptions& options : {paper, dp::TrackerOptions{}})
  {
    dp::Tracker tracker(mesh, tubes.positions(0), options);
    for (std::size_t f = 0; f < tubes.numberOfFrames(); ++f)
    {
      const dp::PointCloud c =
          dp::sampleSurface(tubes.positions(f), tubes.triangles(), sampling, f);
      const dp::FrameResult r = tracker.track(c.points.data(), c.numberOfPoints(), nullptr);
      worst[run] = std::max(worst[run],
                            uncoveredShare(tubes, f, mesh, r.positions, 3 * tracker.voxelSize()));
    }
    ++run;
  }
  EXPECT_GT(worst[0], 0.1) << "the paper's energy was expected to lose part of the leg";
  EXPECT_LT(worst[1], 0.01) << "the default tracker lost part of the surface";
}

TEST(Tracker, FlagsAFrameItCannotExplainAfterTryingAgain)
{
  // Frame 4 also holds a second object the template does not have (a ball of points beside the
  // legs): a fifth of the frame's data stays unexplained whatever the tracker does. It is tried
  // again from other starts and flagged; the legs are still followed, and the frames around it
  // are not flagged.
  const SwingingLeg legs(0.01, 8);
  const dp::TriangleMesh mesh(legs.triangles(), legs.numberOfVertices());
  dp::SamplerOptions sampling;
  sampling.pointsPerFrame = 8000;
  dp::Tracker tracker(mesh, legs.positions(0), dp::TrackerOptions{});
  for (std::size_t f = 0; f < legs.numberOfFrames(); ++f)
  {
    dp::PointCloud c = dp::sampleSurface(legs.positions(f), legs.triangles(), sampling, f);
    if (f == 4)
    {
      std::mt19937_64 rng(2);
      std::normal_distribution<double> n;
      for (int i = 0; i < 2000; ++i)
      {
        const double d[3] = {n(rng), n(rng), n(rng)};
        const double r = 0.2 / std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        c.points.insert(c.points.end(), {-0.6 + r * d[0], r * d[1], 0.5 + r * d[2]});
      }
    }
    const dp::FrameResult r = tracker.track(c.points.data(), c.numberOfPoints(), nullptr);
    EXPECT_EQ(r.failed, f == 4) << "frame " << f;
    if (f == 4)
    {
      EXPECT_EQ(r.retries, 2);
      EXPECT_GT(r.unexplained, 0.1);
    }
    EXPECT_LT(uncoveredShare(legs, f, mesh, r.positions, 3 * tracker.voxelSize()), 0.01)
        << "frame " << f;
  }
}

TEST(Tracker, KeepsALegThatPassesAnother)
{
  // The front foot passes the hind one, 2 cm apart, moving 0.2 a frame (more than a leg's width
  // of 0.16): with the paper's energy the passing foot lags onto the other leg's data; the default
  // tracker keeps both legs. (Before the coarse level continued each node's turn about its own
  // axis, not only its displacement, it lost the leg from 0.16 a frame: Documentation/
  // TrackingHistory.md, The coarse level's start.)
  const PassingLegs legs(0.2, 10);
  const dp::TriangleMesh mesh(legs.triangles(), legs.numberOfVertices());
  dp::SamplerOptions sampling;
  sampling.pointsPerFrame = 8000;
  dp::TrackerOptions paper;
  paper.coverage.weight = 0;
  paper.graph.enabled = false;
  paper.recovery.enabled = false;
  // The defaults (the coarse level's steps Anderson-accelerated: extrapolating from the start of
  // a stage carried the passing foot's vertices 2 cm toward the other leg), plain steps, and the
  // points -> mesh matches followed over the surface within a solve.
  dp::TrackerOptions plain;
  plain.graph.acceleration = 0;
  dp::TrackerOptions followed;
  followed.coverage.followMatches = true;
  double worstError[4] = {0, 0, 0, 0}, worstUncovered[4] = {0, 0, 0, 0};
  int run = 0;
  for (const dp::TrackerOptions& options : {paper, dp::TrackerOptions{}, plain, followed})
  {
    dp::Tracker tracker(mesh, legs.positions(0), options);
    for (std::size_t f = 0; f < legs.numberOfFrames(); ++f)
    {
      const dp::PointCloud c = dp::sampleSurface(legs.positions(f), legs.triangles(), sampling, f);
      const dp::FrameResult r = tracker.track(c.points.data(), c.numberOfPoints(), nullptr);
      const std::vector<double> truth = legs.positions(f);
      for (std::size_t i = 0; i < truth.size(); i += 3)
        worstError[run] = std::max(worstError[run], std::hypot(r.positions[i] - truth[i],
                                                               r.positions[i + 1] - truth[i + 1],
                                                               r.positions[i + 2] - truth[i + 2]));
      worstUncovered[run] = std::max(
          worstUncovered[run], uncoveredShare(legs, f, mesh, r.positions, 3 * tracker.voxelSize()));
    }
    ++run;
  }
  EXPECT_GT(worstUncovered[0], 0.03) << "the paper's energy was expected to lose the foot";
  for (int r = 1; r < 4; ++r)
  {
    EXPECT_LT(worstUncovered[r], 0.01) << "run " << r << " lost part of a leg";
    EXPECT_LT(worstError[r], 0.02) << "run " << r << ": a leg's vertices were carried off";
  }
}

// The samples of `cloud` whose normal faces `view` (a single sensor's side), with their normals.
dp::PointCloud seenFrom(const dp::PointCloud& cloud, const double view[3])
{
  dp::PointCloud seen;
  for (std::size_t i = 0; i < cloud.numberOfPoints(); ++i)
  {
    const float* n = &cloud.normals[3 * i];
    if (n[0] * view[0] + n[1] * view[1] + n[2] * view[2] > 0.2)
    {
      seen.points.insert(seen.points.end(), &cloud.points[3 * i], &cloud.points[3 * i] + 3);
      seen.normals.insert(seen.normals.end(), n, n + 3);
    }
  }
  return seen;
}

TEST(Tracker, KeepsTheUnseenSideOfABodySeenFromOneSide)
{
  // A bending tube seen from one side only, as by a single depth sensor: each vertex is pulled to
  // its nearest point only where no other part of the mesh is nearer to that point, so the
  // unseen side, whose nearest points are the seen side's (its rims), is not pulled onto them;
  // it follows the seen side. Without that test it is drawn in toward the seen side's rims.
  dp::BendingTube::Options o;
  o.frames = 30;
  o.rings = 24;
  o.segments = 16;
  o.radius = 0.15;
  const dp::BendingTube tube(o);
  const dp::TriangleMesh mesh(tube.triangles(), tube.numberOfVertices());
  dp::SamplerOptions sampling;
  sampling.pointsPerFrame = 12000;
  const double view[3] = {0, 1, 0};
  dp::TrackerOptions oneSided;
  oneSided.distance.reciprocal = false;
  double unseenRms[2] = {0, 0};
  int run = 0;
  for (const dp::TrackerOptions& options : {oneSided, dp::TrackerOptions{}})
  {
    dp::Tracker tracker(mesh, tube.positions(0), options);
    double sum = 0;
    std::size_t count = 0;
    for (std::size_t f = 0; f < 10; ++f)
    {
      const dp::PointCloud c =
          seenFrom(dp::sampleSurface(tube.positions(f), tube.triangles(), sampling, f), view);
      const dp::FrameResult r =
          tracker.track(c.points.data(), c.numberOfPoints(), c.normals.data());
      // The unseen side's vertices against the true surface (a tube's twist slides vertices
      // along it unseen, from any side).
      const std::vector<double> truth = tube.positions(f);
      const dp::SurfaceLocator trueSurface(mesh, truth.data());
      std::vector<double> normals(truth.size());
      mesh.vertexNormals(truth.data(), normals.data());
      for (std::size_t i = 0; i < truth.size(); i += 3)
        if (normals[i] * view[0] + normals[i + 1] * view[1] + normals[i + 2] * view[2] < -0.2)
        {
          sum += trueSurface.closest(&r.positions[i]).squaredDistance;
          ++count;
        }
    }
    unseenRms[run++] = std::sqrt(sum / static_cast<double>(count));
  }
  // Measured: 4.8 cm off the true surface without the test, 1.2 cm with it (radius 15 cm).
  EXPECT_GT(unseenRms[0], 0.03) << "without the test the unseen side was expected to collapse";
  EXPECT_LT(unseenRms[1], 0.5 * unseenRms[0]);
  EXPECT_LT(unseenRms[1], 0.016) << "the unseen side left the body";
}

TEST(Tracker, ALegJerkedFarInOneFrameIsFoundAgainAndFlaggedWhileLost)
{
  // A leg (radius 0.08, length 1) turned suddenly about its base within one frame. By 1.2 rad
  // (its foot 0.9 m away, eleven leg widths) it is followed at once. By 1.6 and 2.0 rad it is
  // beyond the coarse level's reach: the retry that moves the lost part onto the points it left
  // (PartRegrowth) finds it within that frame or the next. By 2.5 rad (the foot beside the base)
  // it stays lost. Whatever happens, every frame that leaves the leg's surface uncovered is
  // flagged: a lost limb is never reported as fine.
  const std::size_t jerkFrame = 4;
  for (double jump : {0.4, 1.2, 1.6, 2.0, 2.5})
  {
    const JerkedLeg legs(jump, jerkFrame, 8);
    const dp::TriangleMesh mesh(legs.triangles(), legs.numberOfVertices());
    dp::SamplerOptions sampling;
    sampling.pointsPerFrame = 8000;
    dp::Tracker tracker(mesh, legs.positions(0), dp::TrackerOptions{});
    for (std::size_t f = 0; f < legs.numberOfFrames(); ++f)
    {
      const dp::PointCloud c = dp::sampleSurface(legs.positions(f), legs.triangles(), sampling, f);
      const dp::FrameResult r = tracker.track(c.points.data(), c.numberOfPoints(), nullptr);
      const double uncovered = uncoveredShare(legs, f, mesh, r.positions, 3 * tracker.voxelSize());
      const bool lost = uncovered > 0.01;
      EXPECT_EQ(r.failed, lost) << "jump " << jump << ", frame " << f << ": " << uncovered
                                << " of the surface uncovered";
      const bool foundBy = jump < 1.5 || f > jerkFrame;
      if (jump < 2.2 && foundBy)
      {
        EXPECT_FALSE(lost) << "jump " << jump << ", frame " << f << ": " << uncovered;
      }
    }
  }
}

} // namespace
