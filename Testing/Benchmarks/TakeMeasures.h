// SPDX-License-Identifier: BSD-3-Clause
// BenchmarkTracker's figures of a run (a take tracked with one template under one condition):
// its sums over the frames and the figures they make, and a frame's error against its truth.
#pragma once

#include "TrackingTruth.h"

#include "dp/geometry/MeshDistortion.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/track/Tracker.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <vector>

namespace dp::bench
{

/** A run's figures, over its frames. */
struct Run
{
  dp::FrameTimings time; // summed over the frames
  std::size_t retried = 0, flagged = 0;
  // Against the truth: frames that lost a part (their true surface left uncovered beyond a
  // share), flags on frames that did not (false), frames that did without a flag (missed).
  std::size_t lost = 0, falseFlags = 0, missed = 0;
  // The same where a part counts as lost only on the true surface the data see (rigs): what
  // the data could tell.
  std::size_t lostSeen = 0, falseSeen = 0, missedSeen = 0;
  // The kept attempts' dependent steps, summed: deterministic, unlike the times.
  std::size_t coarseSteps = 0, fineSteps = 0;
  double vertexRms = 0, normalRms = 0, largestVertexError = 0, surfaceRms = 0;
  // --colour: RMS over vertices and frames of the colour a vertex carries (the frame's colour at
  // it) against its material point's true colour, 0-255; and the same at the true positions.
  // The same for the colours as the .dpz stores them (held within --colour-tolerance).
  double colourSwim = -1, truthColourSwim = -1, storedColourSwim = -1;
  double uncoveredMean = 0, uncoveredWorst = 0, jitter = 0, msPerFrame = 0;
  std::size_t worstFrame = 0, frames = 0;
  // Over the vertices the data see (FrameFigures::seenVertices): their RMS error and share.
  double seenRms = 0, seenShare = 0;
  // The worst frame's shares of folded, stretched and torn edges; frames with a torn edge.
  double foldedWorst = 0, stretchedWorst = 0, tornWorst = 0;
  std::size_t tornFrames = 0;
};

// A run's sums over its frames, turned into its figures once the last frame is in.
class RunSums
{
public:
  void add(std::size_t frame, const dp::FrameResult& r, const std::vector<double>& positions,
           const FrameFigures& figures, const std::vector<double>& truth, double cycleSeconds,
           double lostShare = 0.01)
  {
    // Lost: uncovered beyond the first frame's share (what the template itself lacks, as an open
    // template from one view, is not the tracking's loss).
    if (R.frames == 0)
    {
      FirstUncovered = figures.uncovered;
      FirstUncoveredSeen = figures.uncoveredSeen;
    }
    const bool lost = figures.uncovered - FirstUncovered > lostShare;
    R.lost += lost;
    R.falseFlags += r.failed && !lost;
    R.missed += lost && !r.failed;
    const bool lostSeen = figures.uncoveredSeen - FirstUncoveredSeen > lostShare;
    R.lostSeen += lostSeen;
    R.falseSeen += r.failed && !lostSeen;
    R.missedSeen += lostSeen && !r.failed;
    Seconds += cycleSeconds;
    R.time.data += r.timings.data;
    R.time.prediction += r.timings.prediction;
    R.time.coarse += r.timings.coarse;
    R.time.fine += r.timings.fine;
    R.time.quality += r.timings.quality;
    R.retried += r.retries > 0;
    R.coarseSteps += static_cast<std::size_t>(r.coarseIterations);
    R.fineSteps += static_cast<std::size_t>(r.iterations);
    R.flagged += r.failed;
    JitterSums.add(positions, truth);
    VertexSum += figures.vertexSquaredSum;
    NormalSum += figures.normalSquaredSum;
    SurfaceSum += figures.surfaceSquaredSum;
    UncoveredSum += figures.uncovered;
    SeenSum += figures.seenSquaredSum;
    SeenCount += static_cast<double>(figures.seenVertices);
    R.foldedWorst = std::max(R.foldedWorst, figures.folded);
    R.stretchedWorst = std::max(R.stretchedWorst, figures.stretched);
    R.tornWorst = std::max(R.tornWorst, figures.torn);
    R.tornFrames += figures.torn > 0;
    R.largestVertexError = std::max(R.largestVertexError, figures.largestVertexError);
    if (figures.uncovered > R.uncoveredWorst || R.frames == 0)
    {
      R.uncoveredWorst = figures.uncovered;
      R.worstFrame = frame;
    }
    ++R.frames;
  }

