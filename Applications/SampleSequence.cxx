// SPDX-License-Identifier: BSD-3-Clause
// dynamicpoints-sample: make a synthetic point sequence from an animated mesh, the way the
// paper made its CG experiments (random surface samples per frame, noise, holes).
#include "CommandLine.h"
#include "PerFrameMesh.h"

#include "dp/geometry/BoundingBox.h"
#include "dp/geometry/DepthRig.h"
#include "dp/geometry/SurfaceSampler.h"
#include "dp/io/AnimatedMesh.h"
#include "dp/io/FrameSequence.h"

#include <cstdio>
#include <iostream>
#include <memory>

namespace
{

const char* const Usage = R"(Usage: dynamicpoints-sample [OPTIONS] OUTPUT_FOLDER

Samples random points on every frame of an animated mesh and writes one point file per
frame plus OUTPUT_FOLDER/points.series, ready for vtkPointSequenceSource.

Animated mesh (one of):
  --mesh tube           a bending, twisting, capped tube (default; built in)
  --mesh sheet          a waving sheet with an open boundary (built in)
  --mesh FOLDER         one mesh file per frame with the same connectivity (PLY/OBJ)
  --pattern GLOB        files of FOLDER to use (default: *)
  --frames N            number of frames of a built-in mesh (default 30)

Sampling:
  --points N            samples per frame before holes are cut (default 20000)
  --seed N              random seed; the same seed gives the same files (default 1)
  --noise S             Gaussian noise, standard deviation as a fraction of the bounding-box
                        diagonal of frame 0 (default 0)
  --holes N             holes per frame (default 0)
  --hole-radius R       hole radius as a fraction of the diagonal (default 0.05)
  --moving-holes        draw new hole positions in every frame (default: fixed on the surface)
  --no-normals          do not write normals
  --colour              colour every point by a pattern fixed to the material (the same
                        colour for the same material point in every frame: red, green and
                        blue waves over the first frame's shape)

Depth cameras (as depth-camera rigs and single-sensor tools capture; colour and normals always):
  --rig N               render every frame through N simulated depth cameras around the
                        subject (1: a single sensor) with a real sensor's resolution, field of
                        view, depth noise growing with distance and incidence, depth steps,
                        flying pixels at silhouettes, no return at grazing angles, and each
                        camera's pose off by a small error; writes the fused cloud per frame
                        (or with --depth-mesh each camera's open mesh) and rig.json
  --sensor NAME         kinect-v1, kinect-v2 (default), azure-kinect, d415 or d435
  --subject-height M    the subject's extent along --up in frame 0, in metres (default 1.7):
                        the scale of the sensor's noise
  --up AXIS             the subject's up axis: x, y (default), z, -x, -y or -z
  --rig-distance M      cameras' distance from the take's centre in metres (default: where
                        the whole take fills the view)
  --azimuth DEG         camera 0's side of the subject around --up (default 0)
  --rotation-error DEG  each camera's pose error, per axis (default 0.1)
  --translation-error M each camera's position error, per axis, in metres (default 0.002)
  --floor               a floor under the subject, its patch seen where the cameras reach
  --depth-mesh          write each camera's depth image triangulated into an open mesh (one
                        camera: in OUTPUT_FOLDER; more: OUTPUT_FOLDER/camera_K/)
  --points N            with --rig: thin the fused cloud to about N points a frame (default:
                        every point)

Per-frame meshes (as volumetric-video studios publish them):
  --per-frame-mesh N    write each frame as a mesh of about N vertices reconstructed from
                        its samples: its own connectivity every frame, the samples' colours
                        carried to the nearest vertex
  --mesh-defects        give frame 0's mesh what marching cubes and exporters leave:
                        duplicate vertices, triangles without area, a small stray part

Output:
  --format EXT          ply (binary, default), pcd, xyz, csv, obj or drc (Draco)
  --interval T          time between frames in points.series (default 1)
  --truth               also write the true mesh of each frame to OUTPUT_FOLDER/truth/
  -h, --help            show this help
)";

dp::RigOptions noRig()
{
  dp::RigOptions rig;
  rig.cameras = 0;
  return rig;
}

// What to sample and how; noise and hole radius are shares of the mesh's diagonal.
struct Request
{
  std::string mesh = "tube", pattern = "*", output;
  std::size_t frames = 30;
  dp::SamplerOptions sampling;
  dp::SequenceWriteOptions writing;
  double noise = 0, holeRadius = 0.05;
  std::size_t meshVertices = 0; // --per-frame-mesh; 0: points
  bool defects = false;
  dp::RigOptions rig = noRig(); // with rig.cameras > 0 (--rig)
  bool depthMesh = false, pointsGiven = false;
  bool help = false;
};

// The depth-camera options; false for another argument.
bool parseRigOption(int argc, char** argv, int& i, Request& r)
{
  using namespace dp::cli;
  const std::string arg = argv[i];
  dp::RigOptions& rig = r.rig;
  if (arg == "--rig")
    rig.cameras = parseCount(arg, optionValue(argc, argv, i), 1, 64);
  else if (arg == "--sensor")
  {
    rig.sensor = optionValue(argc, argv, i);
    try
    {
      dp::depthSensorModel(rig.sensor);
    }
    catch (const std::invalid_argument& e)
    {
      throw UsageError(std::string("option --sensor: ") + e.what());
    }
  }
  else if (arg == "--subject-height")
    rig.subjectHeight = parseDouble(arg, optionValue(argc, argv, i), 1e-3, 1e3);
  else if (arg == "--up")
  {
    rig.up = optionValue(argc, argv, i);
    if (rig.up != "x" && rig.up != "y" && rig.up != "z" && rig.up != "-x" && rig.up != "-y" &&
        rig.up != "-z")
      throw UsageError("option --up: '" + rig.up + "' is not one of x y z -x -y -z");
  }
  else if (arg == "--rig-distance")
    rig.distance = parseDouble(arg, optionValue(argc, argv, i), 0.1, 100);
  else if (arg == "--azimuth")
    rig.azimuth = parseDouble(arg, optionValue(argc, argv, i), -360, 360);
  else if (arg == "--rotation-error")
    rig.rotationError = parseDouble(arg, optionValue(argc, argv, i), 0, 10);
  else if (arg == "--translation-error")
    rig.translationError = parseDouble(arg, optionValue(argc, argv, i), 0, 1);
  else if (arg == "--floor")
    rig.floor = true;
  else if (arg == "--depth-mesh")
    r.depthMesh = true;
  else
    return false;
  return true;
}

// The animated mesh's options and the random sampling's; false for another argument.
bool parseSamplingOption(int argc, char** argv, int& i, Request& r)
{
  using namespace dp::cli;
  const std::string arg = argv[i];
  if (arg == "--mesh")
    r.mesh = optionValue(argc, argv, i);
  else if (arg == "--pattern")
    r.pattern = optionValue(argc, argv, i);
  else if (arg == "--frames")
    r.frames = parseCount(arg, optionValue(argc, argv, i), 1, 100000);
  else if (arg == "--points")
    r.sampling.pointsPerFrame = parseCount(arg, optionValue(argc, argv, i), 1, 100000000),
    r.pointsGiven = true;
  else if (arg == "--seed")
    r.sampling.seed = parseCount(arg, optionValue(argc, argv, i), 0, ~0ULL);
  else if (arg == "--noise")
    r.noise = parseDouble(arg, optionValue(argc, argv, i), 0, 1);
  else if (arg == "--holes")
    r.sampling.holes = parseCount(arg, optionValue(argc, argv, i), 0, 10000);
  else if (arg == "--hole-radius")
    r.holeRadius = parseDouble(arg, optionValue(argc, argv, i), 0, 10);
  else if (arg == "--moving-holes")
    r.sampling.holesMove = true;
  else if (arg == "--colour")
    r.sampling.colours = true;
  else if (arg == "--no-normals")
    r.sampling.normals = false;
  else
    return false;
  return true;
}

// The per-frame meshes' options and the files' (format, interval, truth); false for another
// argument.
bool parseOutputOption(int argc, char** argv, int& i, Request& r)
{
  using namespace dp::cli;
  const std::string arg = argv[i];
  if (arg == "--per-frame-mesh")
    r.meshVertices = parseCount(arg, optionValue(argc, argv, i), 20, 10000000);
  else if (arg == "--mesh-defects")
    r.defects = true;
  else if (arg == "--format")
  {
    r.writing.extension = optionValue(argc, argv, i);
    const std::string& e = r.writing.extension;
    if (e != "ply" && e != "pcd" && e != "xyz" && e != "csv" && e != "obj" && e != "drc")
      throw UsageError("option --format: '" + e + "' is not one of ply pcd xyz csv obj drc");
  }
  else if (arg == "--interval")
    r.writing.frameInterval = parseDouble(arg, optionValue(argc, argv, i), 1e-12, 1e12);
  else if (arg == "--truth")
    r.writing.writeGroundTruth = true;
  else
    return false;
  return true;
}

// Reads the command line; a UsageError for a bad one.
Request parseArguments(int argc, char** argv)
{
  using namespace dp::cli;
  Request r;
  for (int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    if (arg == "-h" || arg == "--help")
    {
      r.help = true;
      return r;
    }
    else if (parseSamplingOption(argc, argv, i, r) || parseRigOption(argc, argv, i, r) ||
             parseOutputOption(argc, argv, i, r))
      continue;
    else if (!arg.empty() && arg[0] == '-')
      throw UsageError("unknown option '" + arg + "'");
    else if (r.output.empty())
      r.output = arg;
    else
      throw UsageError("more than one output folder given ('" + r.output + "', '" + arg + "')");
  }
  if (r.output.empty())
    throw UsageError("no OUTPUT_FOLDER given");
  if (r.rig.cameras == 0 && (r.depthMesh || r.rig.floor))
    throw UsageError("--depth-mesh and --floor need --rig");
  if (r.rig.cameras > 0 && (r.meshVertices > 0 || r.sampling.holes > 0 || r.noise > 0))
    throw UsageError("--rig makes its own noise and holes: it takes no --noise, --holes or "
                     "--per-frame-mesh");
  if (r.rig.cameras > 0 && r.writing.extension != "ply")
    throw UsageError("--rig writes PLY (points with normals and colours, or meshes)");
  return r;
}

// The built-in tube or sheet, or the mesh files of a folder.
std::unique_ptr<dp::AnimatedMesh> animationOf(const Request& r)
{
  if (r.mesh == "tube")
  {
    dp::BendingTube::Options options;
    options.frames = r.frames;
    return std::make_unique<dp::BendingTube>(options);
  }
  if (r.mesh == "sheet")
  {
    dp::WavingSheet::Options options;
    options.frames = r.frames;
    return std::make_unique<dp::WavingSheet>(options);
  }
  return std::make_unique<dp::MeshSequenceFiles>(
      dp::FrameSequence::fromDirectory(r.mesh, r.pattern));
}

int run(int argc, char** argv)
{
  Request r = parseArguments(argc, argv);
  if (r.help)
  {
    std::cout << Usage;
    return 0;
  }
  const std::unique_ptr<dp::AnimatedMesh> animation = animationOf(r);
  if (r.rig.cameras > 0)
  {
    r.rig.seed = r.sampling.seed;
    r.rig.points = r.pointsGiven ? r.sampling.pointsPerFrame : 0;
    const std::string series =
        dp::writeRigSequence(*animation, r.rig, r.output, r.writing, r.depthMesh);
    std::cout << "wrote " << animation->numberOfFrames() << " frames seen by " << r.rig.cameras
              << " simulated " << r.rig.sensor << " camera" << (r.rig.cameras > 1 ? "s" : "")
              << (r.depthMesh ? " as depth meshes" : ", fused,") << " to " << series << "\n";
    return 0;
  }
  const double diagonal = dp::boundingBoxDiagonal(animation->positions(0));
  r.sampling.noiseStdDev = r.noise * diagonal;
  r.sampling.holeRadius = r.holeRadius * diagonal;
  if (r.defects && r.meshVertices == 0)
    throw dp::cli::UsageError("--mesh-defects needs --per-frame-mesh");
  if (r.meshVertices > 0)
    r.writing.transform = [&r](dp::PointCloud samples, std::size_t frame)
    { return dp::cli::perFrameMesh(samples, r.meshVertices, r.defects && frame == 0); };
  const std::string series = dp::writeSampledSequence(*animation, r.sampling, r.output, r.writing);
  std::cout << "wrote " << animation->numberOfFrames() << " frames of " << r.sampling.pointsPerFrame
            << " samples (" << animation->numberOfVertices() << "-vertex mesh, diagonal "
            << diagonal << ") to " << series << "\n";
  return 0;
}

} // namespace

int main(int argc, char** argv)
{
  try
  {
    return run(argc, argv);
  }
  catch (const dp::cli::UsageError& e)
  {
    std::cerr << "dynamicpoints-sample: " << e.what() << "\nTry 'dynamicpoints-sample --help'.\n";
    return 2;
  }
  catch (const std::exception& e)
  {
    std::cerr << "dynamicpoints-sample: error: " << e.what() << "\n";
    return 1;
  }
}
