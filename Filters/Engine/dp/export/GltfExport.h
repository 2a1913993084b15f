// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file GltfExport.h
 * @brief A compressed sequence (shape layout) as a glTF 2.0 binary (.glb) with morph targets,
 *        written with tinygltf: the base mesh, one morph target per basis shape, one animation
 *        of the morph weights (LINEAR, one key per frame at 24 frames per second).
 *
 * Blender (3.4) clamps morph weights to [0, 1], so each weight track is rescaled into [0, 1]:
 * with lo_j and hi_j its range, the target becomes (hi_j - lo_j) U_j and lo_j U_j is folded into
 * the base; base + sum_j w'_j target_j is the same shape, so the error does not change (only
 * float32 rounding is added). Weights, positions and times are float32, as glTF stores them.
 *
 * With `meshopt`, every buffer view is stored compressed by meshoptimizer (glTF extension
 * EXT_meshopt_compression: vertex codec for positions, targets, times and weights, index codec
 * for the triangles), for web viewers (three.js, Babylon.js, gltfpack's tools). The extension
 * is then required: viewers without it (Blender 3.4, VTK 9.2) cannot read that variant, so the
 * uncompressed one is the default. Decoding gives back the same bytes (lossless).
 *
 * Colour (a sequence with a colour stream): frame 0's colours as the base's COLOR_0 (normalized
 * unsigned bytes), and one morph target per later frame holding its colours' change from frame 0
 * (normalized signed shorts, exact at every key), weighted 1 at its frame's key and 0 at the
 * others, so players that morph COLOR_0 (three.js) play each frame's colours and blend between
 * neighbouring frames. Every target carries both POSITION and COLOR_0 (shared accessors of zeros
 * where it changes nothing): three.js fills a missing target attribute with the base's. The
 * targets are named (extras.targetNames: "shape j", "colour of frame t"). Costs 8 bytes per
 * vertex per frame after the first. Players that do not morph colour show frame 0's: Blender
 * 3.4 imports COLOR_0 as the colour attribute "Col" and the colour targets as shape keys that
 * move nothing; VTK 9.2 reads COLOR_0 as point data and warns once per target that it ignores
 * the targets' COLOR_0.
 *
 * A sequence with a detail layer is written at one level of its fine mesh: the vertices of that
 * level (the base's, then those each subdivision made, displaced as decoded: dp::detailedFrame)
 * on that level's triangles, with their colours, decomposed again into morph targets (float PCA
 * of the shapes, as many components as keep them within the layer's own coding error:
 * max(step / sqrt(12), the base's RMS error)). By default the finest level whose file stays
 * within GlbOptions::maximumBytes; the detail is mostly per-frame capture noise that no few
 * shapes hold, so the finest level can need a component for most frames.
 *
 * Limits: only the shape layout maps onto morph targets (the trajectory layout is refused);
 * no normals (viewers compute them).
 */
#pragma once

#include "dp/compress/PcaCompression.h"

#include <cstddef>
#include <optional>
#include <string>

namespace dp
{

struct GlbOptions
{
  bool meshopt = false; // EXT_meshopt_compression on every buffer view
  // A sequence with a detail layer: the level of its fine mesh written (0: the base), or -1: the
  // finest whose file stays within maximumBytes.
  int detailLevel = -1;
  std::size_t maximumBytes = std::size_t{64} << 20;
};

/** The level writeGlb writes of a sequence's detail layer (0 without one), and the sequence it
 *  writes for it (the detail level as its own base, decomposed again: see the file comment). */
struct GlbLevel
{
  int level = 0;
  std::optional<CompressedSequence> written; // unset: the sequence itself (level 0)
};
GlbLevel glbLevelOf(const CompressedSequence& sequence, const GlbOptions& options = {});

/** What writeGlb wrote: the detail level (0: the base), its vertices and its shape targets. */
struct GlbSummary
{
  int level = 0;
  std::size_t vertices = 0, shapes = 0;
};

/** Writes `sequence` to `path` (.glb); one of the trajectory layout is decomposed again as
 *  shapes (within a quarter of its coding error). Throws std::invalid_argument for a sequence
 *  without triangles or colours of the wrong count, std::runtime_error when the file cannot be
 *  written. */
GlbSummary writeGlb(const std::string& path, const CompressedSequence& sequence,
                    const GlbOptions& options = {});

} // namespace dp
