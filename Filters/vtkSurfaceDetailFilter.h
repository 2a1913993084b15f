// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkSurfaceDetailFilter
 * @brief   the detail layer: a tracked mesh subdivided and displaced onto each frame's data
 *
 * vtkSurfaceDetailFilter gives a tracked mesh (input 0: a temporal mesh of fixed connectivity,
 * e.g. vtkDeformableTrackFilter's output) the detail its frames' data hold (input 1: the same
 * take's points or per-frame meshes, e.g. vtkPointSequenceSource): each frame's mesh is
 * subdivided DetailLevels times by Loop's scheme (dp::SubdivisionMap: the same fine connectivity
 * every frame, a fixed linear map of the tracked vertices) and each fine vertex moved along the
 * subdivided surface's normal to where that line meets the frame's data
 * (dp::DisplacementFitter: a mesh frame read exactly, points as their local planes; holes,
 * stray parts and other surfaces spanned by a smooth membrane, never a spike). Detail that the
 * tracked mesh, at its coarser resolution, cannot carry (faces, fingers, folds) comes back; the
 * displacements, one number per fine vertex per frame, are what vtkPCACompressFilter codes
 * through the take beside the tracked motion.
 *
 * DetailLevels -1 (AUTOMATIC, the default) measures on the first frame: the level whose fine
 * mesh has about the capture's vertex count (or half its point count), kept when it lies at
 * least a fifth closer to the frame's data than the tracked mesh, else 0
 * (dp::chooseDetailLevels); GetLevelsUsed() and the field data "DetailLevels" and
 * "DetailChoice" say what was chosen. With 0 the tracked mesh passes through unchanged.
 *
 * The output at each time: the fine mesh with point data "Detail" (the displacement), "Normals"
 * (of the displaced mesh: smooth shading), "Observed" (1 where the normal line met the data,
 * 0 where the membrane spanned a gap), "Residual" (how far along its normal the vertex lies from
 * the data it met; -1 where it met none), and "Colors" (the tracked mesh's, carried by the same
 * map) where the input has them; field data: the input's (the tracker's per-frame figures,
 * "DataSamples", "DataReach", ...), and "DetailLevels", "DetailObserved" (the share observed),
 * "DetailSeconds", and the tracked mesh itself: "BasePoints" (its positions), "BaseTriangles"
 * and, with colour, "BaseColors", from which vtkPCACompressFilter codes the take.
 *
 * Each frame is fitted once and its displacements kept (8 bytes a fine vertex a frame): a walk
 * over the take (the compressor, a writer, playing) computes each frame once. Changing a property
 * or an input starts over.
 *
 * Limits: normal displacements only: detail the subdivided surface meets at a grazing angle (a
 * finger thinner than the tracked mesh's edge, a deep crease) stays out of reach; a frame whose
 * data hold no surface (no points, a coordinate that is not finite) gets none, with a warning:
 * its output is the subdivided tracked mesh.
 */
#ifndef vtkSurfaceDetailFilter_h
#define vtkSurfaceDetailFilter_h

#include "DynamicPointsFiltersModule.h" // for export macro
#include "vtkPolyDataAlgorithm.h"

class DYNAMICPOINTSFILTERS_EXPORT vtkSurfaceDetailFilter : public vtkPolyDataAlgorithm
{
public:
  static vtkSurfaceDetailFilter* New();
  vtkTypeMacro(vtkSurfaceDetailFilter, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /** The frames' data (input 1): points or per-frame meshes. */
  void SetDataConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }

  enum
  {
    AUTOMATIC = -1
  };
  ///@{
  /** Subdivision levels of the fine mesh: 0 (none: the tracked mesh passes through) to 6, or
   *  AUTOMATIC (-1, default: measured on the first frame). Each level has four times the
   *  triangles of the one before. */
  vtkSetClampMacro(DetailLevels, int, -1, 6);
  vtkGetMacro(DetailLevels, int);
  ///@}

  /** The levels in use: DetailLevels, or what AUTOMATIC chose (-1 before the first frame). */
  int GetLevelsUsed() const { return this->LevelsUsed; }

  ///@{
  /** The farthest a fine vertex is moved, in mean edge lengths of the tracked mesh (default 1). */
  vtkSetClampMacro(Reach, double, 0.01, 10.0);
  vtkGetMacro(Reach, double);
  ///@}

  ///@{
  /** Weight of the membrane term against the data's (default 0.02): higher smooths noise in
   *  point data away, and detail with it. */
  vtkSetClampMacro(Smoothness, double, 0.0, 100.0);
  vtkGetMacro(Smoothness, double);
  ///@}

  ///@{
  /** Data whose normal turns more than this from a fine vertex's (degrees, default 80) is
   *  another surface's (the other side of a thin part, a limb touching the body). */
  vtkSetClampMacro(NormalTestAngle, double, 1.0, 90.0);
  vtkGetMacro(NormalTestAngle, double);
  ///@}

protected:
  vtkSurfaceDetailFilter();
  ~vtkSurfaceDetailFilter() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  int DetailLevels;
  double Reach;
  double Smoothness;
  double NormalTestAngle;
  int LevelsUsed = -1;

private:
  /** The take's map and fitter for this base (made at the first frame); false on an error. */
  bool Prepare(vtkPolyData* base, vtkPointSet* data);
  /** Fits frame `frame` into the cache; false (said) on an error. */
  bool FitFrame(std::size_t frame, vtkPolyData* base, vtkPointSet* data);
  /** The output of a fitted frame. */
  void FillOutput(std::size_t frame, vtkPolyData* base, vtkPolyData* output);

  vtkSurfaceDetailFilter(const vtkSurfaceDetailFilter&) = delete;
  void operator=(const vtkSurfaceDetailFilter&) = delete;

  struct Internals;
  Internals* Internal;
};

#endif
