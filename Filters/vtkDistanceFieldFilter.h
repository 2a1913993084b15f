// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkDistanceFieldFilter
 * @brief   unsigned distance field of a point cloud, built on a sparse OpenVDB grid
 *
 * vtkDistanceFieldFilter computes the distance from space to the points of its input (any
 * vtkPointSet; cells are ignored) and samples it on a vtkImageData for viewing (volume
 * rendering, contouring). It is the field D of the distance energy E_dis = sum_i m_i D_i of
 * Shinya, Shioya & Shiraishi, "Unification of Dynamic Point Data" (the paper uses a dense
 * 200^3 voxel box and a vector distance transform; here the field lives on a sparse band of
 * an OpenVDB grid whose voxels store the index of their nearest point).
 *
 * Parameters follow vtkUnsignedDistance / vtkSignedDistance:
 * - VoxelSize: resolution of the field in world units (0, the default: the input's bounding
 *   box diagonal / 200, the paper's setting);
 * - BandWidth: the band around the points held in the grid (0, the default: 3 voxels).
 *   Outside it distances are exact nearest-point distances from a kd-tree, so the field is
 *   defined (and pulls toward the data) everywhere;
 * - Dimensions (default 128^3) and Bounds of the output image; with AdjustBounds on (default)
 *   the bounds are the input's, padded by AdjustDistance times the diagonal. The output only
 *   samples the field: its spacing need not be the voxel size.
 *
 * Output point arrays: "Distance" (active scalars), "Gradient" (active vectors),
 * "NearestPointId" (index of the nearest input point), "NearestNormal" (that point's normal:
 * the input's "Normals" when present, otherwise estimated by local PCA and consistently
 * oriented, see ComputeNormals) and "InBand" (1 where all 8 surrounding voxels are in the band).
 * Field data: "ActiveVoxels", "VoxelSize", "BandWidth", "FieldMemoryBytes".
 *
 * @warning Points with NaN/Inf coordinates are dropped with a warning. An empty input, a
 * negative VoxelSize or BandWidth, or settings that would need more than
 * MaximumNumberOfVoxels voxels (or output samples) are errors with the numbers in the message;
 * nothing is allocated in that case. Sampling is multi-threaded (TBB).
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
  /** Voxel size of the field in world units; 0 (default) = bounding-box diagonal / 200. */
  vtkSetMacro(VoxelSize, double);
  vtkGetMacro(VoxelSize, double);
  ///@}

  ///@{
  /** Width of the band kept in the grid, in world units; 0 (default) = 3 voxels. */
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
  /** Refuse fields or outputs larger than this many voxels / samples (default 200 million). */
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

  double VoxelSize = 0.0;
  double BandWidth = 0.0;
  int Dimensions[3] = {128, 128, 128};
  double Bounds[6] = {-1.0, 1.0, -1.0, 1.0, -1.0, 1.0};
  vtkTypeBool AdjustBounds = true;
  double AdjustDistance = 0.05;
  vtkTypeBool ComputeNormals = true;
  vtkIdType MaximumNumberOfVoxels = 200000000;

private:
  vtkDistanceFieldFilter(const vtkDistanceFieldFilter&) = delete;
  void operator=(const vtkDistanceFieldFilter&) = delete;
};

#endif
