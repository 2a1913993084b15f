// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file FrameData.h
 * @brief One frame of the tracking problem: the frame's points, their unit normals (given or
 *        estimated), the distance field D of the paper's distance energy (eq. 1, E_dis) with its
 *        nearest-point search, and a well-spread subsample of the points for the points -> mesh
 *        term. The energy terms and solvers read it; nothing in it changes while a frame is
 *        solved, so it can be shared by threads.
 *
 * The subsample keeps, in each cell of a grid whose cell size makes about `spreadCount` cells
 * meet the surface, the point nearest the cell's centre: evenly spread over the data whatever
 * the scanner's density, deterministic (no random choice).
 *
 * The points are kept in the order of a space-filling (Morton) curve, not the frame's: points
 * near in space are near in memory, which the searches and the per-point loops of the energy
 * terms read faster (1.1x a frame of jumping, 20 000 points in random order). point(i) and the
 * subsample's indices refer to that order.
 *
 * A frame of more than `maxPoints` points is thinned first, the same way (one point per cell,
 * cells grown until few enough are left; above 8 x maxPoints every k-th point is taken before
 * the grid, which bounds the memory): the field resolves nothing finer than its voxel, and a
 * 10-million-point frame would otherwise spend minutes and gigabytes on normals. size() is then
 * the thinned count and originalSize() the frame's.
 *
 * Limits: normals are estimated by PCA over 16 neighbours and oriented along a spanning tree
 * (estimateNormals) when not given; orientation can flip on parts thinner than the point
 * spacing. An empty frame has no field: the data terms then contribute nothing.
 */
#pragma once

#include "dp/field/DistanceField.h"
#include "dp/geometry/FrameSamples.h"
#include "dp/geometry/NormalEstimation.h"
#include "dp/geometry/SurfaceNoise.h"

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace dp
{

class ColourField;

struct FrameDataOptions
{
  double voxelSize = 0;        // of the distance field (world units, > 0)
  double bandWidth = 0;        // of the distance field (world units; 0: 4 voxels)
  double surfaceArea = 0;      // the tracked surface's area (sets the subsample's cell size)
  std::size_t spreadCount = 0; // points wanted in the subsample (0: none)
  std::size_t maxPoints = 0; // a larger frame is thinned evenly to at most this many (0: no limit)
};

class FrameData
{
public:
  /** `normals` (nx ny nz per point) may be null: they are then estimated. */
  FrameData(const double* points, std::size_t count, const float* normals,
            const FrameDataOptions& options)
      : FrameData(points, count, normals, nullptr, 0, options)
  {
  }
  /** The same with colours: `colourComponents` (3 or 4: RGB, RGBA) bytes per point, or null. */
  FrameData(const double* points, std::size_t count, const float* normals,
            const std::uint8_t* colours, int colourComponents, const FrameDataOptions& options);
  ~FrameData();
  FrameData(const FrameData&) = delete;
  FrameData& operator=(const FrameData&) = delete;

  bool empty() const { return Count == 0; }
  std::size_t size() const { return Count; }
  /** The frame's own point count (size() is smaller when the frame was thinned). */
  std::size_t originalSize() const { return OriginalCount; }
  const double* points() const { return Field.points(); }
  const double* point(std::size_t i) const { return Field.points() + 3 * i; }
  /** Unit normals, 3 per point. */
  const float* normals() const { return Normals.data(); }
  const float* normal(std::size_t i) const { return Normals.data() + 3 * i; }
  const DistanceField& field() const { return Field; }
  double voxelSize() const { return Voxel; }

  /** The nearest point to x, its squared distance in *d2. */
  std::int64_t nearest(const double x[3], double* d2 = nullptr) const
  {
    return Field.nearestPoint(x, d2);
  }
  /** The k nearest points to x, nearest first (fewer when the frame has fewer). */
  std::size_t nearest(const double x[3], std::size_t k, std::uint32_t* indices, double* d2) const
  {
    return Field.nearestPoints(x, k, indices, d2);
  }
  /** Turns every normal around (they were oriented consistently, but inward). */
  void flipNormals()
  {
    for (float& n : Normals)
      n = -n;
  }
  /** Estimated normals are oriented part by part (estimateNormals): the number of parts (0 for
   *  normals given), each point's part, and turning one part's normals around. */
  std::size_t numberOfParts() const { return PartCount; }
  std::uint32_t part(std::size_t i) const { return Parts[i]; }
  void flipNormals(std::uint32_t part)
  {
    for (std::size_t i = 0; i < Parts.size(); ++i)
      if (Parts[i] == part)
        for (int c = 0; c < 3; ++c)
          Normals[3 * i + c] = -Normals[3 * i + c];
  }
  /** Within the parts: turns around the branches of the orientation that the subsample's votes
   *  (per spread() point: +1 agrees, -1 disagrees, 0 silent) disagree with as a whole
   *  (mendOrientation). Returns the number of points turned; 0 for normals given. */
  std::size_t mendOrientation(const std::vector<std::int8_t>& spreadVotes);
  /** Indices of the well-spread subsample, in increasing order. */
  const std::vector<std::uint32_t>& spread() const { return Spread; }
  /** The data's noise, measured around the subsample (SurfaceNoise.h); zero without one. */
  const SurfaceNoise& noise() const { return Judged.noise; }
  /** Per subsample point: stray (isolated, or off the layer: a flying pixel, a stray return),
   *  which no mesh is to explain; empty without a subsample. */
  const std::vector<char>& strayInSpread() const { return Judged.stray; }
  /** Whether point i is stray, judged as the subsample's points are (SurfaceNoise.h); judged
   *  when first asked and remembered (thread-safe). False without a subsample. */
  bool isStray(std::size_t i) const;
  /** The subsample without its stray points, with its normals, seen in place (valid while the
   *  frame lives, and its normals as they are when read: orient them first): what the data
   *  terms fit. */
  SampleView spreadSamples() const
  {
    return {Field.points(), Normals.data(), SpreadOnSurface.data(), SpreadOnSurface.size(), Voxel};
  }
  /** A copy of the subsample with its normals as they are now. */
  FrameSamples copySamples() const;
  /** The colour field of the points (null without colour). */
  const ColourField* colourField() const { return Colour.get(); }
  /** r g b in [0, 1] per point (empty without colour). */
  const std::vector<float>& colours() const { return Colours; }

private:
  // The points' typical spacing (world units), from the surface's area.
  double spacing() const;
  // The normals: given, or estimated and oriented part by part.
  void takeOrEstimateNormals(const double* points, std::size_t count, const float* normals);
  // The well-spread subsample (see the file comment).
  void chooseSpread(const double* points, std::size_t count, const FrameDataOptions& options);
  void judgeSpread(); // the noise and the stray points of the subsample

  std::size_t Count = 0;
  std::size_t OriginalCount = 0;
  double Voxel = 0;
  DistanceField Field;
  std::vector<float> Normals;
  std::vector<std::uint32_t> Parts; // of the estimated normals' orientation
  OrientationTree Tree;             // the estimated normals' orientation spread along it
  std::size_t PartCount = 0;
  std::vector<std::uint32_t> Spread;
  NoiseAtSamples Judged;                      // the subsample's noise and strays
  std::vector<std::uint32_t> SpreadOnSurface; // the subsample without its strays
  mutable std::unique_ptr<std::atomic<std::uint8_t>[]> StrayKnown; // 0 unknown, 1 on, 2 stray
  std::vector<float> Colours;
  double SurfaceArea = 0;
  std::unique_ptr<ColourField> Colour;
};

} // namespace dp
