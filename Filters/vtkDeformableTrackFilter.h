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
 * "Rejected" (normal test or outlier cut-off), "Normals" (area-weighted, the active normals: smooth
 * shading), and "Colors" (the frame's colour at each vertex, the active scalars) where the points
 * carry colour. Field data: "FrameIndex", "Points" (the frame's),
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

  ///@{
  /**
   * Any tracker option by its name in dp::TrackerOptions ("graph.yieldLimit") or its property
   * name ("Plasticity"): the named accessors below are these for the options ParaView's panel
   * shows; the others (`dynamicpoints --print-options` lists them all, with their ranges, as
   * does Documentation/TrackerOptions.md) are reached only so. A value out of the option's
   * range is clamped to it, as VTK's setters do; an unknown name is an error.
   */
  void SetTrackerOption(const char* name, double value);
  double GetTrackerOption(const char* name);
  ///@}

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
  void SetSolver(int value) { this->SetTrackerOption("Solver", value); }
  int GetSolver() { return static_cast<int>(this->GetTrackerOption("Solver")); }
  ///@}

  enum DistanceMeasureType
  {
    DISTANCE_TO_PLANES = 0, // tangent planes of the nearest points (default)
    DISTANCE_TO_POINTS = 1  // the nearest points themselves (the paper)
  };

  ///@{
  /** What the distance term measures: the distance to the tangent planes of the nearest data
   *  points (default; vertices can slide along the data) or to the points (the paper). */
  void SetDistanceMeasure(int value) { this->SetTrackerOption("DistanceMeasure", value); }
  int GetDistanceMeasure() { return static_cast<int>(this->GetTrackerOption("DistanceMeasure")); }
  ///@}

  ///@{
  /** Penalise the squared distance D^2 / (2 voxel) (default on) or the distance D (the
   *  paper). */
  void SetSquaredDistance(vtkTypeBool value) { this->SetTrackerOption("SquaredDistance", value); }
  vtkTypeBool GetSquaredDistance()
  {
    return static_cast<vtkTypeBool>(this->GetTrackerOption("SquaredDistance"));
  }
  void SquaredDistanceOn() { this->SetSquaredDistance(1); }
  void SquaredDistanceOff() { this->SetSquaredDistance(0); }
  ///@}

  ///@{
  /** Frames that are meshes are read as this many points spread over their area, with their
   *  faces' normals (default 20000, or one a vertex if more; 0: their vertices alone). */
  void SetMeshFrameSamples(int value) { this->SetTrackerOption("MeshFrameSamples", value); }
  int GetMeshFrameSamples() { return static_cast<int>(this->GetTrackerOption("MeshFrameSamples")); }
  ///@}

  ///@{
  /** Share of the previous frame in the rest state of the deformation energy (default 0.3;
   *  0 = the template, as in the paper; 1 = the previous frame). */
  void SetRestUpdate(double value) { this->SetTrackerOption("RestUpdate", value); }
  double GetRestUpdate() { return static_cast<double>(this->GetTrackerOption("RestUpdate")); }
  ///@}

  ///@{
  /** Weights of the energy terms (all dimensionless; defaults 50, 1, 0, 0.5). */
  void SetDistanceWeight(double value) { this->SetTrackerOption("DistanceWeight", value); }
  double GetDistanceWeight()
  {
    return static_cast<double>(this->GetTrackerOption("DistanceWeight"));
  }
  void SetStretchStiffness(double value) { this->SetTrackerOption("StretchStiffness", value); }
  double GetStretchStiffness()
  {
    return static_cast<double>(this->GetTrackerOption("StretchStiffness"));
  }
  void SetShearStiffness(double value) { this->SetTrackerOption("ShearStiffness", value); }
  double GetShearStiffness()
  {
    return static_cast<double>(this->GetTrackerOption("ShearStiffness"));
  }
  void SetBendStiffness(double value) { this->SetTrackerOption("BendStiffness", value); }
  double GetBendStiffness() { return static_cast<double>(this->GetTrackerOption("BendStiffness")); }
  ///@}

  ///@{
  /** Factor on the stretch stiffness of the template's thick parts (a trunk, away from its
   *  limbs; dp::ThicknessSoftening): default 0.3, so that a body's skin stretches and slides
   *  over the torso as it bends; 1 is one stiffness everywhere, better for slow non-rigid
   *  motion far from isometric (a collapse; Documentation/Tracking.md). */
  void SetThickPartStretch(double value) { this->SetTrackerOption("ThickPartStretch", value); }
  double GetThickPartStretch()
  {
    return static_cast<double>(this->GetTrackerOption("ThickPartStretch"));
  }
  ///@}

  ///@{
  /** Factor on the stretch stiffness in the template's creases (armpits, crotch, an arm that
   *  touches the body in the template; dp::CreaseSoftening): default 0.1, so that those bridges
   *  stretch as the parts move apart instead of dragging the torso's skin; 1 switches it off. */
  void SetCreaseStretch(double value) { this->SetTrackerOption("CreaseStretch", value); }
  double GetCreaseStretch() { return static_cast<double>(this->GetTrackerOption("CreaseStretch")); }
  ///@}

  ///@{
  /** Normal test: drop a vertex's distance term when its normal and its nearest point's normal
   *  differ by more than this angle in degrees (default 90; 180 switches the test off). */
  void SetNormalTestAngle(double value) { this->SetTrackerOption("NormalTestAngle", value); }
  double GetNormalTestAngle()
  {
    return static_cast<double>(this->GetTrackerOption("NormalTestAngle"));
  }
  ///@}

  ///@{
  /** Drop the distance term of vertices farther than this from the data (world units;
   *  default 0 = never). */
  void SetOutlierDistance(double value) { this->SetTrackerOption("OutlierDistance", value); }
  double GetOutlierDistance()
  {
    return static_cast<double>(this->GetTrackerOption("OutlierDistance"));
  }
  ///@}

  ///@{
  /** Distance field resolution and band in world units (0 = automatic: the template's
   *  diagonal / 200, and 4 voxels). */
  void SetVoxelSize(double value) { this->SetTrackerOption("VoxelSize", value); }
  double GetVoxelSize() { return static_cast<double>(this->GetTrackerOption("VoxelSize")); }
  void SetBandWidth(double value) { this->SetTrackerOption("BandWidth", value); }
  double GetBandWidth() { return static_cast<double>(this->GetTrackerOption("BandWidth")); }
  ///@}

  ///@{
  /** The paper's speed-ups: motion prediction (MP) and provisional determination (PD). */
  void SetMotionPrediction(vtkTypeBool value) { this->SetTrackerOption("MotionPrediction", value); }
  vtkTypeBool GetMotionPrediction()
  {
    return static_cast<vtkTypeBool>(this->GetTrackerOption("MotionPrediction"));
  }
  void MotionPredictionOn() { this->SetMotionPrediction(1); }
  void MotionPredictionOff() { this->SetMotionPrediction(0); }
  void SetProvisionalDetermination(vtkTypeBool value)
  {
    this->SetTrackerOption("ProvisionalDetermination", value);
  }
  vtkTypeBool GetProvisionalDetermination()
  {
    return static_cast<vtkTypeBool>(this->GetTrackerOption("ProvisionalDetermination"));
  }
  void ProvisionalDeterminationOn() { this->SetProvisionalDetermination(1); }
  void ProvisionalDeterminationOff() { this->SetProvisionalDetermination(0); }
  ///@}

  ///@{
  /** Move the predicted mesh rigidly onto each frame's points before deforming it (default on):
   *  keeps a turning shape from slipping along its surface. Used only without the coarse level
   *  (CoarseLevel off), whose registration includes the rigid motion. */
  void SetRigidAlignment(vtkTypeBool value) { this->SetTrackerOption("RigidAlignment", value); }
  vtkTypeBool GetRigidAlignment()
  {
    return static_cast<vtkTypeBool>(this->GetTrackerOption("RigidAlignment"));
  }
  void RigidAlignmentOn() { this->SetRigidAlignment(1); }
  void RigidAlignmentOff() { this->SetRigidAlignment(0); }
  ///@}

  ///@{
  /** Iteration limit of a frame's cloth solve (with the coarse level on, Gauss-Newton takes at
   *  most FineIterations) and relative tolerance of the stopping rule. */
  void SetMaximumIterations(int value) { this->SetTrackerOption("MaximumIterations", value); }
  int GetMaximumIterations()
  {
    return static_cast<int>(this->GetTrackerOption("MaximumIterations"));
  }
  void SetTolerance(double value) { this->SetTrackerOption("Tolerance", value); }
  double GetTolerance() { return static_cast<double>(this->GetTrackerOption("Tolerance")); }
  ///@}

  ///@{
  /** Weight of the points -> mesh term (default 50; 0 = the paper's energy alone): the data
   *  pulls the closest point of the mesh, so a part of the mesh cannot let go of its data (a
   *  limb) at no cost. */
  void SetCoverageWeight(double value) { this->SetTrackerOption("CoverageWeight", value); }
  double GetCoverageWeight()
  {
    return static_cast<double>(this->GetTrackerOption("CoverageWeight"));
  }
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
  void SetCoarseLevel(vtkTypeBool value) { this->SetTrackerOption("CoarseLevel", value); }
  vtkTypeBool GetCoarseLevel()
  {
    return static_cast<vtkTypeBool>(this->GetTrackerOption("CoarseLevel"));
  }
  void CoarseLevelOn() { this->SetCoarseLevel(1); }
  void CoarseLevelOff() { this->SetCoarseLevel(0); }
  void SetGraphNodes(int value) { this->SetTrackerOption("GraphNodes", value); }
  int GetGraphNodes() { return static_cast<int>(this->GetTrackerOption("GraphNodes")); }
  void SetGraphRigidity(double value) { this->SetTrackerOption("GraphRigidity", value); }
  double GetGraphRigidity() { return static_cast<double>(this->GetTrackerOption("GraphRigidity")); }
  void SetPlasticity(double value) { this->SetTrackerOption("Plasticity", value); }
  double GetPlasticity() { return static_cast<double>(this->GetTrackerOption("Plasticity")); }
  void SetFineIterations(int value) { this->SetTrackerOption("FineIterations", value); }
  int GetFineIterations() { return static_cast<int>(this->GetTrackerOption("FineIterations")); }
  ///@}

  ///@{
  /** Weight of the temporal term pulling vertices toward their constant-velocity course
   *  (default 0 = off; about 1 halves the shake of slow, non-rigid motion, but lags fast
   *  motion such as a jumping human). */
  void SetTemporalWeight(double value) { this->SetTrackerOption("TemporalWeight", value); }
  double GetTemporalWeight()
  {
    return static_cast<double>(this->GetTrackerOption("TemporalWeight"));
  }
  ///@}

  ///@{
  /** Weight of the colour term where the points carry colour ("RGB", "RGBA" or "Colors" bytes,
   *  or active scalars of 3 or 4 bytes): each vertex is pulled, along the surface, to where the
   *  frame shows the colour its material point had in the first frame (default 50; 0 = off).
   *  Geometry says where the surface is, not where on it a vertex lies: colour keeps each vertex
   *  on its material point. The tracked mesh then carries "Colors" (the frame's colour at each
   *  vertex; where the frame has no points near a vertex, its last colour). */
  void SetColourWeight(double value) { this->SetTrackerOption("ColourWeight", value); }
  double GetColourWeight() { return static_cast<double>(this->GetTrackerOption("ColourWeight")); }
  ///@}

  ///@{
  /** Failure detection and recovery (default on): a frame whose share of data unexplained by
   *  the mesh (beyond 3 voxels) exceeds the take's usual share by more than FailureMargin
   *  (default 0.003), or whose mesh tore, is tried again from the last frame and from the
   *  template re-registered; the best attempt is kept, and flagged in "Failed" if it still
   *  fails. Mesh the solve took off its data fails too; mesh without data over a hole in the
   *  data fails nothing. */
  void SetRecovery(vtkTypeBool value) { this->SetTrackerOption("Recovery", value); }
  vtkTypeBool GetRecovery() { return static_cast<vtkTypeBool>(this->GetTrackerOption("Recovery")); }
  void RecoveryOn() { this->SetRecovery(1); }
  void RecoveryOff() { this->SetRecovery(0); }
  void SetFailureMargin(double value) { this->SetTrackerOption("FailureMargin", value); }
  double GetFailureMargin() { return static_cast<double>(this->GetTrackerOption("FailureMargin")); }
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
  void SetTemplateVertices(int vertices); // clamped to the engine's range (20 to 10 million)
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

  int TemplateVertices;
  int TemplateSource;

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
