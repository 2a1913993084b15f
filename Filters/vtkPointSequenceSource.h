// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkPointSequenceSource
 * @brief   reads a time series of point clouds, one file per frame, as a temporal source
 *
 * vtkPointSequenceSource publishes the time steps of a point sequence
 * (vtkStreamingDemandDrivenPipeline::TIME_STEPS and TIME_RANGE) and, on each request, reads
 * only the frame for the requested UPDATE_TIME_STEP: memory does not grow with the length of
 * the sequence. It is the input stage of the pipeline of Shinya, Shioya & Shiraishi,
 * "Unification of Dynamic Point Data" (Fig. 1: a time series of unregistered point clouds).
 *
 * The frames come from, in order of precedence:
 * - an explicit list (AddFileName()), kept in the given order;
 * - FileName: a ParaView `.series` JSON file (`{"file-series-version":"1.0","files":
 *   [{"name":"f0.ply","time":0.0}, ...]}`, times taken from it), or a single point file;
 * - DirectoryName + FilePattern (glob: `*`, `?`, `[...]`), sorted naturally
 *   (`2.ply` before `10.ply`).
 * Frames without explicit times are placed at `index * FrameInterval`.
 *
 * Formats: PLY (ASCII and binary of either endianness; normals, colours, other vertex
 * properties, faces), PCD (ascii, binary, binary_compressed as PCL writes it), XYZ / PTS /
 * CSV / TXT (x y z [nx ny nz], optional header naming the columns), OBJ, Draco (.drc), and VTK's .vtp,
 * .vtu and .vtk (read with VTK's own readers).
 *
 * The output is vtkPolyData with one vertex cell per point, the point arrays found in the file
 * ("Normals" as the active normals, "RGB"/"RGBA" colours as the active scalars, any other
 * property by its name) and the file's polygons when it has them. Field data holds
 * "FrameIndex" and "FileName". DATA_TIME_STEP is the frame's time.
 *
 * @warning Points with a NaN or infinite coordinate are dropped with a warning that counts them
 * (GetNumberOfDroppedPoints()). A missing, unreadable, truncated or malformed file, or an
 * unknown extension, is an error naming the file (ErrorEvent, GetErrorCode() set to
 * vtkErrorCode::FileFormatError, empty output, the request fails); an empty frame
 * is a warning and an empty output, so a downstream tracker can carry on.
 */
#ifndef vtkPointSequenceSource_h
#define vtkPointSequenceSource_h

#include "DynamicPointsFiltersModule.h" // for export macro
#include "vtkPolyDataAlgorithm.h"

class DYNAMICPOINTSFILTERS_EXPORT vtkPointSequenceSource : public vtkPolyDataAlgorithm
{
public:
  static vtkPointSequenceSource* New();
  vtkTypeMacro(vtkPointSequenceSource, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /**
   * A `.series` file, or a single point file (a one-frame sequence).
   * Used when no explicit file list was given.
   */
  vtkSetStringMacro(FileName);
  vtkGetStringMacro(FileName);
  ///@}

  ///@{
  /**
   * A folder of frames, and the glob pattern selecting them (default "*": every file with
   * a readable extension). Used when neither a file list nor FileName is set.
   */
  vtkSetStringMacro(DirectoryName);
  vtkGetStringMacro(DirectoryName);
  vtkSetStringMacro(FilePattern);
  vtkGetStringMacro(FilePattern);
  ///@}

  ///@{
  /**
   * An explicit list of frame files, in time order. Takes precedence over FileName and
   * DirectoryName.
   */
  void AddFileName(const char* fileName);
  void RemoveAllFileNames();
  int GetNumberOfFileNames();
  const char* GetFileName(int index);
  ///@}

  ///@{
  /**
   * Time between frames for sequences without explicit times (default 1).
   * Must be positive.
   */
  vtkSetClampMacro(FrameInterval, double, 1e-300, VTK_DOUBLE_MAX);
  vtkGetMacro(FrameInterval, double);
  ///@}

  /**
   * The number of frames of the current sequence (updates the pipeline information; -1 with
   * an error when the sequence cannot be listed).
   */
  int GetNumberOfFrames();

  /** The file and the time of frame i (after GetNumberOfFrames()); nullptr / 0 when out of range.
   */
  const char* GetFramePath(int frame);
  double GetFrameTime(int frame);

  /** Points dropped from the last frame read because of NaN/Inf coordinates. */
  vtkGetMacro(NumberOfDroppedPoints, vtkIdType);

  /** True when the extension is one this source reads. */
  static bool CanReadFile(const char* fileName);

protected:
  vtkPointSequenceSource();
  ~vtkPointSequenceSource() override;

  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* FileName = nullptr;
  char* DirectoryName = nullptr;
  char* FilePattern = nullptr;
  double FrameInterval = 1.0;
  vtkIdType NumberOfDroppedPoints = 0;

private:
  vtkPointSequenceSource(const vtkPointSequenceSource&) = delete;
  void operator=(const vtkPointSequenceSource&) = delete;

  bool BuildSequence();

  struct Internals;
  Internals* Internal;
};

#endif
