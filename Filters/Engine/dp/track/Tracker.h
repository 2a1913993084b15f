// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file Tracker.h
 * @brief Deforms one template mesh through a sequence of point clouds, frame by frame, by
 *        minimising E = E_int + E_dis (Shinya, Shioya & Shiraishi, "Unification of Dynamic
 *        Point Data", eq. 1) and, beyond the paper, terms that keep it on real captures:
 *
 *   E_int  the cloth energy (ClothEnergy: stretch, shear, bend; rest state = the template, or a
 *          blend with the last frame, restUpdate), softer in stretch in the template's creases
 *          (CreaseSoftening) and on its thick parts (ThicknessSoftening);
 *   E_dis  mesh -> points, read from the frame's distance field (DistanceTerm; the paper's term,
 *          with the normal test and an outlier cut-off; distance to the data's tangent planes
 *          and a squared penalty by default);
 *   E_cov  points -> mesh (CoverageTerm): a well-spread subsample of the data pulls the closest
 *          point of the mesh surface, robustly and only where normals agree, so that a part of
 *          the mesh cannot let go of its data at no cost (the paper's term alone loses limbs);
 *   E_acc  temporal coherence (TemporalTerm): vertices pulled toward their constant-velocity
 *          course, so that the tracked motion does not shake.
 *
 * Each frame (track()): the frame's data (FrameData: field, normals, subsample); the start (the
 * motion predictor continues the last frames); the coarse level (GraphRegistration: an embedded
 * deformation graph on the template, solved from stiff and far-reaching to supple and local,
 * so large motions are caught as whole limbs, with rigidity measured against the template,
 * not the last frame); the fine level (a solver over all the terms, from the coarse result);
 * then the frame's quality from both directions (FrameQuality). A frame whose quality is in
 * doubt (any share beyond the take's usual) is tried again from the last frame without
 * extrapolation, from the last frame that was not in doubt (when the last one was), and from
 * the template re-registered rigidly to the last frame; the best attempt is kept, and the frame
 * is flagged if it still fails: data unexplained, mesh taken off its data or a tear, not mesh
 * over a hole in the data (RecoveryPolicy, RecoveryOptions). When a limb tore (an edge grew
 * beyond its template length by more than two mean edge lengths), the first retry keeps the
 * predicted start but holds the coarse level's limbs stiffer (stretch weight x4, rigidity x2:
 * RecoveryOptions::stiffening): a fast limb that passes another is pulled along with the
 * other's data by stretching, which the default stiffness, tuned for non-rigid takes, allows.
 *
 * Solvers of the fine level (Solvers.h): Gauss-Newton (default), L-BFGS, and the paper's
 * steepest descent with h = 1.9 / k_max, motion prediction (MP: the best of the extrapolations
 * of the trajectories) and provisional determination (PD). With the coarse level switched off,
 * the start is the paper's MP (or the last frame) followed by a rigid alignment (RigidAlignment).
 *
 * Missing data: an empty frame continues the motion (linear extrapolation of the last two
 * frames), relaxed by E_int alone, and is flagged (emptyFrame); so is a frame with too little
 * data to place a surface (under 10 points, or all within 2 voxels), which is also marked failed.
 * Holes are bridged by E_int and E_acc.
 * The first frame is never failed: it sets the take's usual quality.
 *
 * Limits: a local optimiser per frame (the coarse level widens its reach to ~24 voxels); data
 * the template lacks, or template parts fused together, cannot be tracked apart.
 */
#pragma once

