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

  enum DistanceMeasureType
  {
    DISTANCE_TO_PLANES = 0, // tangent planes of the nearest points (default)
    DISTANCE_TO_POINTS = 1  // the nearest points themselves (the paper)
  };

  // The named accessors of the table's options that ParaView's panel shows, written by
  // build/bin/dp-option-code from the table (dp/io/OptionCode.h): edit the table, not here.
  // BEGIN generated options: tracker
  // clang-format off
  ///@{
  /** Resistance to changes of edge length (dimensionless, constant per edge). (cloth.stretch;
   *  range [0, inf]) */
  void SetStretchStiffness(double value) { this->SetTrackerOption("StretchStiffness", value); }
  double GetStretchStiffness() { return this->GetTrackerOption("StretchStiffness"); }
  ///@}
  ///@{
  /** Resistance to changes of the corner angles of triangles. Off by default: edge lengths alone
   *  hold the in-plane shape of a well-shaped mesh, and track more accurately. Set it (e.g. 0.05)
   *  for a template with slivers (nearly flat triangles); the filter warns when it sees them.
   *  (cloth.shear; range [0, inf]) */
  void SetShearStiffness(double value) { this->SetTrackerOption("ShearStiffness", value); }
  double GetShearStiffness() { return this->GetTrackerOption("ShearStiffness"); }
  ///@}
  ///@{
  /** Resistance to bending (changes of the angle between neighbouring triangles), weighted by
   *  area so that it does not depend on the mesh resolution. (cloth.bend; range [0, inf]) */
  void SetBendStiffness(double value) { this->SetTrackerOption("BendStiffness", value); }
  double GetBendStiffness() { return this->GetTrackerOption("BendStiffness"); }
  ///@}
  ///@{
  /** Factor on the stretch stiffness where the template is thick (a trunk, as measured by its
   *  inner medial balls; limbs keep the full stiffness). The default 0.3 lets a body's skin
   *  stretch and slide over the torso as it bends (a captured human: 30.9 to 26.6 mm vertex error
   *  with a reconstructed template). 1 is one stiffness everywhere: better for slow motion far
   *  from isometric, such as a collapse or cloth. (softening.stretch; range [0, 1]) */
  void SetThickPartStretch(double value) { this->SetTrackerOption("ThickPartStretch", value); }
  double GetThickPartStretch() { return this->GetTrackerOption("ThickPartStretch"); }
  ///@}
  ///@{
  /** Factor on the stretch stiffness in the template's creases: where the space in front of the
   *  surface is narrow (armpits, crotch, an arm that touches the body in the template and was
   *  reconstructed joined to it). Soft, those bridges stretch as the parts move apart instead of
   *  dragging the torso's skin along with the arm (reconstructed human: 34 to 29 mm vertex
   *  error). 1 is one stiffness everywhere. (creases.stretch; range [0, 1]) */
  void SetCreaseStretch(double value) { this->SetTrackerOption("CreaseStretch", value); }
  double GetCreaseStretch() { return this->GetTrackerOption("CreaseStretch"); }
  ///@}
  ///@{
  /** Share of the previous frame in the rest shape of the deformation energy: 0 keeps the
   *  template (the paper); larger values let the mesh follow shapes far from the template.
   *  (restUpdate; range [0, 1]) */
  void SetRestUpdate(double value) { this->SetTrackerOption("RestUpdate", value); }
  double GetRestUpdate() { return this->GetTrackerOption("RestUpdate"); }
  ///@}
  ///@{
  /** Weight of the distance-to-data term (dimensionless). (distance.weight; range [0, inf]) */
  void SetDistanceWeight(double value) { this->SetTrackerOption("DistanceWeight", value); }
  double GetDistanceWeight() { return this->GetTrackerOption("DistanceWeight"); }
  ///@}
  ///@{
  /** What the distance term measures: the distance to the tangent planes of the nearest data
   *  points (the mesh can slide along the data), or to the points themselves as in the paper.
   *  (distance.measure; range planes|points) */
  void SetDistanceMeasure(int value) { this->SetTrackerOption("DistanceMeasure", value); }
  int GetDistanceMeasure() { return static_cast<int>(this->GetTrackerOption("DistanceMeasure")); }
  ///@}
  ///@{
  /** Penalise the squared distance (smooth at the data; default) instead of the distance itself
   *  (the paper). (distance.squared; range true|false) */
  void SetSquaredDistance(vtkTypeBool value) { this->SetTrackerOption("SquaredDistance", value); }
  vtkTypeBool GetSquaredDistance() { return static_cast<vtkTypeBool>(this->GetTrackerOption("SquaredDistance")); }
  vtkBooleanMacro(SquaredDistance, vtkTypeBool);
  ///@}
  ///@{
  /** A vertex ignores the data when its normal and the normal of its nearest point differ by more
   *  than this angle in degrees (keeps surfaces from snapping to the wrong side, e.g. between
   *  legs). 180 switches the test off. (distance.normalTestDegrees; range [0, 180], degrees) */
  void SetNormalTestAngle(double value) { this->SetTrackerOption("NormalTestAngle", value); }
  double GetNormalTestAngle() { return this->GetTrackerOption("NormalTestAngle"); }
  ///@}
  ///@{
  /** Vertices farther than this from the data (world units) ignore it. 0: no cut-off. By default
   *  a vertex whose nearest point another part of the mesh is nearer to (a hole's rim, a body's
   *  seen side) already ignores it (the tracker option distance.reciprocal), so a hole no longer
   *  pulls its vertices onto its rim; a cut-off of about 3 voxels (the voxel is the template's
   *  diagonal / 200 unless Voxel Size says otherwise) does the same for every far vertex.
   *  (distance.outlierDistance; range [0, inf], world units) */
  void SetOutlierDistance(double value) { this->SetTrackerOption("OutlierDistance", value); }
  double GetOutlierDistance() { return this->GetTrackerOption("OutlierDistance"); }
  ///@}
  ///@{
  /** Weight of the points-to-mesh term: a well-spread sample of the points pulls the closest
   *  point of the mesh (only where normals agree, so another limb does not pull). Without it (0,
   *  the paper's energy) a limb the mesh lets go of costs nothing and is lost. (coverage.weight;
   *  range [0, inf]) */
  void SetCoverageWeight(double value) { this->SetTrackerOption("CoverageWeight", value); }
  double GetCoverageWeight() { return this->GetTrackerOption("CoverageWeight"); }
  ///@}
  ///@{
  /** Pulls vertices toward their constant-velocity course: smoother motion on shaky data, at the
   *  price of lag behind sudden motion. 0: off (default). About 1 suits slow, non-rigid motion
   *  (cloth, a collapse: half the shake); it pulls fast motion such as a jumping human off its
   *  changes of direction. (temporalWeight; range [0, inf]) */
  void SetTemporalWeight(double value) { this->SetTrackerOption("TemporalWeight", value); }
  double GetTemporalWeight() { return this->GetTrackerOption("TemporalWeight"); }
  ///@}
  ///@{
  /** Where the points carry colour (RGB, RGBA or Colors bytes): each vertex is pulled, along the
   *  surface, to where the frame shows the colour its material point had in the first frame.
   *  Geometry says where the surface is, not where on it a vertex lies; colour keeps each vertex
   *  on its material point (textures do not swim). The output then carries Colors, the frame's
   *  colour at each vertex. 0: off. (colourWeight; range [0, inf]) */
  void SetColourWeight(double value) { this->SetTrackerOption("ColourWeight", value); }
  double GetColourWeight() { return this->GetTrackerOption("ColourWeight"); }
  ///@}
  ///@{
  /** Resolution of each frame's distance field (world units). 0: the template's diagonal / 200.
   *  (voxelSize; range [0, inf], world units) */
  void SetVoxelSize(double value) { this->SetTrackerOption("VoxelSize", value); }
  double GetVoxelSize() { return this->GetTrackerOption("VoxelSize"); }
  ///@}
  ///@{
  /** Band of the distance field around the points (world units). 0: 4 voxels. (bandWidth; range
   *  [0, inf], world units) */
  void SetBandWidth(double value) { this->SetTrackerOption("BandWidth", value); }
  double GetBandWidth() { return this->GetTrackerOption("BandWidth"); }
  ///@}
  ///@{
  /** Where the frames are meshes (a capture's per-frame meshes), each is read as its surface:
   *  this many points spread evenly over its area, with normals from its faces and colours from
   *  its vertices, or one a vertex when the mesh has more vertices. Sparse and dense parts of a
   *  capture mesh then weigh alike, and the surface between vertices is data. 0: the frame's
   *  vertices alone, as points. (meshFrameSamples; range [0, 1000000000]) */
  void SetMeshFrameSamples(int value) { this->SetTrackerOption("MeshFrameSamples", value); }
  int GetMeshFrameSamples() { return static_cast<int>(this->GetTrackerOption("MeshFrameSamples")); }
  ///@}
  ///@{
  /** The minimiser of the same energy: damped Gauss-Newton (default, fastest to converge),
   *  L-BFGS, or the paper's steepest descent with step 1.9 / k_max. (solver; range
   *  gauss-newton|lbfgs|steepest-descent) */
  void SetSolver(int value) { this->SetTrackerOption("Solver", value); }
  int GetSolver() { return static_cast<int>(this->GetTrackerOption("Solver")); }
  ///@}
  ///@{
  /** Start each frame at the minimum of the energy along the linear and quadratic extrapolations
   *  of the trajectories (the paper's MP). (motionPrediction; range true|false) */
  void SetMotionPrediction(vtkTypeBool value) { this->SetTrackerOption("MotionPrediction", value); }
  vtkTypeBool GetMotionPrediction() { return static_cast<vtkTypeBool>(this->GetTrackerOption("MotionPrediction")); }
  vtkBooleanMacro(MotionPrediction, vtkTypeBool);
  ///@}
  ///@{
  /** Without the coarse level: before deforming, move the predicted mesh rigidly onto the frame's
   *  points (point-to-plane alignment weighted by vertex area). Keeps a turning shape from
   *  slipping along its surface a little more each frame. (rigidAlignment; range true|false) */
  void SetRigidAlignment(vtkTypeBool value) { this->SetTrackerOption("RigidAlignment", value); }
  vtkTypeBool GetRigidAlignment() { return static_cast<vtkTypeBool>(this->GetTrackerOption("RigidAlignment")); }
  vtkBooleanMacro(RigidAlignment, vtkTypeBool);
  ///@}
  ///@{
  /** Steepest descent only: freeze vertices that barely move until a neighbour moves (the paper's
   *  PD). (provisionalDetermination; range true|false) */
  void SetProvisionalDetermination(vtkTypeBool value) { this->SetTrackerOption("ProvisionalDetermination", value); }
  vtkTypeBool GetProvisionalDetermination() { return static_cast<vtkTypeBool>(this->GetTrackerOption("ProvisionalDetermination")); }
  vtkBooleanMacro(ProvisionalDetermination, vtkTypeBool);
  ///@}
  ///@{
  /** Iteration limit of a frame's cloth solve (with the coarse level on, Gauss-Newton takes at
   *  most FineIterations). (maxIterations; range [1, 1000000]) */
  void SetMaximumIterations(int value) { this->SetTrackerOption("MaximumIterations", value); }
  int GetMaximumIterations() { return static_cast<int>(this->GetTrackerOption("MaximumIterations")); }
  ///@}
  ///@{
  /** Relative energy decrease under which a frame's minimisation stops. (tolerance; range [1e-15,
   *  1]) */
  void SetTolerance(double value) { this->SetTrackerOption("Tolerance", value); }
  double GetTolerance() { return this->GetTrackerOption("Tolerance"); }
  ///@}
  ///@{
  /** Register an embedded deformation graph (nodes spread over the template, a rotation and a
   *  translation each) to every frame before the cloth solve, from stiff and far-reaching to
   *  supple and local: large and fast motions are caught as whole limbs. Off: the paper's start
   *  (motion prediction, then rigid alignment). (graph.enabled; range true|false) */
  void SetCoarseLevel(vtkTypeBool value) { this->SetTrackerOption("CoarseLevel", value); }
  vtkTypeBool GetCoarseLevel() { return static_cast<vtkTypeBool>(this->GetTrackerOption("CoarseLevel")); }
  vtkBooleanMacro(CoarseLevel, vtkTypeBool);
  ///@}
  ///@{
  /** Nodes of the coarse level's graph. 0: one per 5 template vertices, 30 to 600. (graph.nodes;
   *  range [0, 10000000]) */
  void SetGraphNodes(int value) { this->SetTrackerOption("GraphNodes", value); }
  int GetGraphNodes() { return static_cast<int>(this->GetTrackerOption("GraphNodes")); }
  ///@}
  ///@{
  /** Multiplies the coarse level's rigidity: larger keeps parts stiffer (robust to noise and
   *  holes), smaller lets the graph bend more freely. (graph.rigidity; range [0, inf]) */
  void SetGraphRigidity(double value) { this->SetTrackerOption("GraphRigidity", value); }
  double GetGraphRigidity() { return this->GetTrackerOption("GraphRigidity"); }
  ///@}
  ///@{
  /** Where the shape stays bent far from the template (a collapse, cloth), the coarse level's
   *  reference gives way by this share per frame, so lasting deformation is not pulled back. 0:
   *  always measured against the template. (graph.yieldRate; range [0, 1]) */
  void SetPlasticity(double value) { this->SetTrackerOption("Plasticity", value); }
  double GetPlasticity() { return this->GetTrackerOption("Plasticity"); }
  ///@}
  ///@{
  /** Gauss-Newton steps of the cloth solve after the coarse level (at most). The graph has placed
   *  the surface and a few steps fit its detail; more let vertices slide along the data and end
   *  farther from where they belong (and take longer). (graph.fineIterations; range [1, 1000000]) */
  void SetFineIterations(int value) { this->SetTrackerOption("FineIterations", value); }
  int GetFineIterations() { return static_cast<int>(this->GetTrackerOption("FineIterations")); }
  ///@}
  ///@{
  /** Detect frames that failed (more points far from the mesh than usual in the take, or a limb
   *  torn: caught by another limb's data, its edges stretched by more than two edge lengths,
   *  LargestStretch) and try them again: held stiffer, from the last frame and from the template;
   *  the best attempt is kept and flagged in Failed if it still fails. Mesh far from the points
   *  (Unsupported: holes in the data) is no failure by itself. (recovery.enabled; range
   *  true|false) */
  void SetRecovery(vtkTypeBool value) { this->SetTrackerOption("Recovery", value); }
  vtkTypeBool GetRecovery() { return static_cast<vtkTypeBool>(this->GetTrackerOption("Recovery")); }
  vtkBooleanMacro(Recovery, vtkTypeBool);
  ///@}
  ///@{
  /** A frame fails when its share of unexplained points (or of mesh the solve took off its
   *  points) exceeds the median of the last frames by more than this share (0.003 = 0.3 %). Mesh
   *  over a hole in the points is no failure. (recovery.margin; range [0, 1]) */
  void SetFailureMargin(double value) { this->SetTrackerOption("FailureMargin", value); }
  double GetFailureMargin() { return this->GetTrackerOption("FailureMargin"); }
  ///@}
  // clang-format on
  // END generated options

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
