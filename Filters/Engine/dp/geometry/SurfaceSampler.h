// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file SurfaceSampler.h
 * @brief Turns an animated mesh into a synthetic point sequence, the way the paper made its
 *        CG test data: area-uniform random surface points per frame, optionally with Gaussian
 *        noise, holes (surface regions the "scanner" did not see) and normals.
 *
 * Determinism: frame f's points depend only on (seed, f), never on which frames were sampled
 * before, so frames can be made in any order and the same seed gives the same files on every
 * platform (own generators on std::mt19937_64, whose output the C++ standard fixes).
 *
 * Holes are balls around material points of the surface (a triangle and barycentric
 * coordinates), so a hole follows the surface as it moves; every sample inside a ball is
 * removed. With `holesMove` the material points are drawn anew for every frame.
 *
 * Colour (`colourRest`): each sample takes the colour of the pattern at its material point's
 * rest position (materialColour()), as a textured body seen by 3D video would.
 */
#pragma once

#include "dp/io/AnimatedMesh.h"
#include "dp/io/PointCloud.h"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace dp
{

struct SamplerOptions
{
  std::size_t pointsPerFrame = 20000; // samples drawn before holes are cut
  std::uint64_t seed = 1;
  double noiseStdDev = 0.0; // Gaussian noise per coordinate, in the mesh's units
  std::size_t holes = 0;    // number of holes per frame
  double holeRadius = 0.0;  // in the mesh's units
  bool holesMove = false;   // new hole positions in every frame
  bool normals = true;      // write interpolated vertex normals
  // A colour fixed to the material (materialColour() at each sample's rest position, so the
  // true colour of every point is known). sampleSurface() needs the rest positions (3 per
  // vertex; they must outlive the call); writeSampledSequence() takes the mesh's first frame.
  bool colours = false;
  const std::vector<double>* colourRest = nullptr;
};

/** The sampler's material colour pattern at a rest position `p` of a mesh whose rest
 *  bounding-box diagonal is `diagonal`: red, green and blue in [0, 1], each a sum of two plane
 *  waves (wavelengths 12 % and 4 % of the diagonal) in fixed directions. Smooth, so a tracker
 *  can follow it, and without symmetry, so it says where on the surface a point lies. */
void materialColour(const double p[3], double diagonal, double rgb[3]);

/**
 * Samples one frame. `positions` are x y z per vertex, `triangles` 3 indices each.
 * Throws std::invalid_argument for a mesh with no area or indices out of range.
 */
PointCloud sampleSurface(const std::vector<double>& positions,
                         const std::vector<std::int64_t>& triangles, const SamplerOptions& options,
                         std::size_t frame);

/** The centres (x y z each) of the holes sampleSurface() cuts into this frame. */
std::vector<double> holeCentres(const std::vector<double>& positions,
                                const std::vector<std::int64_t>& triangles,
                                const SamplerOptions& options, std::size_t frame);

struct SequenceWriteOptions
{
  std::string filePrefix = "frame_";
  std::string extension = "ply"; // any format the product writes: ply pcd xyz csv obj drc
  double frameInterval = 1.0;    // times written into the .series file
  bool writeGroundTruth = false; // also truth/<prefix>NNNN.ply: the mesh of each frame
  // Applied to each frame's samples before they are written (frame index given), e.g. to turn
  // them into a mesh; empty: the samples as they are.
  std::function<PointCloud(PointCloud, std::size_t)> transform;
};

/**
 * Samples every frame of `mesh` and writes `outDir/<prefix>NNNN.<ext>` plus
 * `outDir/points.series`. Creates outDir. Returns the .series path.
 */
std::string writeSampledSequence(const AnimatedMesh& mesh, const SamplerOptions& sampling,
                                 const std::string& outDir,
                                 const SequenceWriteOptions& writing = {});

/** Writes `makeFrame(positions, f)` (then `writing.transform`) for every frame of `mesh` as
 *  `outDir/<prefix>NNNN.<ext>`, the truth if asked, and `outDir/points.series`; returns its
 *  path. */
std::string writeFrameSequence(
    const AnimatedMesh& mesh, const std::string& outDir, const SequenceWriteOptions& writing,
    const std::function<PointCloud(const std::vector<double>&, std::size_t)>& makeFrame);

} // namespace dp
