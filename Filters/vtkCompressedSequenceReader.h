// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkCompressedSequenceReader
 * @brief   reads a compressed mesh sequence (.dpz, written by vtkPCACompressFilter) as a
 *          temporal vtkPolyData source
 *
 * RequestInformation reads and checks the whole file (magic, version, lengths, CRC-32 of the
 * header and of each zstd section; see dp::readCompressedSequence) and publishes its time steps;
 * a bad file is reported with its name and what is wrong, and the output stays empty. Each
 * request then rebuilds only the requested frame from the decoded basis and weights (3 Nv k
 * multiply-adds). Field data: "Components". A file with a colour stream (format version 2) gives
 * each frame's "Colors" (unsigned char, r g b, exactly as written) as the active scalars, so
 * ParaView shows them by default, and field data "ColourBytes" (the stream's size in the file).
 * A file with a detail layer (format version 3, vtkSurfaceDetailFilter's output compressed) gives
 * the fine mesh by default: the base subdivided and displaced along its normals
 * (dp::detailedFrame), with point data "Normals" (smooth shading), the colours carried to the
 * fine mesh, and field data "DetailLevels" and "DetailBytes"; ReadDetail off gives the base.
 */
#ifndef vtkCompressedSequenceReader_h
#define vtkCompressedSequenceReader_h

#include "DynamicPointsFiltersModule.h" // for export macro
#include "vtkPolyDataAlgorithm.h"

class DYNAMICPOINTSFILTERS_EXPORT vtkCompressedSequenceReader : public vtkPolyDataAlgorithm
{
public:
  static vtkCompressedSequenceReader* New();
  vtkTypeMacro(vtkCompressedSequenceReader, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /** The .dpz file. */
  vtkSetStringMacro(FileName);
  vtkGetStringMacro(FileName);
  ///@}

  ///@{
  /** With a detail layer in the file: the fine mesh (on, default) or the tracked base (off). */
  vtkSetMacro(ReadDetail, vtkTypeBool);
  vtkGetMacro(ReadDetail, vtkTypeBool);
  vtkBooleanMacro(ReadDetail, vtkTypeBool);
  ///@}

  /** 1 if `name` starts like a compressed sequence (for ParaView's reader choice). */
  int CanReadFile(const char* name);

protected:
  vtkCompressedSequenceReader();
  ~vtkCompressedSequenceReader() override;

  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* FileName = nullptr;
  vtkTypeBool ReadDetail = 1;

private:
  vtkCompressedSequenceReader(const vtkCompressedSequenceReader&) = delete;
  void operator=(const vtkCompressedSequenceReader&) = delete;

  struct Internals;
  Internals* Internal;
};

#endif