#include "dp/geometry/FrameSamples.h"
#include "dp/geometry/TriangleMesh.h"
#include "dp/track/ClothEnergy.h"
#include "dp/track/TrackerOptions.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace dp
{

/** Where a frame's time went, in seconds. */
struct FrameTimings
{
  double data = 0;       // distance field, normals, subsample
  double prediction = 0; // the start (motion prediction, rigid alignment)
  double coarse = 0;     // the deformation graph's registration
  double fine = 0;       // the fine solve
  double quality = 0;    // the quality measures
};

struct FrameResult
{
  std::vector<double> positions;      // 3 per vertex
  std::vector<double> residual;       // distance to the data per vertex (D), -1 if no data
  std::vector<std::uint8_t> frozen;   // PD: frozen at the end of the solve
  std::vector<std::uint8_t> rejected; // normal test or outlier cut-off dropped the data term
  int iterations = 0;                 // of the fine solve (the kept attempt)
  // The kept attempt's fine level went on to convergence after its few steps
  // (GraphOptions::fineIterations) left a frame that failed the quality check.
  bool solvedOn = false;
  int coarseIterations = 0; // of the coarse level (the kept attempt)
  double internalEnergy = 0;
  double distanceEnergy = 0;
  double unexplained = 0; // share of the data farther than 3 voxels from the mesh (FrameQuality)
  double unsupported = 0; // share of the mesh farther than 3 voxels from the data
  double tear = 0;        // the most a stiff edge grew, in mean edge lengths (largestEdgeGrowth)
  double noise = 0;       // the data's layer thickness, measured (FrameData::noise)
  int retries = 0;        // attempts after the first (the frame's quality failed)
  // Which attempt was kept: 0 the first, 1 a retry from another start, 2 the stiff retry.
  int kept = 0;
  bool failed = false; // the quality still failed after the retries: do not trust this frame
  double seconds = 0;  // the frame's work: its data's preparation and its tracking
  // Of that, the preparation's share that ran beside the frame before (set by a caller that
  // prepares frames on another thread, e.g. vtkDeformableTrackFilter): the frame's own wall
  // time is seconds - overlapped.
  double overlapped = 0;
  FrameTimings timings;
  bool emptyFrame = false;
  std::size_t pointsGiven = 0; // the frame's points (a mesh frame's vertices)
  // The points read: the same, fewer when the frame was thinned (maxFramePoints), or a mesh
  // frame's samples of its surface (meshFrameSamples).
  std::size_t pointsUsed = 0;
  bool thinned = false;
  // The frame's well-spread subsample with its oriented normals (empty for an empty frame or
  // one with too little data): what a take's fit to its data is measured on (measureDataFit).
  FrameSamples samples;
  // Where the points carry colour: each vertex's colour in this frame (r g b bytes), the frame's
  // colour at the vertex (ColourField, the colour term's fine kernel); a vertex without points
  // near it keeps its colour of the frame before. Empty without colour.
  std::vector<std::uint8_t> colours;
  // For diagnosis (BenchmarkTracker prints their errors): the kept attempt's start and the
  // coarse level's result.
  std::vector<double> startPositions, coarsePositions;
};

class FrameData;
struct FrameQuality;
struct MeshSurface;

/** A frame's data made ready for Tracker::track(): its distance field, normals and subsample
 *  (FrameData), or the finding that it has too little data to say where a surface is. Made from
 *  the points and the tracker's settings alone, never its state, so Tracker::prepare() may run
 *  on another thread while the frame before is tracked: in a pipeline the frame's data, about a
 *  fifth of its work, costs no waiting (the second core is idle for much of a solve). */
class PreparedFrame
{
public:
  PreparedFrame();
  PreparedFrame(PreparedFrame&&) noexcept;
  PreparedFrame& operator=(PreparedFrame&&) noexcept;
  ~PreparedFrame();
  /** How long prepare() took, in seconds. */
  double seconds() const { return Seconds; }

private:
  friend class Tracker;
  std::unique_ptr<FrameData> Data; // null when the frame has too little data
  std::size_t Count = 0;           // the frame's points
  double Seconds = 0;
  const class Tracker* Owner = nullptr; // whose settings made it
};

class Tracker
{
public:
  /** `templatePositions` is the rest state and the start of frame 0. Throws
   *  std::invalid_argument for a mesh without area or options out of range. */
  Tracker(TriangleMesh mesh, std::vector<double> templatePositions, const TrackerOptions& options);
  // The energies refer to the tracker's own mesh: a tracker does not move.
  Tracker(const Tracker&) = delete;
  Tracker& operator=(const Tracker&) = delete;
  ~Tracker();

  /**
   * Fits the mesh to the next frame's points (x y z each; normals nx ny nz each or nullptr to
   * estimate them) and returns the result; the tracker remembers it for the next frame.
   */
  FrameResult track(const double* points, std::size_t count, const float* normals);

  /** The first half of track(): the frame's data (throws std::invalid_argument for a frame
   *  the tracker cannot take). Const and thread-safe: it reads only the tracker's settings, so
   *  it may run while another thread is in track(). */
  PreparedFrame prepare(const double* points, std::size_t count, const float* normals) const
  {
    return prepare(points, count, normals, nullptr, 0);
  }
  /** The same for points with colour: `colourComponents` (3 or 4) bytes a point, or null. The
   *  colours ride along to FrameResult::samples for the take's colour term. */
  PreparedFrame prepare(const double* points, std::size_t count, const float* normals,
                        const std::uint8_t* colours, int colourComponents) const;
  /** The same for a frame that is a mesh: read as its surface (options().meshFrameSamples
   *  points spread over its area with its faces' normals and its vertices' colours,
   *  sampleMeshSurface), or as its vertices when that option is 0. The result's pointsGiven
   *  is then the mesh's vertex count, and pointsUsed the samples read. */
  PreparedFrame prepare(const MeshSurface& frame) const;
  /** The second half: fits the mesh to a prepared frame, as track() does. Its `seconds` and
   *  `timings.data` include the preparation's time, wherever it ran. Throws
   *  std::invalid_argument for a frame another tracker (or nobody) prepared. */
  FrameResult track(PreparedFrame frame);

  /** Forgets the trajectory: the next track() starts from the template again. */
  void reset();

  /** Continues from `positions` as if it had been the last result (no motion history). */
  void restartFrom(const std::vector<double>& positions);

  const TriangleMesh& mesh() const { return Mesh; }
  const std::vector<double>& templatePositions() const { return Template; }
  const TrackerOptions& options() const { return Options; }
  const ClothEnergy& clothEnergy() const { return Cloth; }
  double voxelSize() const { return Voxel; }

private:
  struct Attempt;
  enum class Start
  {
    Predicted, // the motion of the last frames continued
    Stiff,     // the same, with the coarse level's limbs held stiffer (a limb caught by another)
    Still,     // the last frame, no extrapolation
    LastGood,  // the last frame that did not fail (while the frames since fail)
    Template,  // the template, moved rigidly onto the last frame
    Regrown    // the best try with its lost part moved onto the points it left (PartRegrowth)
  };
  /** One try at a frame from `start`: the start, the coarse level, the fine solve, the
   *  frame's quality. The first try (Start::Predicted) takes the few fine steps of
   *  GraphOptions::fineIterations; other starts, and a try that goes on from `capped` (a first
   *  try that failed: its start and coarse level are kept), solve the fine level to
   *  convergence. */
  Attempt attempt(const class FrameData& frame, Start start, const Attempt* capped = nullptr);
  /** The frame's quality at positions x, its tear included; what departed is measured from
   *  a's start. */
  FrameQuality qualityOf(const class FrameData& frame, const std::vector<double>& x,
                         const Attempt& a) const;
  /** The start's positions (the graph deformed by a.state, or the last frame's extrapolated
   *  and aligned when the coarse level is off). */
  std::vector<double> startPositions(Start start, Attempt& a, class DistanceTerm& distance,
                                     class InternalEnergyTerm& internal) const;
  /** The coarse level from a.state; x becomes the graph's deformation. */
  void solveCoarse(Start start, Attempt& a, class DistanceTerm& distance,
                   class CoverageTerm* coverage, class ColourTerm* colour, std::vector<double>& x);
  /** The fine solve from x with the frame's terms; records iterations, energies and the
   *  per-vertex residuals in `a`; without `converge`, the few steps of attempt(). */
  void solveFine(Attempt& a, class DistanceTerm& distance, class CoverageTerm* coverage,
                 class ColourTerm* colour, class InternalEnergyTerm& internal,
                 std::vector<double>& x, bool converge);
  /** Each vertex's colour in the first frame with colour (the colour term's references). */
  void readColourReference(const class FrameData& frame, const std::vector<double>& positions);
  /** The vertices' colours in a frame (FrameResult::colours). */
  void readVertexColours(const class FrameData* frame, FrameResult& result);
  /** The coarse level's start: sets a.state, the graph's state for `start` (the identity at
   *  frame 0). */
  void startState(Start start, Attempt& a) const;
  /** Replaces the turning continuation a.state (deformed: x) by the straight one when the data
   *  are closer to it (MotionPredictor, Extrapolation). */
  void preferStraightIfCloser(class DistanceTerm& distance, Attempt& a,
                              std::vector<double>& x) const;
  /** Whether a first try's fine level stops after GraphOptions::fineIterations steps (the graph
   *  is on, the solver Gauss-Newton, and the limit below maxIterations). */
  bool capsFineLevel() const;
  /** The predicted attempt, then the retries while it fails; counts them in `result`. */
  Attempt solveWithRetries(const class FrameData& frame, FrameResult& result);
  /** Whether `best` lost a part that regrowLostPart can place on the points it left; if so,
   *  Start::Regrown's state is set to that placement. */
  bool regrowable(const class FrameData& frame, const Attempt& best);
  /** Moves the kept attempt's outcome into `result`. */
  static void keep(Attempt&& best, FrameResult& result);
  /** What the next frames need of this one: motion history, the graph's reference, the last
   *  frame that did not fail. */
  void remember(const FrameResult& result);
  void trackEmptyFrame(FrameResult& result);
  /** Turns the frame's estimated normals to agree with the last shape: each part by its
   *  majority, then the branches of the orientation that disagree as a whole. */
  void orientData(class FrameData& frame) const;

  TriangleMesh Mesh;
  std::vector<double> Template;
  TrackerOptions Options;
  ClothEnergy Cloth;
  ClothRestState TemplateRest;
  double Voxel = 0;
  struct Parts;
  std::unique_ptr<Parts> P; // graph, solvers, predictor
};

} // namespace dp
