// SPDX-License-Identifier: BSD-3-Clause
/**
 * VTK XML readers that work with expat >= 2.6 (and distributions' backports of it).
 *
 * Why: expat 2.6 defers re-parsing of incomplete tokens ("reparse deferral", the fix for
 * CVE-2023-52425). VTK <= 9.3's vtkXMLDataParser feeds the file to expat in chunks and stops
 * at the <AppendedData> marker, so with deferral on it misses elements and fails on any
 * .vtp/.vtu whose data is "appended" (the writers' default) once the file is a few kB:
 * "Error parsing XML ... junk after document element". Debian bookworm's ParaView 5.11 has
 * exactly this combination. VTK fixed it upstream by switching deferral off in the parser;
 * these readers do the same through vtkXMLReader's CreateXMLParser() hook.
 *
 * Limits: only for the readers created here (vtkPointSequenceSource's .vtp/.vtu frames);
 * other readers in the same process keep the platform's behaviour.
 */
#ifndef vtkDPXMLReaders_h
#define vtkDPXMLReaders_h

#include "vtkXMLPolyDataReader.h"
#include "vtkXMLUnstructuredGridReader.h"

class vtkDPXMLPolyDataReader : public vtkXMLPolyDataReader
{
public:
  static vtkDPXMLPolyDataReader* New();
  vtkTypeMacro(vtkDPXMLPolyDataReader, vtkXMLPolyDataReader);

protected:
  vtkDPXMLPolyDataReader() = default;
  void CreateXMLParser() override;
};

class vtkDPXMLUnstructuredGridReader : public vtkXMLUnstructuredGridReader
{
public:
  static vtkDPXMLUnstructuredGridReader* New();
  vtkTypeMacro(vtkDPXMLUnstructuredGridReader, vtkXMLUnstructuredGridReader);

protected:
  vtkDPXMLUnstructuredGridReader() = default;
  void CreateXMLParser() override;
};

#endif
