// SPDX-License-Identifier: BSD-3-Clause
// vtkDeformableTrackFilter's output for one tracked frame: the positions on the template's
// triangles, their point data and the frame's field data (private to the module).
#ifndef vtkDPTrackedFrame_h
#define vtkDPTrackedFrame_h

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

class vtkCellArray;
class vtkPolyData;

namespace dp
{
struct FrameResult;
}

namespace vtkDP
{
/** What every frame's output shows beside the frame's own result. */
struct TakeContext
{
  vtkCellArray* polys;                        // the template's triangles
  const std::vector<std::int64_t>* triangles; // ... as the engine holds them
  const std::vector<double>* rest;            // the template's positions
  double reach;                    // how far from the mesh a point still counts (DataReach)
  const std::string* templateMade; // how the template was made (field data "Template")
};

/** Frame `frame`'s result `r` as the track filter's output: the tracked positions on the
 *  template's triangles; per vertex Displacement (from the template), Residual, Frozen,
 *  Rejected, Normals and, where the points carry colour, Colors; the frame's figures
 *  (dp::FrameFigures), its data samples ("DataSamples") and how the template was made as field
 *  data. */
void fillTrackedFrame(vtkPolyData* output, const TakeContext& take, const dp::FrameResult& r,
                      std::size_t frame);
} // namespace vtkDP

#endif
