// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file TemplateMesh.h
 * @brief The template the tracker deforms, made from what a take offers and made fit for
 *        tracking, with a report of what was done to it.
 *
 * Sources:
 *   - a mesh (frame 0's own polygons, as a capture studio's per-frame meshes have, or a mesh the
 *     user gives): repaired (duplicate vertices merged; triangles with no area, repeated
 *     triangles and parts far smaller than the largest dropped; unused vertices dropped) and,
 *     for frame 0's mesh, simplified by isotropic remeshing (IsotropicRemesher) to about the
 *     vertex count asked when it has more than 10 % over it. A mesh the user gives is repaired
 *     only: its resolution is the user's choice, and every change is in the report;
 *   - points: a surface reconstructed from them (reconstructSurface), their normals estimated
 *     when not given.
 * Auto takes the mesh when there are triangles, else the points.
 *
 * Limits: holes in a mesh are not closed (the remesher keeps them as boundaries); a mesh whose
 * triangles are not consistently oriented remeshes poorly (reconstruct from its points instead);
 * parts of a mesh joined in frame 0 stay joined.
 */
#pragma once

#include "dp/field/SurfaceReconstruction.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace dp
{

enum class TemplateSource
{
  Auto,  // the mesh when there are triangles, else the points
  Mesh,  // the triangles (an error without them)
  Points // a surface reconstructed from the points, whatever triangles there are
};

struct TemplateOptions
{
  TemplateSource source = TemplateSource::Auto;
  std::size_t targetVertices = 1000; // wanted vertex count (remeshing, reconstruction)
  // false for a mesh the user gives: repaired, never remeshed.
  bool remesh = true;
  ReconstructionOptions reconstruction; // its targetVertices is targetVertices
};

/** What was done to make the template, in counts. */
struct TemplateReport
{
  std::string source;             // "frame 0's mesh", "the template mesh", "frame 0's points"
  std::size_t verticesGiven = 0;  // the source's (points for a reconstruction)
  std::size_t trianglesGiven = 0; // the source's, polygons split into triangles
  std::size_t duplicateVertices = 0, unusedVertices = 0;
  std::size_t degenerateTriangles = 0, duplicateTriangles = 0, smallPartTriangles = 0;
  bool remeshed = false, reconstructed = false;
  std::size_t vertices = 0, triangles = 0; // the template's
  SurfaceNoise noise;                      // a reconstruction's: the points' noise measured
  bool smoothedForNoise = false;           // a noisy layer: smoothed by its thickness
  double smoothingVoxel = 0;               // its fine voxel
  std::size_t strayPoints = 0;             // the stray returns it left out

  /** One sentence a user reads: "frame 0's mesh: 12 degenerate triangles removed, remeshed
   *  from 20913 to 1000 vertices". */
  std::string summary() const;
};

struct TemplateMesh
{
  std::vector<double> positions;       // x y z per vertex
  std::vector<std::int64_t> triangles; // 3 vertex indices each
  TemplateReport report;
};

/** The template from `count` points (x y z each; `normals` nx ny nz each, or null) and
 *  `triangles` (3 indices each into the points; may be empty). `what` names a mesh source in
 *  the report and the errors ("frame 0's mesh", "the template mesh"). Throws
 *  std::invalid_argument naming the source and the reason when no template can be made (no
 *  triangle left after the repair, indices out of range, too few points to reconstruct), and
 *  what reconstructSurface throws. */
TemplateMesh makeTemplate(const double* points, std::size_t count, const float* normals,
                          const std::vector<std::int64_t>& triangles,
                          const TemplateOptions& options, const std::string& what);

} // namespace dp
