// SPDX-License-Identifier: BSD-3-Clause
/**
 * @file MeshDistortion.h
 * @brief How far a decoded mesh lies from a frame's own mesh, as volumetric-video codecs report
 *        it: D1 (point-to-point) and D2 (point-to-plane) PSNR, both directions, the worse kept.
 *
 * Each surface is sampled evenly by area (sampleMeshSurface); for every sample of one surface,
 * e is the vector to the closest point of the other surface (exact, on its triangles: the figure
 * does not depend on how densely the other side was sampled). D1 adds |e|^2, D2 adds (e . n)^2
 * with n the other surface's normal there (its vertex normals interpolated). Each direction's
 * mean is its mean squared error; the larger of the two directions is kept (a part missing from
 * one mesh shows in one direction only). PSNR = 10 log10(peak^2 / MSE), the peak being the
 * reference mesh's bounding-box diagonal.
 *
 * Limits: the exact closest point makes D1 a little smaller than the MPEG tools' nearest-sample
 * D1 (which includes half a sample spacing of sampling noise); D2 is the same in kind.
 * Triangles that repeat a vertex are left out of both meshes.
 */
#pragma once

#include "dp/geometry/MeshSurfaceSamples.h"

#include <cstddef>

namespace dp
{

struct MeshDistortion
{
  double d1 = 0;           // mean squared point-to-point error, the worse direction (units^2)
  double d2 = 0;           // mean squared point-to-plane error, the worse direction (units^2)
  double peak = 0;         // the reference's bounding-box diagonal
  std::size_t samples = 0; // per surface
  /** In dB; infinite for identical surfaces. */
  double d1Psnr() const;
  double d2Psnr() const;
};

/**
 * D1 and D2 of `test` against `reference` with about `samples` points on each surface (see the
 * file comment). Throws std::invalid_argument for a mesh without area or bad indices.
 * Multi-threaded; the result is the same for any thread count.
 */
MeshDistortion meshDistortion(const MeshSurface& reference, const MeshSurface& test,
                              std::size_t samples);

} // namespace dp
