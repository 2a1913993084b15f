// SPDX-License-Identifier: BSD-3-Clause
#include "vtkPointSequenceSource.h"

#include "dp/io/FrameSequence.h"
#include "dp/io/PointCloudIO.h"

#include "vtkCellArray.h"
#include "vtkCellArrayIterator.h"
#include "vtkCommand.h"
#include "vtkDPPointSetAccess.h"
#include "vtkDPXMLReaders.h"
#include "vtkDoubleArray.h"
#include "vtkErrorCode.h"
#include "vtkExecutive.h"
#include "vtkFieldData.h"
#include "vtkFloatArray.h"
#include "vtkGenericDataObjectReader.h"
#include "vtkIdTypeArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkStringArray.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkPointSequenceSource);

struct vtkPointSequenceSource::Internals
{
  std::vector<std::string> FileNames;
  dp::FrameSequence Sequence;
  vtkTimeStamp SequenceBuilt;
  bool SequenceValid = false;
};

namespace
{

// Collects the errors a VTK reader reports, so they become one message naming the file
// instead of text in the output window.
class ErrorCollector : public vtkCommand
{
public:
  static ErrorCollector* New() { return new ErrorCollector; }
  void Execute(vtkObject*, unsigned long, void* callData) override
  {
    if (callData)
    {
      Messages << (Messages.tellp() > 0 ? "; " : "") << static_cast<const char*>(callData);
    }
    Failed = true;
  }
  std::ostringstream Messages;
  bool Failed = false;
};

vtkSmartPointer<vtkIdTypeArray> toIdArray(const std::vector<std::int64_t>& values)
{
  auto array = vtkSmartPointer<vtkIdTypeArray>::New();
  array->SetNumberOfValues(static_cast<vtkIdType>(values.size()));
  std::copy(values.begin(), values.end(), array->GetPointer(0));
  return array;
}

// One vertex cell per point: ParaView and most VTK filters only see points through cells.
vtkSmartPointer<vtkCellArray> vertexCells(vtkIdType n)
{
  auto offsets = vtkSmartPointer<vtkIdTypeArray>::New();
  auto connectivity = vtkSmartPointer<vtkIdTypeArray>::New();
  offsets->SetNumberOfValues(n + 1);
  connectivity->SetNumberOfValues(n);
  for (vtkIdType i = 0; i < n; ++i)
  {
    offsets->SetValue(i, i);
    connectivity->SetValue(i, i);
  }
  offsets->SetValue(n, n);
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  cells->SetData(offsets, connectivity);
  return cells;
}

void cloudToPolyData(const dp::PointCloud& cloud, vtkPolyData* output)
{
  const auto n = static_cast<vtkIdType>(cloud.numberOfPoints());
  vtkNew<vtkDoubleArray> coordinates;
  coordinates->SetNumberOfComponents(3);
  coordinates->SetNumberOfTuples(n);
  std::copy(cloud.points.begin(), cloud.points.end(), coordinates->GetPointer(0));
  vtkNew<vtkPoints> points;
  points->SetData(coordinates);
  output->SetPoints(points);
  output->SetVerts(vertexCells(n));
  if (cloud.numberOfFaces() > 0)
  {
    vtkNew<vtkCellArray> polys;
    polys->SetData(toIdArray(cloud.faceOffsets), toIdArray(cloud.faceConnectivity));
    output->SetPolys(polys);
  }
  vtkPointData* pd = output->GetPointData();
  if (cloud.hasNormals())
  {
    vtkNew<vtkFloatArray> normals;
    normals->SetName("Normals");
    normals->SetNumberOfComponents(3);
    normals->SetNumberOfTuples(n);
    std::copy(cloud.normals.begin(), cloud.normals.end(), normals->GetPointer(0));
    pd->SetNormals(normals);
  }
  if (cloud.hasColors())
  {
    vtkNew<vtkUnsignedCharArray> colors;
    colors->SetName(cloud.colorComponents == 4 ? "RGBA" : "RGB");
    colors->SetNumberOfComponents(cloud.colorComponents);
    colors->SetNumberOfTuples(n);
    std::copy(cloud.colors.begin(), cloud.colors.end(), colors->GetPointer(0));
    pd->SetScalars(colors);
  }
  for (const auto& attribute : cloud.attributes)
  {
    vtkNew<vtkFloatArray> array;
    array->SetName(attribute.name.c_str());
    array->SetNumberOfComponents(attribute.components);
    array->SetNumberOfTuples(n);
    std::copy(attribute.values.begin(), attribute.values.end(), array->GetPointer(0));
    pd->AddArray(array);
  }
}

// The point set in a .vtp / .vtu / .vtk file, read by VTK's readers; a FileError naming the file
// and the reader's complaint when it cannot be read or holds no points.
vtkSmartPointer<vtkPointSet> readPointSet(const std::string& path, dp::PointFileFormat format)
{
  if (!std::ifstream(path).good())
  {
    throw dp::FileError(path, "cannot open file (missing or unreadable)");
  }
  vtkSmartPointer<vtkAlgorithm> reader;
  if (format == dp::PointFileFormat::VTKXMLPolyData)
  {
    auto r = vtkSmartPointer<vtkDPXMLPolyDataReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else if (format == dp::PointFileFormat::VTKXMLUnstructuredGrid)
  {
    auto r = vtkSmartPointer<vtkDPXMLUnstructuredGridReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  else
  {
    auto r = vtkSmartPointer<vtkGenericDataObjectReader>::New();
    r->SetFileName(path.c_str());
    reader = r;
  }
  vtkNew<ErrorCollector> errors;
  reader->AddObserver(vtkCommand::ErrorEvent, errors);
  reader->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, errors);
  reader->Update();
  if (errors->Failed || reader->GetErrorCode() != 0)
  {
    const std::string what = errors->Messages.str();
    throw dp::FileError(path, "VTK reader failed" + (what.empty() ? std::string() : ": " + what));
  }
  vtkSmartPointer<vtkPointSet> input = vtkPointSet::SafeDownCast(reader->GetOutputDataObject(0));
  if (!input)
  {
    throw dp::FileError(path, "holds no point set (only polydata, unstructured or structured "
                              "grids have points to read)");
  }
  return input;
}

// The input's points with finite coordinates, and their point data, into `output`; each input
// point's index there (-1: dropped).
std::vector<vtkIdType> copyFinitePoints(vtkPointSet* input, vtkPolyData* output)
{
  const vtkIdType n = input->GetNumberOfPoints();
  std::vector<vtkIdType> newIndex(n, -1);
  vtkIdType kept = 0;
  for (vtkIdType i = 0; i < n; ++i)
  {
    double p[3];
    input->GetPoint(i, p);
    if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))
      newIndex[i] = kept++;
  }
  if (kept == n)
  {
    if (n > 0)
      output->SetPoints(input->GetPoints());
    output->GetPointData()->ShallowCopy(input->GetPointData());
  }
  else
  {
    vtkNew<vtkPoints> points;
    points->SetDataType(input->GetPoints()->GetDataType());
    points->SetNumberOfPoints(kept);
    vtkPointData* outPD = output->GetPointData();
    outPD->CopyAllocate(input->GetPointData(), kept);
    for (vtkIdType i = 0; i < n; ++i)
      if (newIndex[i] >= 0)
      {
        points->SetPoint(newIndex[i], input->GetPoint(i));
        outPD->CopyData(input->GetPointData(), i, newIndex[i]);
      }
    output->SetPoints(points);
  }
  output->SetVerts(vertexCells(kept));
  return newIndex;
}

