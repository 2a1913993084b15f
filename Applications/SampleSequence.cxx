// SPDX-License-Identifier: BSD-3-Clause
// dynamicpoints-sample: make a synthetic point sequence from an animated mesh, the way the
// paper made its CG experiments (random surface samples per frame, noise, holes).
#include "CommandLine.h"
#include "PerFrameMesh.h"

#include "dp/geometry/BoundingBox.h"
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

Per-frame meshes (as volumetric-video studios publish them):
  --per-frame-mesh N    write each frame as a mesh of about N vertices reconstructed from
                        its samples: its own connectivity every frame, the samples' colours
                        carried to the nearest vertex
  --mesh-defects        give frame 0's mesh what marching cubes and exporters leave:
                        duplicate vertices, triangles without area, a small stray part

Output:
  --format EXT          ply (binary, default), pcd, xyz, csv or obj
  --interval T          time between frames in points.series (default 1)
  --truth               also write the true mesh of each frame to OUTPUT_FOLDER/truth/
  -h, --help            show this help
)";

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
  bool help = false;
};

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
    else if (arg == "--mesh")
      r.mesh = optionValue(argc, argv, i);
    else if (arg == "--pattern")
      r.pattern = optionValue(argc, argv, i);
    else if (arg == "--frames")
      r.frames = parseCount(arg, optionValue(argc, argv, i), 1, 100000);
    else if (arg == "--points")
      r.sampling.pointsPerFrame = parseCount(arg, optionValue(argc, argv, i), 1, 100000000);
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
    else if (arg == "--per-frame-mesh")
      r.meshVertices = parseCount(arg, optionValue(argc, argv, i), 20, 10000000);
    else if (arg == "--mesh-defects")
      r.defects = true;
    else if (arg == "--no-normals")
      r.sampling.normals = false;
    else if (arg == "--format")
    {
      r.writing.extension = optionValue(argc, argv, i);
      const std::string& e = r.writing.extension;
      if (e != "ply" && e != "pcd" && e != "xyz" && e != "csv" && e != "obj")
        throw UsageError("option --format: '" + e + "' is not one of ply pcd xyz csv obj");
    }
    else if (arg == "--interval")
      r.writing.frameInterval = parseDouble(arg, optionValue(argc, argv, i), 1e-12, 1e12);
    else if (arg == "--truth")
      r.writing.writeGroundTruth = true;
    else if (!arg.empty() && arg[0] == '-')
      throw UsageError("unknown option '" + arg + "'");
    else if (r.output.empty())
      r.output = arg;
    else
      throw UsageError("more than one output folder given ('" + r.output + "', '" + arg + "')");
  }
  if (r.output.empty())
    throw UsageError("no OUTPUT_FOLDER given");
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
