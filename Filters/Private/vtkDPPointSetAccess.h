// SPDX-License-Identifier: BSD-3-Clause
// Moving data between VTK point sets and the engine's plain arrays (private to the module).
#ifndef vtkDPPointSetAccess_h
#define vtkDPPointSetAccess_h

#include "vtkSmartPointer.h"
#include "vtkType.h"

#include <cstdint>
#include <vector>

class vtkDataObject;
class vtkFloatArray;
class vtkInformation;
class vtkPointSet;
class vtkPolyData;
class vtkUnsignedCharArray;

namespace vtkDP
{
/** The finite points (x y z) of a point set, their original ids, and their normals when the
 *  set has a 3-component "Normals" array (or active normals). */
struct TargetPoints
{
  std::vector<double> xyz;
  std::vector<vtkIdType> ids;
  std::vector<float> normals;
  // r g b per point, from the points' colours ("RGB", "RGBA", "Colors", or active scalars of
  // 3 or 4 bytes a point); empty without them.
  std::vector<std::uint8_t> colours;
  vtkIdType dropped = 0; // points with NaN/Inf coordinates left out
};
/** A point set's colours: an unsigned char array of 3 or 4 components named "RGB", "RGBA" or
 *  "Colors", or the active scalars if they are such an array; null without one. */
vtkUnsignedCharArray* pointColours(vtkPointSet* input);
TargetPoints finitePoints(vtkPointSet* input);

/** A surface mesh as triangles (polygons split into fans) and positions. Returns false (with
 *  `why` set) when the mesh has no polygons or a non-finite point. */
bool triangleMesh(vtkPolyData* mesh, std::vector<std::int64_t>& triangles,
                  std::vector<double>& positions, const char*& why);
/** Publishes the input's TIME_STEPS and TIME_RANGE on the output (or removes them for a static
 *  input) and returns the steps (empty for a static input). */
std::vector<double> forwardTimeSteps(vtkInformation* inInfo, vtkInformation* outInfo);

/** The last of the ascending time `steps` at or before `t` (with a little slack for rounding);
 *  0 when t is before the first. */
std::size_t frameAtTime(const std::vector<double>& steps, double t);

/** The frame an output request asks for: frameAtTime of its UPDATE_TIME_STEP; 0 for a static
 *  input (no steps) or a request without a time. */
std::size_t requestedFrame(const std::vector<double>& steps, vtkInformation* outInfo);

/** A "Colors" array of `n` r g b byte triples copied from `rgb` (the mesh colours the tracker,
 *  the compressor and the reader give; ParaView shows such bytes as they are). */
vtkSmartPointer<vtkUnsignedCharArray> colorsArray(const std::uint8_t* rgb, vtkIdType n);

/** A float array `name` of the distances between the points of `a` and `b` (x y z each, `n`
 *  points): how far each vertex moved (a compression's error). */
vtkSmartPointer<vtkFloatArray> distancesArray(const char* name, const double* a, const double* b,
                                              vtkIdType n);

/** Adds a one-value double array `name` to `data`'s field data (per-frame figures). */
void addFieldValue(vtkDataObject* data, const char* name, double value);

/** True when the output request is for a piece other than 0. The sources hand the whole frame
 *  to piece 0 (they do not split), so under MPI the tracker and the compressor run on process 0
 *  and give the other processes an empty output, without errors or files. */
bool isSecondaryPiece(vtkInformation* outInfo);
} // namespace vtkDP

#endif
