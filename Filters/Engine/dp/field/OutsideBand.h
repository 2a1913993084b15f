// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file OutsideBand.h
 * @brief SurfaceReconstruction's field where it holds no plane distance: the signs of the pieces
 *        of space outside the band around the points (OutsideBand), and the values across the
 *        holes in the data (interpolateHoles).
 *
 * Internal to dp/field: it includes OpenVDB, which the field concern keeps private. The grid is
 * the reconstruction's: the band's voxels hold the plane distance in voxels, clamped to
 * +-background, the holes' voxels UnknownHoleValue until interpolateHoles gives them one.
 */
#pragma once

#include <openvdb/openvdb.h>

#include <cstddef>
#include <utility>
#include <vector>

namespace dp::support
{

/** The value of hole voxels until interpolateHoles gives them one. */
constexpr float UnknownHoleValue = 1e6f;

/**
 * The space outside the band, in cells of Ratio^3 voxels. Its connected pieces (the outside,
 * the inside of each closed part) each take the sign that most of the band's voxels along their
 * border have; settle() sets the border voxels that disagree to it and gives every value
 * outside the band its piece's sign. A patch of wrong normals then makes at worst a blister at
 * the patch, where openvdb's signedFloodFill (which takes the sign of whichever band voxel its
 * scan meets first) would carry the wrong sign far from the data, and a surface with it.
 */
class OutsideBand
{
public:
  static constexpr int Ratio = 2;

  /** Cells over the band's bounding box and one more around it; every voxel of a cell that
   *  the band touches is made active, so that what lies outside the band is whole cells. */
  explicit OutsideBand(openvdb::FloatGrid& grid);

  /** The connected pieces of free cells (sharing faces) and their signs, from the band's
   *  values. */
  void findPieces(const openvdb::FloatGrid& grid);

  /** Whether a piece's border has both signs in large parts: the data are open there (a sheet,
   *  a scan from one side) rather than closed with a few wrong normals. */
  bool open() const;

  /** -1 inside, +1 outside, 0 in the band, for a voxel. */
  int side(const openvdb::Coord& voxel) const;

  /** The border voxels of the pieces whose border mostly agrees, and whether their piece is
   *  inside. */
  void borderOfSettledPieces(std::vector<std::pair<openvdb::Coord, bool>>& out) const;

  /** Border voxels to their piece's sign; every value outside the band (voxels of partly active
   *  leaves, tiles, the background) to its piece's sign. */
  void settle(openvdb::FloatGrid& grid, float background) const;

private:
  static constexpr int Free = -2, Band = -1;
  int Low[3] = {0, 0, 0}, Size[3] = {0, 0, 0};
  std::vector<int> Label;   // per cell: Free, Band, or its piece
  std::vector<bool> Inside; // per piece
  std::vector<bool> Mixed;  // per piece: its border is of both signs in large parts

  // Numbers the connected pieces of free cells (Label); returns how many there are.
  std::size_t labelPieces();

  static int floorDiv(int i) { return i >= 0 ? i / Ratio : -((-i + Ratio - 1) / Ratio); }
  openvdb::Coord cellOf(const openvdb::Coord& v) const
  {
    return openvdb::Coord(floorDiv(v.x()) - Low[0], floorDiv(v.y()) - Low[1],
                          floorDiv(v.z()) - Low[2]);
  }
  std::size_t index(const openvdb::Coord& c) const
  {
    return static_cast<std::size_t>(c.x()) +
           static_cast<std::size_t>(Size[0]) *
               (static_cast<std::size_t>(c.y()) + static_cast<std::size_t>(Size[1]) * c.z());
  }
  openvdb::Coord coordOf(std::size_t i) const
  {
    const auto nx = static_cast<std::size_t>(Size[0]), ny = static_cast<std::size_t>(Size[1]);
    return openvdb::Coord(static_cast<int>(i % nx), static_cast<int>((i / nx) % ny),
                          static_cast<int>(i / (nx * ny)));
  }
  // visit(j, axis, side) for each cell j sharing a face with cell i.
  template <typename Visit>
  void forFaces(std::size_t i, Visit visit) const;
  // visit(piece, voxel) for each band voxel that shares a face with a free cell.
  template <typename Visit>
  void border(Visit visit) const;
};

/**
 * The voxels of holes get the harmonic interpolation (successive over-relaxation of the mean of
 * the six neighbours) of the values around them: the band's, and the pieces' outside it. Across
 * a hole, between the inside (band voxels or hole voxels themselves, when the closing filled a
 * thin part) and the outside, that is a membrane from rim to rim. A connected part of hole
 * voxels that meets pieces of one sign only and whose band neighbours mostly have that sign
 * too (a concave corner of the outside, the hollow of a cupped ear) is no hole: it takes that
 * sign, so no surface appears there where a few band voxels next to it have the other one (a
 * part too thin for the voxels). Call it after OutsideBand::settle.
 */
void interpolateHoles(openvdb::FloatGrid& grid, const std::vector<openvdb::Coord>& holes,
                      float background);

} // namespace dp::support
