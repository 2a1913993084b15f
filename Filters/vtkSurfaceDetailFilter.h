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
  /** The levels in use: DetailLevels, or what AUTOMATIC chose (-1 before the first frame). */
  int GetLevelsUsed() const { return this->LevelsUsed; }

  ///@{
  /**
   * Any detail option by its name in dp::DetailOptions ("detail.reach") or its property name
   * ("Reach"); dp::detailOptions() describes them all (as does Documentation/Compression.md). A
   * value out of the option's range is clamped to it, as vtkSetClampMacro does; an unknown name
   * or a NaN is an error. The named accessors below are this under the property's name.
   */
  void SetDetailOption(const char* name, double value);
  double GetDetailOption(const char* name);
  ///@}

  // The named accessors of the table's options, written by build/bin/dp-option-code from the
  // table (dp/io/OptionCode.h): edit the table, not here.
  // BEGIN generated options: detail
  // clang-format off
  ///@{
  /** Subdivision levels of the fine mesh (0: none, the tracked mesh passes through; each level
   *  has four times the triangles of the one before). -1 (default): measured on the first frame:
   *  the level whose fine mesh has about the capture's vertex count (half its point count), kept
   *  where it lies at least a fifth closer to the data than the tracked mesh, else none
   *  (DetailChoice says what was measured). (detail.levels; range [-1, 6]) */
  void SetDetailLevels(int value) { this->SetDetailOption("DetailLevels", value); }
  int GetDetailLevels() { return static_cast<int>(this->GetDetailOption("DetailLevels")); }
  ///@}
  ///@{
  /** The farthest a fine vertex is moved onto the data, in mean edge lengths of the tracked mesh
   *  (default 1): data farther along its normal count as none. (detail.reach; range [0.01, 10],
   *  mean edge lengths) */
  void SetReach(double value) { this->SetDetailOption("Reach", value); }
  double GetReach() { return this->GetDetailOption("Reach"); }
  ///@}
  ///@{
  /** Weight of the membrane term against the data's (default 0.02): it spans holes; more smooths
   *  the noise of point data away, and detail with it. (detail.smoothness; range [0, 100]) */
  void SetSmoothness(double value) { this->SetDetailOption("Smoothness", value); }
  double GetSmoothness() { return this->GetDetailOption("Smoothness"); }
  ///@}
  ///@{
  /** Data whose surface normal turns more than this many degrees from a fine vertex's is another
   *  surface's (the other side of a thin part, a limb touching the body) and is not followed
   *  (default 80). (detail.normalAngle; range [1, 90], degrees) */
  void SetNormalTestAngle(double value) { this->SetDetailOption("NormalTestAngle", value); }
  double GetNormalTestAngle() { return this->GetDetailOption("NormalTestAngle"); }
  ///@}
  // clang-format on
  // END generated options

protected:
  vtkSurfaceDetailFilter();
  ~vtkSurfaceDetailFilter() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

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