// The polygons whose points were all kept, renumbered, into `output`.
void copyKeptPolygons(vtkPolyData* input, const std::vector<vtkIdType>& newIndex,
                      vtkPolyData* output)
{
  vtkNew<vtkCellArray> polys;
  const vtkIdType* ids = nullptr;
  vtkIdType count = 0;
  std::vector<vtkIdType> face;
  auto iter = vtk::TakeSmartPointer(input->GetPolys()->NewIterator());
  for (iter->GoToFirstCell(); !iter->IsDoneWithTraversal(); iter->GoToNextCell())
  {
    iter->GetCurrentCell(count, ids);
    face.assign(ids, ids + count);
    bool valid = true;
    for (auto& id : face)
    {
      valid = valid && newIndex[id] >= 0;
      id = valid ? newIndex[id] : 0;
    }
    if (valid)
      polys->InsertNextCell(count, face.data());
  }
  output->SetPolys(polys);
}

// Reads .vtp / .vtu / .vtk with VTK's readers into `output` (points, point data, polygons).
// Returns the number of points dropped for non-finite coordinates.
vtkIdType readVTKFile(const std::string& path, dp::PointFileFormat format, vtkPolyData* output)
{
  const vtkSmartPointer<vtkPointSet> input = readPointSet(path, format);
  const std::vector<vtkIdType> newIndex = copyFinitePoints(input, output);
  vtkPolyData* inputPolys = vtkPolyData::SafeDownCast(input);
  if (inputPolys && inputPolys->GetNumberOfPolys() > 0)
    copyKeptPolygons(inputPolys, newIndex, output);
  return static_cast<vtkIdType>(std::count(newIndex.begin(), newIndex.end(), -1));
}

