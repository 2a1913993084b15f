// SPDX-License-Identifier: BSD-3-Clause
#include "dp/track/TrackerOptionTable.h"

#include <stdexcept>
#include <string>

namespace dp
{

namespace
{

using Row = OptionDescription<TrackerOptions>;
using Panel = OptionPanel;
using Rows = OptionRows<TrackerOptions>;
constexpr auto real = [](auto&&... a) { return Rows::real(a...); };
constexpr auto integer = [](auto&&... a) { return Rows::integer(a...); };
constexpr auto flag = [](auto&&... a) { return Rows::flag(a...); };
constexpr auto automatic = [](Row row) { return Rows::automatic(std::move(row)); };

Row solverRow()
{
  return Rows::choice(
             "solver", "Solver", OptionPanel::Shown, {"gauss-newton", "lbfgs", "steepest-descent"},
             "the fine level's minimiser: Gauss-Newton, L-BFGS or the paper's steepest descent",
             [](auto& o) -> auto& { return o.solver; })
      .withChoiceLabels({"Gauss-Newton", "L-BFGS", "Steepest descent (paper)"})
      .withHelp("The minimiser of the same energy: damped Gauss-Newton (default, fastest to "
                "converge), L-BFGS, or the paper's steepest descent with step 1.9 / k_max.");
}

Row measureRow()
{
  Row row =
      Rows::choice(
          "distance.measure", "DistanceMeasure", OptionPanel::Advanced, {"planes", "points"},
          "what the distance term measures: the distance to the tangent planes of the nearest "
          "points (vertices may slide along the data) or to the points (the paper)",
          [](auto& o) -> auto& { return o.distance.measure; })
          .withChoiceLabels({"Tangent planes", "Points (paper)"})
          .withHelp("What the distance term measures: the distance to the tangent planes of the "
                    "nearest data points (the mesh can slide along the data), or to the points "
                    "themselves as in the paper.");
  // The property's values are planes 0, points 1 (the enum's are the other way round).
  row.get = [](const TrackerOptions& o)
  { return o.distance.measure == DistanceMeasure::Points ? 1.0 : 0.0; };
  row.set = [](TrackerOptions& o, double v)
  { o.distance.measure = v == 1 ? DistanceMeasure::Points : DistanceMeasure::Planes; };
  return row;
}

// The cloth energy's stiffnesses (k_st, k_sh, k_ben).
std::vector<Row> clothStiffnessRows()
{
  return {
      real(
          "cloth.stretch", "StretchStiffness", Panel::Shown, 0, Unbounded, "",
          "k_st: the cloth's stiffness against stretch",
          [](auto& o) -> auto& { return o.cloth.stretch; })
          .withHelp("Resistance to changes of edge length (dimensionless, constant per edge)."),
      real(
          "cloth.shear", "ShearStiffness", Panel::Shown, 0, Unbounded, "",
          "k_sh: against the change of the triangles' corner angles (0: edges alone)",
          [](auto& o) -> auto& { return o.cloth.shear; })
          .withHelp("Resistance to changes of the corner angles of triangles. Off by default: edge "
                    "lengths alone hold the in-plane shape of a well-shaped mesh, and track more "
                    "accurately. Set it (e.g. 0.05) for a template with slivers (nearly flat "
                    "triangles); the filter warns when it sees them."),
      real(
          "cloth.bend", "BendStiffness", Panel::Shown, 0, Unbounded, "",
          "k_ben: against bending across edges", [](auto& o) -> auto& { return o.cloth.bend; })
          .withHelp("Resistance to bending (changes of the angle between neighbouring triangles), "
                    "weighted by area so that it does not depend on the mesh resolution."),
  };
}

// Softer stretch and bending on the template's thick parts (ThicknessSoftening).
std::vector<Row> thickPartRows()
{
  return {
      real(
          "softening.stretch", "ThickPartStretch", Panel::Advanced, 0, 1, "",
          "factor on the stretch stiffness of thick parts (a trunk: its skin slides); 1: off",
          [](auto& o) -> auto& { return o.softening.stretch; })
          .withHelp("Factor on the stretch stiffness where the template is thick (a trunk, as "
                    "measured by its inner medial balls; limbs keep the full stiffness). The "
                    "default 0.3 lets a body's skin stretch and slide over the torso as it bends (a"
                    " captured human: 30.9 to 26.6 mm vertex error with a reconstructed template). "
                    "1 is one stiffness everywhere: better for slow motion far from isometric, such"
                    " as a collapse or cloth."),
      real(
          "softening.bend", "", Panel::None, 0, 1, "",
          "factor on the bending stiffness of thick parts; 1: off",
          [](auto& o) -> auto& { return o.softening.bend; }),
      real(
          "softening.from", "", Panel::None, 0, Unbounded, "",
          "inner medial radius (over the template's 90th percentile) where softening starts",
          [](auto& o) -> auto& { return o.softening.from; }),
      real(
          "softening.to", "", Panel::None, 0, Unbounded, "",
          "inner medial radius where softening is whole (above `from`)",
          [](auto& o) -> auto& { return o.softening.to; }),
  };
}

// Softer stretch in the template's creases (CreaseSoftening).
std::vector<Row> creaseRows()
{
  return {
      real(
          "creases.stretch", "CreaseStretch", Panel::Advanced, 0, 1, "",
          "factor on the stretch stiffness in the template's creases (armpits, crotch); 1: off",
          [](auto& o) -> auto& { return o.creases.stretch; })
          .withHelp("Factor on the stretch stiffness in the template's creases: where the space in "
                    "front of the surface is narrow (armpits, crotch, an arm that touches the body "
                    "in the template and was reconstructed joined to it). Soft, those bridges "
                    "stretch as the parts move apart instead of dragging the torso's skin along "
                    "with the arm (reconstructed human: 34 to 29 mm vertex error). 1 is one "
                    "stiffness everywhere."),
      real(
          "creases.width", "", Panel::None, 0, Unbounded, "",
          "outer medial radius, over the template's thickness, below which a vertex is in a crease",
          [](auto& o) -> auto& { return o.creases.width; }),
  };
}

// The cloth's rest state: the template, or a blend with the last frame.
std::vector<Row> restStateRows()
{
  return {
      real(
          "restUpdate", "RestUpdate", Panel::Advanced, 0, 1, "",
          "share of the last frame in the cloth's rest state (0: the template, the paper)",
          [](auto& o) -> auto& { return o.restUpdate; })
          .withHelp("Share of the previous frame in the rest shape of the deformation energy: 0 "
                    "keeps the template (the paper); larger values let the mesh follow shapes far "
                    "from the template."),
  };
}

// The mesh -> points term (DistanceTerm).
std::vector<Row> distanceRows()
{
  return {
      real(
          "distance.weight", "DistanceWeight", Panel::Shown, 0, Unbounded, "",
          "k_dis: the weight of the mesh -> points term",
          [](auto& o) -> auto& { return o.distance.weight; })
          .withHelp("Weight of the distance-to-data term (dimensionless)."),
      measureRow(),
      flag(
          "distance.squared", "SquaredDistance", Panel::Advanced,
          "penalise D^2 / (2 voxel), smooth at the data; off: the paper's D",
          [](auto& o) -> auto& { return o.distance.squared; })
          .withHelp("Penalise the squared distance (smooth at the data; default) instead of the "
                    "distance itself (the paper)."),
      real(
          "distance.normalTestDegrees", "NormalTestAngle", Panel::Advanced, 0, 180, "degrees",
          "a vertex's distance term drops where its normal and its data's differ by more; 180: "
          "no test",
          [](auto& o) -> auto& { return o.distance.normalTestDegrees; })
          .withHelp("A vertex ignores the data when its normal and the normal of its nearest point "
                    "differ by more than this angle in degrees (keeps surfaces from snapping to the"
                    " wrong side, e.g. between legs). 180 switches the test off."),
      real(
          "distance.outlierDistance", "OutlierDistance", Panel::Advanced, 0, Unbounded,
          "world units", "a vertex farther than this from the data has no distance term; 0: none",
          [](auto& o) -> auto& { return o.distance.outlierDistance; })
          .withHelp("Vertices farther than this from the data (world units) ignore it. 0: no "
                    "cut-off. By default a vertex whose nearest point another part of the mesh is "
                    "nearer to (a hole's rim, a body's seen side) already ignores it (the tracker "
                    "option distance.reciprocal), so a hole no longer pulls its vertices onto its "
                    "rim; a cut-off of about 3 voxels (the voxel is the template's diagonal / 200 "
                    "unless Voxel Size says otherwise) does the same for every far vertex."),
      real(
          "distance.robustScale", "", Panel::None, 0, Unbounded, "world units",
          "Geman-McClure scale of the distance term; 0: plain least squares",
          [](auto& o) -> auto& { return o.distance.robustScale; }),
      flag(
          "distance.reciprocal", "", Panel::None,
          "a vertex's distance term drops where another part of the mesh is nearer to its "
          "nearest point by more than two voxels (data seen from one side, holes)",
          [](auto& o) -> auto& { return o.distance.reciprocal; }),
  };
}

// The points -> mesh term (CoverageTerm).
std::vector<Row> coverageTermRows()
{
  return {
      real(
          "coverage.weight", "CoverageWeight", Panel::Shown, 0, Unbounded, "",
          "k_cov: the weight of the points -> mesh term (0: the paper's energy alone)",
          [](auto& o) -> auto& { return o.coverage.weight; })
          .withHelp("Weight of the points-to-mesh term: a well-spread sample of the points pulls "
                    "the closest point of the mesh (only where normals agree, so another limb does "
                    "not pull). Without it (0, the paper's energy) a limb the mesh lets go of costs"
                    " nothing and is lost."),
      real(
          "coverage.pointToPoint", "", Panel::None, 0, 1, "",
          "share of the point-to-point distance in the points -> mesh term",
          [](auto& o) -> auto& { return o.coverage.pointToPoint; }),
      real(
          "coverage.normalTestDegrees", "", Panel::None, 0, 180, "degrees",
          "a point pulls only mesh whose normal is within this angle of its own; 180: no test",
          [](auto& o) -> auto& { return o.coverage.normalTestDegrees; }),
      real(
          "coverage.robustScale", "", Panel::None, 0, Unbounded, "world units",
          "Geman-McClure scale of the points -> mesh term; 0: plain least squares",
          [](auto& o) -> auto& { return o.coverage.robustScale; }),
      real(
          "coverage.maxDistance", "", Panel::None, 0, Unbounded, "world units",
          "points farther than this from the mesh do not pull; 0: no cut-off",
          [](auto& o) -> auto& { return o.coverage.maxDistance; }),
      integer(
          "coverage.points", "", Panel::None, 0, 1e9,
          "size of the well-spread subsample that pulls; 0: 4 per vertex",
          [](auto& o) -> auto& { return o.coverage.points; }),
      flag(
          "coverage.followMatches", "", Panel::None,
          "within a solve, each point's match follows the surface instead of a new search",
          [](auto& o) -> auto& { return o.coverage.followMatches; }),
  };
}

// The pull toward the constant-velocity course (TemporalTerm).
std::vector<Row> temporalRows()
{
  return {
      real(
          "temporalWeight", "TemporalWeight", Panel::Advanced, 0, Unbounded, "",
          "k_acc: pull toward the constant-velocity course (smoother, lags fast motion); 0: off",
          [](auto& o) -> auto& { return o.temporalWeight; })
          .withHelp("Pulls vertices toward their constant-velocity course: smoother motion on shaky"
                    " data, at the price of lag behind sudden motion. 0: off (default). About 1 "
                    "suits slow, non-rigid motion (cloth, a collapse: half the shake); it pulls "
                    "fast motion such as a jumping human off its changes of direction."),
  };
}

// The colour term (ColourTerm).
std::vector<Row> colourRows()
{
  return {
      real(
          "colourWeight", "ColourWeight", Panel::Shown, 0, Unbounded, "",
          "k_col: where points carry colour, pull each vertex along the surface to its material "
          "point's colour; 0: off",
          [](auto& o) -> auto& { return o.colourWeight; })
          .withHelp("Where the points carry colour (RGB, RGBA or Colors bytes): each vertex is "
                    "pulled, along the surface, to where the frame shows the colour its material "
                    "point had in the first frame. Geometry says where the surface is, not where on"
                    " it a vertex lies; colour keeps each vertex on its material point (textures do"
                    " not swim). The output then carries Colors, the frame's colour at each vertex."
                    " 0: off."),
      real(
          "colourCoarseKernel", "", Panel::None, 1, 100, "",
          "the colour term's kernel on the coarse level, in times the fine level's",
          [](auto& o) -> auto& { return o.colourCoarseKernel; }),
  };
}

// A frame's data: the distance field, thinning, a mesh frame's samples.
std::vector<Row> frameDataRows()
{
  return {
      real(
          "voxelSize", "VoxelSize", Panel::Advanced, 0, Unbounded, "world units",
          "the distance field's voxel; 0: the template's diagonal / 200",
          [](auto& o) -> auto& { return o.voxelSize; })
          .withHelp("Resolution of each frame's distance field (world units). 0: the template's "
                    "diagonal / 200."),
      real(
          "bandWidth", "BandWidth", Panel::Advanced, 0, Unbounded, "world units",
          "the distance field's narrow band; 0: 4 voxels",
          [](auto& o) -> auto& { return o.bandWidth; })
          .withHelp("Band of the distance field around the points (world units). 0: 4 voxels."),
      automatic(integer(
          "maxFramePoints", "", Panel::None, 100, 1e12,
          "a frame of more points is thinned evenly to this many; 0: no limit",
          [](auto& o) -> auto& { return o.maxFramePoints; })),
      integer(
          "meshFrameSamples", "MeshFrameSamples", Panel::Advanced, 0, 1e9,
          "a frame that is a mesh is read as this many points spread evenly over its area, with "
          "its faces' normals (or one a vertex, if it has more vertices); 0: its vertices alone",
          [](auto& o) -> auto& { return o.meshFrameSamples; })
          .withHelp("Where the frames are meshes (a capture's per-frame meshes), each is read as "
                    "its surface: this many points spread evenly over its area, with normals from "
                    "its faces and colours from its vertices, or one a vertex when the mesh has "
                    "more vertices. Sparse and dense parts of a capture mesh then weigh alike, and "
                    "the surface between vertices is data. 0: the frame's vertices alone, as "
                    "points."),
  };
}

// The fine level's minimiser and, without the coarse level, the paper's start and PD.
std::vector<Row> fineLevelRows()
{
  return {
      solverRow(),
      flag(
          "motionPrediction", "MotionPrediction", Panel::Advanced,
          "start each frame from the last frames' motion continued (the paper's MP)",
          [](auto& o) -> auto& { return o.motionPrediction; })
          .withHelp("Start each frame at the minimum of the energy along the linear and quadratic "
                    "extrapolations of the trajectories (the paper's MP)."),
      flag(
          "rigidAlignment", "RigidAlignment", Panel::Advanced,
          "without the coarse level: align the start rigidly to the data first",
          [](auto& o) -> auto& { return o.rigidAlignment; })
          .withHelp("Without the coarse level: before deforming, move the predicted mesh rigidly "
                    "onto the frame's points (point-to-plane alignment weighted by vertex area). "
                    "Keeps a turning shape from slipping along its surface a little more each "
                    "frame.")
          .shownWith("CoarseLevel=0"),
      flag(
          "provisionalDetermination", "ProvisionalDetermination", Panel::Advanced,
          "steepest descent only: fix vertices that have settled (the paper's PD)",
          [](auto& o) -> auto& { return o.provisionalDetermination; })
          .withHelp("Steepest descent only: freeze vertices that barely move until a neighbour "
                    "moves (the paper's PD).")
          .shownWith("Solver=2"),
  };
}

// When a solve ends.
std::vector<Row> solveLimitRows()
{
  return {
      integer(
          "maxIterations", "MaximumIterations", Panel::Advanced, 1, 1e6,
          "iteration limit of the fine level's solve (without the coarse level)",
          [](auto& o) -> auto& { return o.maxIterations; })
          .withHelp("Iteration limit of a frame's cloth solve (with the coarse level on, "
                    "Gauss-Newton takes at most FineIterations)."),
      real(
          "tolerance", "Tolerance", Panel::Advanced, 1e-15, 1, "",
          "relative energy decrease that ends a solve",
          [](auto& o) -> auto& { return o.tolerance; })
          .withHelp("Relative energy decrease under which a frame's minimisation stops."),
  };
}

// The coarse level's deformation graph: on or off, its nodes and their blending.
std::vector<Row> graphShapeRows()
{
  return {
      flag(
          "graph.enabled", "CoarseLevel", Panel::Shown,
          "register an embedded deformation graph first: fast motion caught as whole limbs",
          [](auto& o) -> auto& { return o.graph.enabled; })
          .withHelp("Register an embedded deformation graph (nodes spread over the template, a "
                    "rotation and a translation each) to every frame before the cloth solve, from "
                    "stiff and far-reaching to supple and local: large and fast motions are caught "
                    "as whole limbs. Off: the paper's start (motion prediction, then rigid "
                    "alignment)."),
      integer(
          "graph.nodes", "GraphNodes", Panel::Advanced, 0, 1e7,
          "the graph's node count; 0: one per 5 vertices, 30 to 600",
          [](auto& o) -> auto& { return o.graph.nodes; })
          .withHelp("Nodes of the coarse level's graph. 0: one per 5 template vertices, 30 to 600.")
          .shownWith("CoarseLevel=1"),
      integer(
          "graph.influences", "", Panel::None, 1, 16, "nodes blended per vertex",
          [](auto& o) -> auto& { return o.graph.influences; }),
  };
}

// How stiff the graph is: its regulariser, plasticity and stretch term.
std::vector<Row> graphStiffnessRows()
{
  return {
      real(
          "graph.rigidity", "GraphRigidity", Panel::Advanced, 0, Unbounded, "",
          "factor on the graph's regularisation weights",
          [](auto& o) -> auto& { return o.graph.rigidity; })
          .withHelp("Multiplies the coarse level's rigidity: larger keeps parts stiffer (robust to "
                    "noise and holes), smaller lets the graph bend more freely.")
          .shownWith("CoarseLevel=1"),
      real(
          "graph.robustScale", "", Panel::None, 0, Unbounded, "voxels",
          "Huber scale of the graph's regulariser: edges bending more cost in proportion",
          [](auto& o) -> auto& { return o.graph.robustScale; }),
      real(
          "graph.yieldRate", "Plasticity", Panel::Advanced, 0, 1, "",
          "share of a lasting bend the graph's reference yields each frame; 0: off",
          [](auto& o) -> auto& { return o.graph.yieldRate; })
          .withHelp("Where the shape stays bent far from the template (a collapse, cloth), the "
                    "coarse level's reference gives way by this share per frame, so lasting "
                    "deformation is not pulled back. 0: always measured against the template.")
          .shownWith("CoarseLevel=1"),
      real(
          "graph.yieldLimit", "", Panel::None, 0, Unbounded, "voxels",
          "bend of a graph edge below which its reference does not yield",
          [](auto& o) -> auto& { return o.graph.yieldLimit; }),
      real(
          "graph.stretchWeight", "", Panel::None, 0, Unbounded, "",
          "weight of the graph's stretch term against its bending term; 0: off",
          [](auto& o) -> auto& { return o.graph.stretchWeight; }),
  };
}

// The coarse level's steps and the fine steps after it.
std::vector<Row> graphStepRows()
{
  return {
      integer(
          "graph.iterations", "", Panel::None, 0, 1000,
          "Levenberg-Marquardt steps per stage of the coarse level (at most)",
          [](auto& o) -> auto& { return o.graph.iterations; }),
      integer(
          "graph.fineIterations", "FineIterations", Panel::Advanced, 1, 1e6,
          "Gauss-Newton steps of the fine level after the coarse level (at most)",
          [](auto& o) -> auto& { return o.graph.fineIterations; })
          .withHelp("Gauss-Newton steps of the cloth solve after the coarse level (at most). The "
                    "graph has placed the surface and a few steps fit its detail; more let vertices"
                    " slide along the data and end farther from where they belong (and take "
                    "longer).")
          .shownWith("CoarseLevel=1"),
      integer(
          "graph.acceleration", "", Panel::None, 0, 20,
          "earlier steps Anderson acceleration combines; 0: plain steps",
          [](auto& o) -> auto& { return o.graph.acceleration; }),
  };
}

// Which frames fail: the recovery switch, the reach and the margin.
std::vector<Row> failureRows()
{
  return {
      flag(
          "recovery.enabled", "Recovery", Panel::Shown,
          "try a frame that failed again from other starts, keep the best, flag it if it fails",
          [](auto& o) -> auto& { return o.recovery.enabled; })
          .withHelp("Detect frames that failed (more points far from the mesh than usual in the "
                    "take, or a limb torn: caught by another limb's data, its edges stretched by "
                    "more than two edge lengths, LargestStretch) and try them again: held stiffer, "
                    "from the last frame and from the template; the best attempt is kept and "
                    "flagged in Failed if it still fails. Mesh far from the points (Unsupported: "
                    "holes in the data) is no failure by itself."),
      real(
          "recovery.reach", "", Panel::None, 1e-3, 1e3, "voxels",
          "data farther than this from the mesh is unexplained (and mesh from the data, "
          "unsupported)",
          [](auto& o) -> auto& { return o.recovery.reach; }),
      real(
          "recovery.margin", "FailureMargin", Panel::Advanced, 0, 1, "",
          "share of unexplained data beyond the take's usual that fails a frame",
          [](auto& o) -> auto& { return o.recovery.margin; })
          .withHelp("A frame fails when its share of unexplained points (or of mesh the solve took "
                    "off its points) exceeds the median of the last frames by more than this share "
                    "(0.003 = 0.3 %). Mesh over a hole in the points is no failure.")
          .shownWith("Recovery=1"),
  };
}

// The retries of a frame that failed: stiffer, regrown, and which one is kept.
std::vector<Row> retryRows()
{
  return {
      flag(
          "recovery.stiffRetry", "", Panel::None,
          "a frame with a torn limb is tried again with the coarse level's limbs stiffer",
          [](auto& o) -> auto& { return o.recovery.stiffRetry; }),
      flag(
          "recovery.regrow", "", Panel::None,
          "a frame that lost a part is tried again with that part moved onto the points it left "
          "(a limb moved beyond the coarse level's reach)",
          [](auto& o) -> auto& { return o.recovery.regrow; }),
      real(
          "recovery.tearGrowth", "", Panel::None, 0, Unbounded, "mean edge lengths",
          "a stiff edge grown beyond its template length by more than this: a torn limb",
          [](auto& o) -> auto& { return o.recovery.tearGrowth; }),
      real(
          "recovery.stiffening", "", Panel::None, 1, 100, "",
          "the stiff retry's factor on the coarse rigidity (its square on the stretch weight)",
          [](auto& o) -> auto& { return o.recovery.stiffening; }),
      real(
          "recovery.retryShare", "", Panel::None, 0, 1, "",
          "a retry is kept only with a score below this share of the best attempt's",
          [](auto& o) -> auto& { return o.recovery.retryShare; }),
  };
}

// The take's usual quality that a frame is judged against.
std::vector<Row> baselineRows()
{
  return {
      integer(
          "recovery.window", "", Panel::None, 1, 1000,
          "the last frames kept whose median quality is the take's usual",
          [](auto& o) -> auto& { return o.recovery.window; }),
      integer(
          "recovery.persistentFailures", "", Panel::None, 1, 1000,
          "frames in doubt in a row after which their quality becomes the usual",
          [](auto& o) -> auto& { return o.recovery.persistentFailures; }),
  };
}

std::vector<Row> makeTable()
{
  std::vector<Row> rows;
  for (auto group :
       {clothStiffnessRows, thickPartRows, creaseRows, restStateRows, distanceRows,
        coverageTermRows, temporalRows, colourRows, frameDataRows, fineLevelRows, solveLimitRows,
        graphShapeRows, graphStiffnessRows, graphStepRows, failureRows, retryRows, baselineRows})
    for (Row& row : group())
      rows.push_back(std::move(row));
  return rows;
}

} // namespace

const OptionTable<TrackerOptions>& trackerOptions()
{
  static const OptionTable<TrackerOptions> table("tracker option", makeTable());
  return table;
}

void checkTrackerOptions(const TrackerOptions& options)
{
  trackerOptions().check(options);
  if (!(options.softening.to > options.softening.from))
    throw std::invalid_argument("tracker options softening.from and softening.to: from (" +
                                std::to_string(options.softening.from) + ") must be below to (" +
                                std::to_string(options.softening.to) + ")");
}

} // namespace dp
