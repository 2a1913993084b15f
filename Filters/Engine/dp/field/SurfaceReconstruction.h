// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file SurfaceReconstruction.h
 * @brief A triangle mesh from an oriented point cloud: the paper's first step ("polygonize the
 *        first frame's points and simplify to a working resolution") when the user has no template
 *        and the first frame has no polygons. The mesh is the tracker's template: closed where the
 *        data are closed (holes in the data bridged), with the wanted number of vertices and evenly
 *        shaped triangles, facing the way the data's normals do (outward).
 *
 * Method, in two stages.
 * 1. A faithful surface at a fine voxel size (1.5 median point spacings, whatever the wanted
 *    count). A narrow band of voxels around the points (OpenVDB) holds the signed distance to the
 *    points' tangent planes (Hoppe et al. 1992), averaged over each voxel's nearest points with
 *    Gaussian weights so that noise is smoothed. Holes in the data (gaps up to about twice
 *    `holeReach`) are the cells that a morphological closing of the points' coarse cells adds;
 *    their voxels get no plane distance (far from the data it is unreliable) but the harmonic
 *    interpolation of the values around them, which spans a hole from rim to rim (parts that only
 *    meet the outside, concave corners, stay outside). Outside the band, each connected piece of
 *    space takes the sign that most of the band's voxels on its border have, so no crossing appears
 *    where the band ends. Normals that most of the border voxels near them contradict (a wrongly
 *    oriented patch, cloth folded over itself) are flipped and the field evaluated again there;
 *    border voxels still in disagreement take their piece's sign, which leaves at worst a small
 *    blister instead of a surface far from the data. OpenVDB's volumeToMesh meshes the zero
 *    crossing; the largest connected piece is kept (or, with `keptPieceShare` under 1, every
 *    piece at least that share of its size).
 * 2. Isotropic remeshing of that surface to the wanted count (Botsch & Kobbelt 2004): edge splits,
 *    collapses (with the link condition, no folded triangles, the merged vertex where the fine
 *    surface's planes around the edge are best kept, as in Garland & Heckbert's quadric
 *    simplification, so that tips and thin parts do not shrink), flips towards valence 6 and
 *    tangential relaxation, every vertex projected back onto the fine surface, at the edge length
 *    that area and count call for, corrected once from the count reached; then the shortest edges
 *    are collapsed or the longest split until the count is met exactly, the triangles are evened
 *    out again and the diagonals of poorly shaped pairs flipped. Orientation: the way the data's
 *    normals face, by a vote of all triangles.
 *
 * Limits: the normals must be mostly consistently oriented (estimateNormals orients them; a
 * scanner's face its position); small wrongly oriented patches are tolerated. Parts thinner than
 * about two fine voxels merge or vanish (a horse's ears become blobs), and parts much thinner than
 * the target edge length are kept only coarsely. Where the data pass through themselves (an arm
 * through the body in a captured mesh), a small tunnel inside the shape may remain. Holes wider
 * than about twice `holeReach` stay open; bridged holes are smooth membranes, not the true shape.
 * Open data (a surface seen from one side: the border of a piece of space has both signs in large
 * parts) give an open mesh, its boundary where the data end. The vertex count is met exactly unless
 * the mesh is too small to collapse further. Time: 0.5 to 0.9 s for 20 000 points on two cores (a
 * person 1.70 m tall, 500 to 5000 vertices): about 0.4 s the fine surface, the rest remeshing.
 */
#pragma once

#include "dp/geometry/SurfaceNoise.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dp
{

/** The vertex counts a template may ask for (reconstruction, remeshing): the engine, the filter,
 *  its ParaView property and the command line take this range (a test checks the XML). */
constexpr std::size_t MinimumTemplateVertices = 20;
constexpr std::size_t MaximumTemplateVertices = 10000000;
struct ReconstructionOptions
{
  std::size_t targetVertices = 1000;        // wanted vertex count
  std::size_t neighbours = 8;               // points whose planes each voxel averages
  std::size_t maxActiveVoxels = 50'000'000; // refuse larger grids (memory guard)
  double voxelSize = 0;      // of the fine grid; 0: 1.5 times the points' median spacing
  double holeReach = 0.035;  // holes in the data are bridged up to about this distance from
                             // their rim, as a fraction of the bounding box diagonal (0.035:
                             // 6.7 cm on a person 1.70 m tall; 0: only gaps of a few voxels)
  double handleLoop = 0.3;   // a closed surface's handles whose loop is shorter than this
                             // share of the diagonal are cut (HandleRemoval.h): noise and
                             // closing make such bridges; a body has none (0: none cut)
  double keptPieceShare = 1; // pieces with at least this share of the largest piece's triangles
                             // are kept (1: the largest alone, as a template needs; a small
                             // share keeps what a capture's marching cubes keep, a tail cut off
                             // by a hole, and drops the floaters of noise)
};

struct ReconstructedMesh
{
  std::vector<double> positions;       // x y z per vertex
  std::vector<std::int64_t> triangles; // 3 vertex indices each, consistently oriented
  double voxelSize = 0;                // the fine grid's voxel size
  bool closed = false;                 // watertight: every edge has two triangles
  SurfaceNoise noise;                  // the points' noise, measured (SurfaceNoise.h)
  std::size_t neighbours = 0;          // the points each voxel's planes were averaged over
  std::size_t strayPoints = 0;         // left out as stray returns
  bool smoothedForNoise = false;       // the points were a noisy layer: smoothed beyond spacing
  std::size_t handlesCut = 0;          // handles cut to make the surface genus 0
};

/**
 * Reconstructs a surface from `count` points (x y z each) with unit normals (nx ny nz each;
 * estimateNormals gives them). Throws std::invalid_argument for fewer than 16 points,
 * non-finite coordinates or normals, points that all coincide, a target under 20 vertices or
 * a negative or non-finite voxelSize or holeReach, a keptPieceShare outside (0, 1], and
 * std::runtime_error when the fine grid would exceed maxActiveVoxels (a larger voxelSize helps) or
 * no surface comes out.
 */
ReconstructedMesh reconstructSurface(const double* points, const float* normals, std::size_t count,
                                     const ReconstructionOptions& options = {});

} // namespace dp
