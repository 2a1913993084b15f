// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file TrackerOptions.h
 * @brief The settings of the tracker (dp::Tracker) and of its parts: the paper's energy and
 *        solvers, and what goes beyond it (the points -> mesh term, the deformation graph's
 *        coarse level, the temporal term, failure detection and recovery). Plain values; every
 *        default is the product's default. Their names, ranges and documentation are in
 *        TrackerOptionTable (one row each), from which the validation, the filter, the command
 *        line and the documentation are derived.
 */
#pragma once

#include "dp/track/ClothEnergy.h"

#include <cstddef>

namespace dp
{

/** What D_i of the distance energy measures. */
enum class DistanceMeasure
{
  Points, // the distance to the nearest data point (the paper)
  Planes  // the distance to the tangent planes of the nearest data points: no pull toward
          // individual samples, so the mesh can slide along the data
};

enum class TrackerSolver
{
  GaussNewton,
  LBFGS,
  SteepestDescent
};

/** The mesh -> points term (the paper's E_dis; DistanceTerm). `squared`: each vertex's term is
 *  D_i^2 / (2 voxel), smooth at the data, so vertices do not stick where they first touch it. */
struct DistanceTermOptions
{
  double weight = 50.0; // k_dis
  DistanceMeasure measure = DistanceMeasure::Planes;
  bool squared = true;             // P(D) = D^2 / (2 voxel); false: the paper's D
  double normalTestDegrees = 90.0; // >= 180: no normal test
  double outlierDistance = 0.0;    // world units; 0: no cut-off
  double robustScale = 0.0;        // Geman-McClure scale (world units); 0: plain least squares
  // A vertex is pulled to its nearest point only where no other part of the mesh is nearer to
  // that point by more than two voxels: data seen from one side (a single sensor, a hole) do
  // not pull the unseen side onto them.
  bool reciprocal = true;
};

/** The points -> mesh term (CoverageTerm). */
struct CoverageOptions
{
  double weight = 50.0;            // k_cov; 0 switches the term off
  double pointToPoint = 0.1;       // mu: share of the point-to-point distance
  double normalTestDegrees = 60.0; // >= 180: no normal test
  double robustScale = 0.0;        // Geman-McClure scale (world units); 0: plain least squares
  double maxDistance = 0.0;        // world units; 0: no cut-off
  std::size_t points = 0;          // size of the well-spread subsample; 0: 4 per vertex
  // Within a solve, each point's closest point follows the surface from its last triangle
  // (SurfaceLocator::follow) instead of being searched over the whole surface again, where it
  // stays within a voxel; the tracker still searches everything where a coarse stage and the
  // fine level start (CoverageTerm). Off by default: 1.2-1.3x faster a frame, but over three
  // seeds jumping's vertex RMS was 2.8 % higher (Documentation/TrackingHistory.md).
  bool followMatches = false;
};

/** The coarse level: an embedded deformation graph (DeformationGraph, GraphRegistration). */
struct GraphOptions
{
  bool enabled = true;
  std::size_t nodes = 0;      // 0: one per 5 template vertices, at least 30, at most 600
  std::size_t influences = 4; // nodes blended per vertex
  double rigidity = 1.0;      // multiplies the schedule's regularisation weights k_reg
  // Scale of the regulariser's robust (Huber) penalty, in voxels: edges bending more than this
  // cost in proportion to their bending (an L1 penalty: joints bend, the rest stays rigid).
  double robustScale = 0.5;
  // Plasticity: after each frame, where an edge of the graph is bent more than yieldLimit voxels
  // from what the regulariser measures against, that reference gives way by yieldRate of the
  // excess, so lasting deformation (a collapse, clothes) is not pulled back to the template while
  // parts that stay near-rigid keep the template's shape (0 switches it off).
  double yieldRate = 0.3;
  double yieldLimit = 1.0;
  // Weight of the stretch term (edge lengths beyond a free 10 %, least squares) against the
  // bending term's: limbs bend but do not stretch. 0 switches it off.
  double stretchWeight = 1.0;
  int iterations = 10; // Levenberg-Marquardt steps per stage of the schedule (at most)
  // Gauss-Newton steps of the fine level after this level (at most; TrackerOptions::
  // maxIterations bounds the other solvers, and Gauss-Newton without the graph). The graph has
  // placed the surface and a few steps fit its detail; solved to convergence, the fine level
  // lets vertices slide along the data, where no term holds them, and the tracked vertices end
  // farther from the true ones (Documentation/TrackingHistory.md).
  int fineIterations = 3;
  // Anderson acceleration of the Levenberg-Marquardt steps (AndersonAcceleration): the number of
  // earlier steps combined (0: plain steps, stages end on the energy's gain), once steps move no
  // vertex two voxels; an accelerated state moves no vertex more than a voxel beyond the plain
  // step, and a stage also ends once a step moves no vertex a tenth of a voxel. 1.05-1.2x faster
  // where frames are not retried, and over three seeds as accurate as plain steps or more
  // (Documentation/TrackingHistory.md).
  int acceleration = 3;
};

/** Failure detection and recovery (FrameQuality): a frame fails when the share of its data
 *  farther than `reach` voxels from the mesh (unexplained) exceeds what is usual in the take (the
 *  median of the last frames kept) by more than `margin`; it is then tried again from other
 *  starts and the best attempt is kept. Relative, so data the template lacks do not count as
 *  failures, while a lost limb (a few % of the surface) does. So does mesh the solve took off its
 *  data (departed) by more than usual, and a torn limb (see stiffRetry). Mesh without data
 *  (unsupported) beyond the usual is tried again from the other starts too (a limb left behind
 *  looks so) but flags nothing: holes in the data look the same. */
struct RecoveryOptions
{
  bool enabled = true;
  double reach = 3.0;
  double margin = 0.003;
  // A frame with a torn limb (a stiff edge grown beyond its template length by more than two
  // mean edge lengths: caught by another limb's data) fails, is first tried again with the
  // coarse level's limbs held stiffer, and keeps an attempt without the tear that explains the
  // data about as well. Off: tears are neither failures nor retried stiffer.
  bool stiffRetry = true;
  // A frame that lost a part is also tried from its best attempt with the lost part moved
  // rigidly onto the points it left (PartRegrowth: a limb moved beyond the coarse level's reach).
  bool regrow = true;
  double tearGrowth = 2.0; // mean edge lengths a stiff edge may grow before its limb counts torn
  // The stiff retry's coarse level: its rigidity times `stiffening`, its stretch weight times
  // the square.
  double stiffening = 2.0;
  // A retry replaces the best attempt only with a score below this share of the best's (and
  // half a margin below it): two plausible fits differ by noise, and a start from elsewhere
  // breaks the motion's continuity.
  double retryShare = 0.7;
  std::size_t window = 9;     // the last frames kept whose median is the take's usual quality
  int persistentFailures = 3; // frames in doubt in a row after which they are the usual
};

/** Softer cloth where the shape is thick (LocalThickness): a trunk has data all round it and
 *  its skin stretches and slides, while a limb lies close to other limbs' data and must keep
 *  its shape. A vertex whose medial radius, over the template's 90th percentile, is below
 *  `from` keeps the cloth's stiffness; above `to` its edges' stretch stiffness is multiplied by
 *  `stretch` and its hinges' bending stiffness by `bend`; in between it blends smoothly.
 *  Measured with the creases' softening (Documentation/TrackingHistory.md; seed 1, stretch
 *  1 -> 0.3): the captured human 18.2 / 18.3 / 30.9 / 28.8 -> 16.8 / 16.1 / 26.6 / 27.6 mm
 *  (decimated clean / noisy, reconstructed clean / noisy), the galloping horse better on three
 *  rows and worse reconstructed/clean (17.5 -> 19.5 mm, a leg drawn toward another over three
 *  frames; 17.1 mm since a torn limb counts as a failed frame, RecoveryOptions::stiffRetry), the
 *  melting horse (far from isometric) up to 10 mm worse: for slow non-rigid motion set
 *  stretch 1. Only vertices whose inner ball meets the surface's other side count as thick: a
 *  sheet, or a template open there, keeps its stiffness.
 *  stretch = bend = 1 switches it off. */
struct ThicknessSoftening
{
  double stretch = 0.3;
  double bend = 1.0;
  double from = 0.4;
  double to = 0.7;
};

/** Softer stretch in the template's creases: where the ball that touches the surface from
 *  outside (LocalThickness, outer medial radius) is smaller than `width` times the template's
 *  thickness (the 90th percentile of the inner radii), the edges' stretch stiffness is
 *  multiplied by `stretch`. A creased template joins what the motion parts (arms that touch the
 *  body at frame 0, reconstructed as one surface; armpits, crotch, neck): stiff, those bridges
 *  drag the torso's skin along with the arm. Measured (Documentation/TrackingHistory.md): the
 *  reconstructed human 34.2 -> 28.8 mm, the galloping horse better too, nothing lost.
 *  stretch = 1 switches it off. */
struct CreaseSoftening
{
  double stretch = 0.1;
  double width = 0.7;
};

struct TrackerOptions
{
  ClothParameters cloth;
  ThicknessSoftening softening;
  CreaseSoftening creases;
  DistanceTermOptions distance;
  double voxelSize = 0.0; // world units; 0: template diagonal / 200
  double bandWidth = 0.0; // world units; 0: 4 voxels
  // A frame of more points is thinned evenly to this many (FrameData): the field resolves
  // nothing finer than a voxel, and a 10-million-point frame would otherwise take minutes and
  // gigabytes. 0: no limit.
  std::size_t maxFramePoints = 200000;
  // A frame that is a mesh (Tracker::prepare(MeshSurface)) is read as its surface: this many
  // points spread evenly over its area, with its faces' normals (sampleMeshSurface), or as many
  // as it has vertices when that is more; 0: its vertices as points.
  std::size_t meshFrameSamples = 20000;
  TrackerSolver solver = TrackerSolver::GaussNewton;
  // Rest state of E_int for frame t: (1 - restUpdate) * template + restUpdate * frame t-1.
  // 0 is the paper (the template); a share of the last frame lets the rest state follow shapes
  // that stray far from the template (a collapse), so that E_int stops pulling them back.
  double restUpdate = 0.3;
  bool motionPrediction = true;
  // Before the deformable solve, move the predicted mesh rigidly onto the data (point-to-plane
  // ICP weighted by vertex mass): the cloth energy holds a rigid motion only weakly along the
  // surface, so without it a turning shape slips tangentially a little more each frame.
  bool rigidAlignment = true;
  bool provisionalDetermination = true; // steepest descent only
  int maxIterations = 300;
  double tolerance = 1e-3; // relative energy decrease that ends a solve

  CoverageOptions coverage;
  GraphOptions graph;
  // k_acc of the temporal term (TemporalTerm): pulls each vertex toward the constant-velocity
  // extrapolation of its last two positions; 0 switches it off.
  double temporalWeight = 0.0;
  // k_col of the colour term (ColourTerm) where the points carry colour: each vertex pulled,
  // along the surface, to where the frame shows its material point's colour of the first frame
  // (in the coarse and fine levels); 0 switches it off.
  double colourWeight = 50.0;
  // The colour term's kernel on the coarse level, in times the fine one (ColourField::kernel): it
  // reaches farther, as the coarse level's data terms do.
  double colourCoarseKernel = 3.0;
  RecoveryOptions recovery;
};

} // namespace dp