  Run finish(std::size_t vertices) const
  {
    Run run = R;
    const double tracked = static_cast<double>(run.frames);
    const double samples = tracked * static_cast<double>(vertices);
    run.vertexRms = std::sqrt(VertexSum / samples);
    run.normalRms = std::sqrt(NormalSum / samples);
    run.surfaceRms = std::sqrt(SurfaceSum / samples);
    run.uncoveredMean = UncoveredSum / tracked;
    run.seenRms = SeenCount > 0 ? std::sqrt(SeenSum / SeenCount) : 0.0;
    run.seenShare = SeenCount / samples;
    run.jitter = JitterSums.ratio();
    run.msPerFrame = 1e3 * Seconds / tracked;
    return run;
  }

private:
  Run R;
  Jitter JitterSums;
  double VertexSum = 0, NormalSum = 0, SurfaceSum = 0, UncoveredSum = 0, Seconds = 0;
  double SeenSum = 0, SeenCount = 0;
  double FirstUncovered = 0, FirstUncoveredSeen = 0;
};

// The RMS distance (mm) of positions y to the true ones; -1 for none (an attempt not made).
inline double rmsAgainst(const std::vector<double>& y, const std::vector<double>& truth)
{
  double e = 0;
  for (std::size_t i = 0; i < y.size(); ++i)
    e += (y[i] - truth[i]) * (y[i] - truth[i]);
  return y.empty() ? -1.0 : 1e3 * std::sqrt(e / static_cast<double>(truth.size() / 3));
}

// The error (mm, RMS) left once the best rigid motion is taken out (Kabsch): local, not global,
// error.
inline double rigidFreeRms(const std::vector<double>& y, const std::vector<double>& truth)
{
  const std::size_t n = y.size() / 3;
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
  for (std::size_t v = 0; v < n; ++v)
  {
    a += Eigen::Vector3d(&y[3 * v]);
    b += Eigen::Vector3d(&truth[3 * v]);
  }
  a /= static_cast<double>(n);
  b /= static_cast<double>(n);
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (std::size_t v = 0; v < n; ++v)
    C += (Eigen::Vector3d(&truth[3 * v]) - b) * (Eigen::Vector3d(&y[3 * v]) - a).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(C, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  const Eigen::Matrix3d R = svd.matrixU() * D * svd.matrixV().transpose();
  double e = 0;
  for (std::size_t v = 0; v < n; ++v)
    e += (R * (Eigen::Vector3d(&y[3 * v]) - a) + b - Eigen::Vector3d(&truth[3 * v])).squaredNorm();
  return 1e3 * std::sqrt(e / static_cast<double>(n));
}

// How far a per-frame input mesh lies from the true surface of its frame: D1's mean squared
// error (both directions, the worse kept), what no tracking of that mesh can undo.
inline double inputMeshError(const dp::AnimatedMesh& mesh, std::size_t f,
                             const dp::PointCloud& input)
{
  const std::vector<double> truth = mesh.positions(f);
  dp::MeshSurface surface;
  surface.positions = truth.data();
  surface.vertices = truth.size() / 3;
  surface.triangles = mesh.triangles().data();
  surface.triangleCount = mesh.triangles().size() / 3;
  const std::vector<std::int64_t> triangles = dp::triangleFans(input);
  return dp::meshDistortion(surface, dp::meshSurfaceOf(input, triangles), 20000).d1;
}

} // namespace dp::bench