bool isSeriesFile(const std::string& name)
{
  return name.size() > 7 && name.compare(name.size() - 7, 7, ".series") == 0;
}

// A .series file lists the frames; any other file is a one-frame sequence.
dp::FrameSequence sequenceFromOneFile(const std::string& name, double frameInterval)
{
  return isSeriesFile(name) ? dp::FrameSequence::fromSeriesFile(name)
                            : dp::FrameSequence::fromFiles({name}, frameInterval);
}

// Reads a frame's file into output, with the engine's readers or VTK's by its extension; returns
// the points dropped for non-finite coordinates. Throws for an unknown extension or an
// unreadable file.
vtkIdType readFrame(const std::string& path, vtkPolyData* output)
{
  const dp::PointFileFormat format = dp::formatFromFileName(path);
  if (dp::isEngineFormat(format))
  {
    dp::ReadReport report;
    const dp::PointCloud cloud = dp::readPointCloud(path, &report);
    cloudToPolyData(cloud, output);
    return static_cast<vtkIdType>(report.droppedNonFinite);
  }
  if (format != dp::PointFileFormat::Unknown)
    return readVTKFile(path, format, output);
  throw dp::FileError(path,
                      std::string("unknown file extension; readable: ") + dp::readableExtensions());
}

// The field data naming the frame: FrameIndex and FileName.
void addFrameIdentity(vtkPolyData* output, std::size_t index, const std::string& path)
{
  vtkNew<vtkIntArray> frameIndex;
  frameIndex->SetName("FrameIndex");
  frameIndex->InsertNextValue(static_cast<int>(index));
  output->GetFieldData()->AddArray(frameIndex);
  vtkNew<vtkStringArray> fileName;
  fileName->SetName("FileName");
  fileName->InsertNextValue(path);
  output->GetFieldData()->AddArray(fileName);
}

// The frame the output request asks for (the first without a time).
std::size_t requestedIndex(const dp::FrameSequence& sequence, vtkInformation* outInfo)
{
  if (!outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
    return 0;
  return sequence.frameAtTime(outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()));
}

// The progress text while frame `index` (of `frames`) is read.
std::string progressText(std::size_t index, std::size_t frames)
{
  return "Point Sequence Reader: frame " + std::to_string(index + 1) + " of " +
         std::to_string(frames);
}
} // namespace

vtkPointSequenceSource::vtkPointSequenceSource() : Internal(new Internals)
{
  this->SetNumberOfInputPorts(0);
  this->SetFilePattern("*");
}

vtkPointSequenceSource::~vtkPointSequenceSource()
{
  this->SetFileName(nullptr);
  this->SetDirectoryName(nullptr);
  this->SetFilePattern(nullptr);
  delete this->Internal;
}

void vtkPointSequenceSource::AddFileName(const char* fileName)
{
  if (fileName)
  {
    this->Internal->FileNames.emplace_back(fileName);
    this->Modified();
  }
}

void vtkPointSequenceSource::RemoveAllFileNames()
{
  if (!this->Internal->FileNames.empty())
  {
    this->Internal->FileNames.clear();
    this->Modified();
  }
}

int vtkPointSequenceSource::GetNumberOfFileNames()
{
  return static_cast<int>(this->Internal->FileNames.size());
}

const char* vtkPointSequenceSource::GetFileName(int index)
{
  if (index < 0 || index >= this->GetNumberOfFileNames())
    return nullptr;
  return this->Internal->FileNames[index].c_str();
}

bool vtkPointSequenceSource::CanReadFile(const char* fileName)
{
  if (!fileName)
    return false;
  const std::string name(fileName);
  return dp::formatFromFileName(name) != dp::PointFileFormat::Unknown || isSeriesFile(name);
}

bool vtkPointSequenceSource::BuildSequence()
{
  Internals& in = *this->Internal;
  if (in.SequenceValid && in.SequenceBuilt > this->GetMTime())
    return true;
  in.SequenceValid = false;
  try
  {
    if (in.FileNames.size() == 1)
    {
      // One name (ParaView's file dialog passes a lone .series this way): same as FileName.
      in.Sequence = sequenceFromOneFile(in.FileNames[0], this->FrameInterval);
    }
    else if (!in.FileNames.empty())
    {
      in.Sequence = dp::FrameSequence::fromFiles(in.FileNames, this->FrameInterval);
    }
    else if (this->FileName && *this->FileName)
    {
      in.Sequence = sequenceFromOneFile(this->FileName, this->FrameInterval);
    }
    else if (this->DirectoryName && *this->DirectoryName)
    {
      in.Sequence = dp::FrameSequence::fromDirectory(
          this->DirectoryName, this->FilePattern ? this->FilePattern : "*", this->FrameInterval);
    }
    else
    {
      vtkErrorMacro("No input: set FileName (a .series or point file), DirectoryName (with "
                    "FilePattern), or add file names.");
      return false;
    }
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    return false;
  }
  in.SequenceValid = true;
  in.SequenceBuilt.Modified();
  return true;
}

