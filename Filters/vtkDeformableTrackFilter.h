// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkDeformableTrackFilter
 * @brief   deforms one template mesh through a time series of point clouds
 *
 * vtkDeformableTrackFilter turns a temporal point sequence (input 0: any temporal vtkPointSet
 * source, e.g. vtkPointSequenceSource) into ONE deforming mesh of fixed connectivity: frame by
 * frame it minimises the cloth energy of the mesh (stretch, shear, bend; rest state = the
 * template) plus the distance from its vertices to the frame's points, as in Shinya, Shioya &
 * Shiraishi, "Unification of Dynamic Point Data" (see dp::Tracker for the equations and the
 * solvers). No skeleton, no correspondences.
 *
 * The template (dp::makeTemplate) is input 1 when connected (a vtkPolyData with polygons,
 * repaired, never remeshed), else frame 0's own mesh (repaired and remeshed to TemplateVertices
 * vertices: a capture's per-frame mesh), else a surface reconstructed from frame 0's points
 * (dp::reconstructSurface: signed distance to the points' tangent planes on a fine OpenVDB grid,
 * holes in the data bridged, remeshed isotropically to TemplateVertices vertices; frame 0's
 * "Normals" are used when present, else estimated); TemplateSource chooses between frame 0's mesh
 * and its points. What was done is in the output's field data "Template". The output has the
 * template's connectivity; its points follow the requested time. Beyond the paper (see
 * dp::Tracker): a points -> mesh term (CoverageWeight), a coarse level (an embedded deformation
 * graph, CoarseLevel) and failure detection with retries (Recovery), and where the points carry
 * colour a colour term (ColourWeight). Point arrays: "Displacement" (from the template), "Residual"
 * (distance to the frame's points, -1 without data), "Frozen" (provisional determination),
 * "Rejected" (normal test or outlier cut-off), and "Colors" (the frame's colour at each vertex, the
 * active scalars) where the points carry colour. Field data: "FrameIndex", "Points" (the frame's),
 * "Iterations", "CoarseIterations", "InternalEnergy", "DistanceEnergy", "Seconds" (the frame's wall
 * time) and where its work went
 * ("DataSeconds": field, normals, subsample, of which "OverlappedSeconds" ran beside the frame
 * before; "PredictionSeconds": the start; "CoarseSeconds", "FineSeconds", "QualitySeconds" of the
 * kept attempt; "RetrySeconds": the other attempts; the stages add up to Seconds +
 * OverlappedSeconds but for a little bookkeeping, an empty frame's time is in Seconds only),
 * "EmptyFrame", and the frame's quality: "Unexplained" (share of the points farther than 3 voxels
 * from the mesh), "Unsupported" (share of the mesh farther than that from the points: holes in the
 * data, no failure by itself), "LargestStretch" (the most a stiff edge grew beyond its template
 * length, in mean edge lengths: above 2 a limb was caught by other data and torn), "Retries",
 * "Failed" (1: the frame still failed after the retries; do not trust it; a warning says so);
 * "DataSamples" (the frame's well-spread subsample of points, about 4 a vertex) and "DataReach"
 * (how far from the mesh a point still counts as explained): what vtkPCACompressFilter's
 * DISTANCE_TO_DATA judges a compression by.
 *
 * Time: the output publishes the input's time steps. Asking for time t computes the frames up
 * to t in order (each needs the one before; the pipeline re-executes with CONTINUE_EXECUTING),
 * with progress and abort, and caches every result: later requests for any computed time are
 * answered from the cache. Any change of a parameter, of the template or upstream clears the
 * cache. The input is read one frame ahead: while frame f is tracked, frame f + 1's data is
 * prepared on another thread (dp::Tracker::prepare; not with one thread). A frame whose input
 * says it could not be read ("UnreadableFrame", vtkPointSequenceSource) stops the run before it
 * with an error; the frames before are kept.
 *
 * @warning Memory: the cache keeps one position array per computed frame (24 bytes per vertex
 * and frame). An empty frame is tracked by continuing the motion and flagged in "EmptyFrame".
 */
#ifndef vtkDeformableTrackFilter_h
#define vtkDeformableTrackFilter_h

#include "DynamicPointsFiltersModule.h" // for export macro
#include "vtkDPTemporalFilter.h"

#include <cstdint> // for std::int64_t
#include <vector>  // for std::vector

class DYNAMICPOINTSFILTERS_EXPORT vtkDeformableTrackFilter : public vtkDPTemporalFilter
{
public:
  static vtkDeformableTrackFilter* New();
  vtkTypeMacro(vtkDeformableTrackFilter, vtkDPTemporalFilter);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /** The template mesh (optional input 1). */
  void SetTemplateConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }

  enum SolverType
  {
    GAUSS_NEWTON = 0,
    LBFGS = 1,
    STEEPEST_DESCENT = 2
  };

  ///@{
  /** The minimiser: Gauss-Newton (default), L-BFGS, or the paper's steepest descent. */
  vtkSetClampMacro(Solver, int, GAUSS_NEWTON, STEEPEST_DESCENT);
  vtkGetMacro(Solver, int);
  ///@}

  enum DistanceMeasureType
  {
    DISTANCE_TO_PLANES = 0, // tangent planes of the nearest points (default)
    DISTANCE_TO_POINTS = 1  // the nearest points themselves (the paper)
  };

  ///@{
  /** What the distance term measures: the distance to the tangent planes of the nearest data
   *  points (default; vertices can slide along the data) or to the points (the paper). */
  vtkSetClampMacro(DistanceMeasure, int, DISTANCE_TO_PLANES, DISTANCE_TO_POINTS);
  vtkGetMacro(DistanceMeasure, int);
  ///@}

  ///@{
  /** Penalise the squared distance D^2 / (2 voxel) (default on) or the distance D (the
   *  paper). */
  vtkSetMacro(SquaredDistance, vtkTypeBool);
  vtkGetMacro(SquaredDistance, vtkTypeBool);
  vtkBooleanMacro(SquaredDistance, vtkTypeBool);
  ///@}

  ///@{
  /** Share of the previous frame in the rest state of the deformation energy (default 0.3;
   *  0 = the template, as in the paper; 1 = the previous frame). */
  vtkSetClampMacro(RestUpdate, double, 0.0, 1.0);
  vtkGetMacro(RestUpdate, double);
  ///@}

  ///@{
  /** Weights of the energy terms (all dimensionless; defaults 50, 1, 0, 0.5). */
  vtkSetClampMacro(DistanceWeight, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(DistanceWeight, double);
  vtkSetClampMacro(StretchStiffness, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(StretchStiffness, double);
  vtkSetClampMacro(ShearStiffness, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(ShearStiffness, double);
  vtkSetClampMacro(BendStiffness, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(BendStiffness, double);
  ///@}

  ///@{
  /** Factor on the stretch stiffness of the template's thick parts (a trunk, away from its
   *  limbs; dp::ThicknessSoftening): default 0.3, so that a body's skin stretches and slides
   *  over the torso as it bends; 1 is one stiffness everywhere, better for slow non-rigid
   *  motion far from isometric (a collapse; Documentation/Tracking.md). */
  vtkSetClampMacro(ThickPartStretch, double, 0.0, 1.0);
  vtkGetMacro(ThickPartStretch, double);
  ///@}

  ///@{
  /** Factor on the stretch stiffness in the template's creases (armpits, crotch, an arm that
   *  touches the body in the template; dp::CreaseSoftening): default 0.1, so that those bridges
   *  stretch as the parts move apart instead of dragging the torso's skin; 1 switches it off. */
  vtkSetClampMacro(CreaseStretch, double, 0.0, 1.0);
  vtkGetMacro(CreaseStretch, double);
  ///@}

  ///@{
  /** Normal test: drop a vertex's distance term when its normal and its nearest point's normal
   *  differ by more than this angle in degrees (default 90; 180 switches the test off). */
  vtkSetClampMacro(NormalTestAngle, double, 0.0, 180.0);
  vtkGetMacro(NormalTestAngle, double);
  ///@}

  ///@{
  /** Drop the distance term of vertices farther than this from the data (world units;
   *  default 0 = never). */
  vtkSetClampMacro(OutlierDistance, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(OutlierDistance, double);
  ///@}

  ///@{
  /** Distance field resolution and band in world units (0 = automatic: the template's
   *  diagonal / 200, and 4 voxels). */
  vtkSetClampMacro(VoxelSize, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(VoxelSize, double);
  vtkSetClampMacro(BandWidth, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(BandWidth, double);
  ///@}

  ///@{
  /** The paper's speed-ups: motion prediction (MP) and provisional determination (PD). */
  vtkSetMacro(MotionPrediction, vtkTypeBool);
  vtkGetMacro(MotionPrediction, vtkTypeBool);
  vtkBooleanMacro(MotionPrediction, vtkTypeBool);
  vtkSetMacro(ProvisionalDetermination, vtkTypeBool);
  vtkGetMacro(ProvisionalDetermination, vtkTypeBool);
  vtkBooleanMacro(ProvisionalDetermination, vtkTypeBool);
  ///@}

  ///@{
  /** Move the predicted mesh rigidly onto each frame's points before deforming it (default on):
   *  keeps a turning shape from slipping along its surface. Used only without the coarse level
   *  (CoarseLevel off), whose registration includes the rigid motion. */
  vtkSetMacro(RigidAlignment, vtkTypeBool);
  vtkGetMacro(RigidAlignment, vtkTypeBool);
  vtkBooleanMacro(RigidAlignment, vtkTypeBool);
  ///@}

  ///@{
  /** Iteration limit of a frame's cloth solve (with the coarse level on, Gauss-Newton takes at
   *  most FineIterations) and relative tolerance of the stopping rule. */
  vtkSetClampMacro(MaximumIterations, int, 1, VTK_INT_MAX);
  vtkGetMacro(MaximumIterations, int);
  vtkSetClampMacro(Tolerance, double, 1e-15, 1.0);
  vtkGetMacro(Tolerance, double);
  ///@}

  ///@{
  /** Weight of the points -> mesh term (default 50; 0 = the paper's energy alone): the data
   *  pulls the closest point of the mesh, so a part of the mesh cannot let go of its data (a
   *  limb) at no cost. */
  vtkSetClampMacro(CoverageWeight, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(CoverageWeight, double);
  ///@}

  ///@{
  /** The coarse level (default on): an embedded deformation graph on the template is registered
   *  to each frame first, from stiff and far-reaching to supple, so that large and fast motions
   *  are caught as whole limbs; then the cloth solve refines. GraphNodes: its node count (0 =
   *  automatic, one per 5 vertices within 30..600). GraphRigidity multiplies its rigidity
   *  (default 1). Plasticity (0..1, default 0.3): where the shape stays bent far from the
   *  template (a collapse, clothes), the graph's reference gives way by this share per frame.
   *  FineIterations (default 3): the Gauss-Newton steps the cloth solve takes after the graph
   *  (at most); more let vertices slide along the data and end farther from the true ones. */
  vtkSetMacro(CoarseLevel, vtkTypeBool);
  vtkGetMacro(CoarseLevel, vtkTypeBool);
  vtkBooleanMacro(CoarseLevel, vtkTypeBool);
  vtkSetClampMacro(GraphNodes, int, 0, VTK_INT_MAX);
  vtkGetMacro(GraphNodes, int);
  vtkSetClampMacro(GraphRigidity, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(GraphRigidity, double);
  vtkSetClampMacro(Plasticity, double, 0.0, 1.0);
  vtkGetMacro(Plasticity, double);
  vtkSetClampMacro(FineIterations, int, 1, VTK_INT_MAX);
  vtkGetMacro(FineIterations, int);
  ///@}

  ///@{
  /** Weight of the temporal term pulling vertices toward their constant-velocity course
   *  (default 0 = off; about 1 halves the shake of slow, non-rigid motion, but lags fast
   *  motion such as a jumping human). */
  vtkSetClampMacro(TemporalWeight, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(TemporalWeight, double);
  ///@}

  ///@{
  /** Weight of the colour term where the points carry colour ("RGB", "RGBA" or "Colors" bytes,
   *  or active scalars of 3 or 4 bytes): each vertex is pulled, along the surface, to where the
   *  frame shows the colour its material point had in the first frame (default 50; 0 = off).
   *  Geometry says where the surface is, not where on it a vertex lies: colour keeps each vertex
   *  on its material point. The tracked mesh then carries "Colors" (the frame's colour at each
   *  vertex; where the frame has no points near a vertex, its last colour). */
  vtkSetClampMacro(ColourWeight, double, 0.0, VTK_DOUBLE_MAX);
  vtkGetMacro(ColourWeight, double);
  ///@}

  ///@{
  /** Failure detection and recovery (default on): a frame whose share of data unexplained by
   *  the mesh (beyond 3 voxels) exceeds the take's usual share by more than FailureMargin
   *  (default 0.003), or whose mesh tore, is tried again from the last frame and from the
   *  template re-registered; the best attempt is kept, and flagged in "Failed" if it still
   *  fails. Mesh the solve took off its data fails too; mesh without data over a hole in the
   *  data fails nothing. */
  vtkSetMacro(Recovery, vtkTypeBool);
  vtkGetMacro(Recovery, vtkTypeBool);
  vtkBooleanMacro(Recovery, vtkTypeBool);
  vtkSetClampMacro(FailureMargin, double, 0.0, 1.0);
  vtkGetMacro(FailureMargin, double);
  ///@}

  enum TemplateSourceType
  {
    TEMPLATE_AUTO = 0,       // frame 0's polygons when it has some, else its points
    TEMPLATE_FROM_MESH = 1,  // frame 0's polygons (an error without them)
    TEMPLATE_FROM_POINTS = 2 // a surface reconstructed from frame 0's points
  };
  ///@{
  /** What the template is made from without input 1 (default TEMPLATE_AUTO): frame 0's mesh
   *  (a capture's per-frame mesh), repaired (duplicate vertices merged, triangles without area,
   *  repeated triangles and small stray parts removed) and remeshed to about TemplateVertices
   *  vertices when it has more; or a surface reconstructed from frame 0's points with about
   *  TemplateVertices vertices (default 1000). A mesh on input 1 is repaired, never remeshed.
   *  What was done is in the output's field data "Template". */
  vtkSetClampMacro(TemplateSource, int, TEMPLATE_AUTO, TEMPLATE_FROM_POINTS);
  vtkGetMacro(TemplateSource, int);
  vtkSetClampMacro(TemplateVertices, int, 20, 10000000);
  vtkGetMacro(TemplateVertices, int);
  ///@}

  /**
   * An abort (ParaView's abort button, or SetAbortExecute(1) from a progress observer) stops
   * the run after the frame being tracked and keeps the frames done. Unlike the settings, it
   * does not change what is computed, so it does not mark the filter modified (which would
   * drop the cached frames).
   */
  void SetAbortExecute(vtkTypeBool abort) override;

  /** Number of frames computed and cached so far. */
  int GetNumberOfCachedFrames();

protected:
  vtkDeformableTrackFilter();
  ~vtkDeformableTrackFilter() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  void ClearTemporalState() override;
  long long NextInputFrame(std::size_t requestedFrame) override;
  int RequestFrameData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  // The properties; their defaults are the engine's (dp::TrackerOptions), set by the constructor.
  int Solver;
  double DistanceWeight;
  int DistanceMeasure;
  vtkTypeBool SquaredDistance;
  double RestUpdate;
  double StretchStiffness;
  double ShearStiffness;
  double BendStiffness;
  double ThickPartStretch;
  double CreaseStretch;
  double NormalTestAngle;
  double OutlierDistance;
  double VoxelSize;
  double BandWidth;
  vtkTypeBool MotionPrediction;
  vtkTypeBool RigidAlignment;
  vtkTypeBool ProvisionalDetermination;
  int MaximumIterations;
  double Tolerance;
  int TemplateVertices;
  int TemplateSource;
  double CoverageWeight;
  vtkTypeBool CoarseLevel;
  int GraphNodes;
  double GraphRigidity;
  int FineIterations;
  double Plasticity;
  double TemporalWeight;
  double ColourWeight;
  vtkTypeBool Recovery;
  double FailureMargin;

private:
  // RequestFrameData's steps; each reports its own errors and returns false on one.
  /** The template: input 1, else frame 0's polygons, else reconstructed from frame 0. */
  bool TemplateOf(vtkInformationVector** inputVector, vtkPointSet* frame0,
                  std::vector<std::int64_t>& triangles, std::vector<double>& positions);
  bool MakeTracker(vtkInformationVector** inputVector, vtkPointSet* frame0);
  struct PendingFrame;
  /** Starts preparing input `frame`'s data (beside the caller when there is a second thread). */
  PendingFrame PrepareFrame(std::size_t frame, vtkPointSet* input);
  /** Tracks the next frame from its prepared data into the cache, with its warnings. */
  bool TrackFrame(std::size_t frame, PendingFrame pending);
  enum class PipelineStep
  {
    Tracked,  // frame `frame` is in the cache
    Prepared, // only its data was started: the next pass reads the frame after it
    Failed    // an error was reported
  };
  /** One pass of the frame-after-frame run: the input read now goes into the pipeline (its data
   *  prepared beside the solve), and frame `frame` is tracked once its data is there. */
  PipelineStep StepPipeline(std::size_t frame, vtkInformationVector** inputVector);
  /** Progress text, shift and scale while computing `frame`, or once it is done. */
  void ShowProgressOf(std::size_t frame, bool done);
  vtkDeformableTrackFilter(const vtkDeformableTrackFilter&) = delete;
  void operator=(const vtkDeformableTrackFilter&) = delete;

  struct Internals;
  Internals* Internal;
};

#endif
