// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkDistanceFieldFilter
 * @brief   unsigned distance from the voxels of an image to a point cloud, with the nearest points
 *
 * vtkDistanceFieldFilter computes the distance from each point of its output image to the points
 * of its input (any vtkPointSet; cells are ignored), for viewing (volume rendering, contouring)
 * or further processing. It is the field D of the distance energy E_dis = sum_i m_i D_i of
 * Shinya, Shioya & Shiraishi, "Unification of Dynamic Point Data", computed the paper's way on a
 * dense box of voxels: exact nearest points within a band around the points, a vector distance
 * transform beyond it (linear in the voxels; see dp::computeDistanceImage).
 *
 * Parameters follow vtkUnsignedDistance:
 * - Dimensions (default 128^3) and Bounds of the output image; with AdjustBounds on (default)
 *   the bounds are the input's, padded by AdjustDistance times the diagonal. The image's voxels
 *   are the field's: no resampling;
 * - BandWidth: within this distance of the points every voxel's distance and nearest point are
 *   exact (0, the default: 3 voxels of the image). Beyond it the distance is to a real input
 *   point found by the transform: never below the true distance, above it by a small fraction of
 *   a voxel.
 *
 * Output point arrays: "Distance" (active scalars), "Gradient" (active vectors: the unit vector
 * away from the nearest point), "NearestPointId" (index of the nearest input point),
 * "NearestNormal" (that point's normal: the input's "Normals" when present, otherwise estimated
 * by local PCA and consistently oriented, see ComputeNormals) and "InBand" (1 where the voxel is
 * within the band: its values are exact). Field data: "BandWidth", "BandVoxels".
 *
 * @warning Points with NaN/Inf coordinates are dropped with a warning. An empty input, a
 * negative BandWidth, or an image of more than MaximumNumberOfVoxels samples are errors with the
 * numbers in the message; nothing is allocated in that case. Multi-threaded (TBB); the same
 * result on any number of threads.
 */
#ifndef vtkDistanceFieldFilter_h
#define vtkDistanceFieldFilter_h

#include "DynamicPointsFiltersModule.h" // for export macro
#include "vtkImageAlgorithm.h"

class DYNAMICPOINTSFILTERS_EXPORT vtkDistanceFieldFilter : public vtkImageAlgorithm
{
public:
  static vtkDistanceFieldFilter* New();
  vtkTypeMacro(vtkDistanceFieldFilter, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /** Within this distance of the points (world units) the values are exact; 0 (default): 3
   *  voxels of the output image. */
  vtkSetMacro(BandWidth, double);
  vtkGetMacro(BandWidth, double);
  ///@}

  ///@{
  /** Output samples per axis (default 128 x 128 x 128; at least 2 each). */
  vtkSetVector3Macro(Dimensions, int);
  vtkGetVectorMacro(Dimensions, int, 3);
  ///@}

  ///@{
  /** Output bounds, used when AdjustBounds is off. */
  vtkSetVector6Macro(Bounds, double);
  vtkGetVectorMacro(Bounds, double, 6);
  ///@}

  ///@{
  /** Take the output bounds from the input, padded by AdjustDistance x diagonal (default on). */
  vtkSetMacro(AdjustBounds, vtkTypeBool);
  vtkGetMacro(AdjustBounds, vtkTypeBool);
  vtkBooleanMacro(AdjustBounds, vtkTypeBool);
  vtkSetClampMacro(AdjustDistance, double, 0.0, 10.0);
  vtkGetMacro(AdjustDistance, double);
  ///@}

  ///@{
  /** Estimate normals (local PCA) when the input has none (default on). */
  vtkSetMacro(ComputeNormals, vtkTypeBool);
  vtkGetMacro(ComputeNormals, vtkTypeBool);
  vtkBooleanMacro(ComputeNormals, vtkTypeBool);
  ///@}

  ///@{
  /** Refuse output images of more samples than this (default 200 million). */
  vtkSetClampMacro(MaximumNumberOfVoxels, vtkIdType, 1, VTK_ID_MAX);
  vtkGetMacro(MaximumNumberOfVoxels, vtkIdType);
  ///@}

protected:
  vtkDistanceFieldFilter();
  ~vtkDistanceFieldFilter() override = default;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  double BandWidth; // the engine's default (dp::DistanceFieldOptions), set by the constructor
  int Dimensions[3] = {128, 128, 128};
  double Bounds[6] = {-1.0, 1.0, -1.0, 1.0, -1.0, 1.0};
  vtkTypeBool AdjustBounds = true;
  double AdjustDistance = 0.05;
  vtkTypeBool ComputeNormals = true;
  vtkIdType MaximumNumberOfVoxels; // the engine's default, set by the constructor

private:
  vtkDistanceFieldFilter(const vtkDistanceFieldFilter&) = delete;
  void operator=(const vtkDistanceFieldFilter&) = delete;
};

#endif