int vtkPointSequenceSource::GetNumberOfFrames()
{
  this->UpdateInformation();
  return this->Internal->SequenceValid ? static_cast<int>(this->Internal->Sequence.size()) : -1;
}

const char* vtkPointSequenceSource::GetFramePath(int frame)
{
  const auto& s = this->Internal->Sequence;
  if (!this->Internal->SequenceValid || frame < 0 || frame >= static_cast<int>(s.size()))
    return nullptr;
  return s[frame].path.c_str();
}

double vtkPointSequenceSource::GetFrameTime(int frame)
{
  const auto& s = this->Internal->Sequence;
  if (!this->Internal->SequenceValid || frame < 0 || frame >= static_cast<int>(s.size()))
    return 0.0;
  return s[frame].time;
}

int vtkPointSequenceSource::RequestInformation(vtkInformation*, vtkInformationVector**,
                                               vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  outInfo->Remove(vtkStreamingDemandDrivenPipeline::TIME_STEPS());
  outInfo->Remove(vtkStreamingDemandDrivenPipeline::TIME_RANGE());
  if (!this->BuildSequence())
    return 0;
  std::vector<double> times;
  for (const auto& frame : this->Internal->Sequence.frames())
    times.push_back(frame.time);
  outInfo->Set(vtkStreamingDemandDrivenPipeline::TIME_STEPS(), times.data(),
               static_cast<int>(times.size()));
  const double range[2] = {times.front(), times.back()};
  outInfo->Set(vtkStreamingDemandDrivenPipeline::TIME_RANGE(), range, 2);
  return 1;
}

int vtkPointSequenceSource::RequestData(vtkInformation*, vtkInformationVector**,
                                        vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkPolyData* output = vtkPolyData::GetData(outInfo);
  this->NumberOfDroppedPoints = 0;
  this->SetErrorCode(vtkErrorCode::NoError);
  if (!this->BuildSequence())
    return 0;
  const dp::FrameSequence& sequence = this->Internal->Sequence;
  const std::size_t index = requestedIndex(sequence, outInfo);
  const dp::Frame& frame = sequence[index];
  output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), frame.time);
  this->SetProgressText(progressText(index, sequence.size()).c_str());

  try
  {
    this->NumberOfDroppedPoints = readFrame(frame.path, output);
  }
  catch (const std::exception& e)
  {
    output->Initialize();
    output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), frame.time);
    this->SetErrorCode(vtkErrorCode::FileFormatError);
    vtkErrorMacro(<< "frame " << index << ": " << e.what());
    // An empty output that says so, not a failed request: a failure upstream of a filter that
    // computes frame after frame (CONTINUE_EXECUTING) keeps VTK's executive asking again forever,
    // while this lets it stop with the frames before kept (vtkDeformableTrackFilter).
    vtkDP::addFieldValue(output, "UnreadableFrame", static_cast<double>(index));
    return 1;
  }

  if (this->NumberOfDroppedPoints > 0)
  {
    vtkWarningMacro(<< frame.path << ": dropped " << this->NumberOfDroppedPoints
                    << " point(s) with NaN or infinite coordinates (frame " << index << ")");
  }
  if (output->GetNumberOfPoints() == 0)
  {
    vtkWarningMacro(<< frame.path << ": empty frame (no points), frame " << index);
  }

  addFrameIdentity(output, index, frame.path);
  this->UpdateProgress(1.0);
  return 1;
}

void vtkPointSequenceSource::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
  os << indent << "DirectoryName: " << (this->DirectoryName ? this->DirectoryName : "(none)")
     << "\n";
  os << indent << "FilePattern: " << (this->FilePattern ? this->FilePattern : "(none)") << "\n";
  os << indent << "NumberOfFileNames: " << this->Internal->FileNames.size() << "\n";
  os << indent << "FrameInterval: " << this->FrameInterval << "\n";
  os << indent << "NumberOfDroppedPoints: " << this->NumberOfDroppedPoints << "\n";
}
