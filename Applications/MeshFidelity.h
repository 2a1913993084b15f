// SPDX-License-Identifier: BSD-3-Clause
// The main job's figures for per-frame mesh input, as volumetric-video codecs give them: each
// decompressed frame against that frame's own mesh (D1 and D2 PSNR, dp::meshDistortion) and
// the file's bits per input vertex per frame.
#pragma once

#include "dp/compress/PcaCompression.h"
#include "dp/geometry/MeshDistortion.h"
#include "dp/io/PointCloud.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace dp::cli
{

/** A decoded frame against its input mesh, as the codecs are measured (D1 and D2, both
 *  directions, the worse kept; peak = the input's diagonal), on enough samples that each of the
 *  input's triangles is visited about twice (at least 20 000). The report's measure, and the
 *  rate-distortion benchmark's for Draco's frames. */
MeshDistortion distortionAgainstInput(const MeshSurface& decoded, const PointCloud& input);

/**
 * The decompressed `sequence` (frame t; the fine mesh of its detail layer when it has one)
 * against the mesh in `framePaths[t]`, for every frame:
 * {"d1PsnrDb", "d2PsnrDb" (means over frames), "worstD1PsnrDb", "worstD2PsnrDb",
 *  "bitsPerInputVertexFrame" (the whole file), "geometryBitsPerInputVertexFrame" (without the
 *  colour stream), "detailBitsPerInputVertexFrame" (the detail layer's share),
 *  "inputVertices", "samplesPerSurface", "perFrame": [...]}.
 * Null when frame 0's file has no polygons (point input: nothing to compare surfaces with) or
 * the counts differ. `progress` is told each frame measured. Throws what the readers throw.
 */
nlohmann::json measureAgainstInputMeshes(const CompressedSequence& sequence,
                                         const std::vector<std::string>& framePaths,
                                         std::size_t fileBytes,
                                         const std::function<void(std::size_t)>& progress = {});

} // namespace dp::cli
