// SPDX-License-Identifier: BSD-3-Clause
#include "vtkCompressedSequenceWriter.h"

#include "dp/compress/PcaCompression.h"
#include "dp/export/GltfExport.h"

#include "vtkCallbackCommand.h"
#include "vtkCommand.h"
#include "vtkErrorCode.h"
#include "vtkExecutive.h"
#include "vtkInformation.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPCACompressFilter.h"
#include "vtkPolyData.h"

#include <vtksys/SystemTools.hxx>

#include <string>

vtkStandardNewMacro(vtkCompressedSequenceWriter);

vtkCompressedSequenceWriter::vtkCompressedSequenceWriter()
{
  // The codec's defaults (the engine's), not a copy of them.
  vtkNew<vtkPCACompressFilter> codec;
  this->Layout = codec->GetLayout();
  this->ErrorMeasure = codec->GetErrorMeasure();
  this->ErrorTarget = codec->GetErrorTarget();
  this->NumberOfComponents = codec->GetNumberOfComponents();
  this->ColourTolerance = codec->GetColourTolerance();
  this->MeshoptCompression = dp::GlbOptions().meshopt;
}

vtkCompressedSequenceWriter::~vtkCompressedSequenceWriter()
{
  this->SetFileName(nullptr);
}

int vtkCompressedSequenceWriter::FillInputPortInformation(int, vtkInformation* info)
{
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData");
  return 1;
}

namespace
{
// Shows the codec's progress as the writer's: "Saving tracked.dpz: PCA Compress: frame 3 of 30".
struct ProgressRelay
{
  vtkCompressedSequenceWriter* Writer;
  std::string File; // as users see it
};
void relayProgress(vtkObject* caller, unsigned long, void* clientData, void* callData)
{
  auto* relay = static_cast<ProgressRelay*>(clientData);
  auto* codec = vtkAlgorithm::SafeDownCast(caller);
  const std::string text =
      "Saving " + relay->File +
      (codec && codec->GetProgressText() ? std::string(": ") + codec->GetProgressText()
                                         : std::string());
  relay->Writer->SetProgressText(text.c_str());
  relay->Writer->UpdateProgress(*static_cast<double*>(callData));
}

bool endsWith(const std::string& name, const char* extension)
{
  const std::string lower = vtksys::SystemTools::LowerCase(name);
  const std::size_t n = std::char_traits<char>::length(extension);
  return lower.size() > n && lower.compare(lower.size() - n, n, extension) == 0;
}
// Runs `codec` on the writer's input with the writer's settings, its progress shown as the
// writer's; returns its failure, empty when none.
std::string compress(vtkCompressedSequenceWriter* writer, vtkPCACompressFilter* codec, bool glb)
{
  // The codec is a consumer of the writer's input of its own: it asks for every time step.
  codec->SetInputConnection(writer->GetInputConnection(0, 0));
  codec->SetLayout(glb ? vtkPCACompressFilter::SHAPES : writer->GetLayout()); // glTF: shapes
  codec->SetErrorMeasure(writer->GetErrorMeasure());
  codec->SetErrorTarget(writer->GetErrorTarget());
  codec->SetNumberOfComponents(writer->GetNumberOfComponents());
  codec->SetColourTolerance(writer->GetColourTolerance());
  ProgressRelay relay{writer, vtksys::SystemTools::GetFilenameName(writer->GetFileName())};
  vtkNew<vtkCallbackCommand> progress;
  progress->SetCallback(relayProgress);
  progress->SetClientData(&relay);
  codec->AddObserver(vtkCommand::ProgressEvent, progress);
  // Its errors become the writer's, with the file's name; not printed twice.
  vtkNew<vtkCallbackCommand> quiet;
  codec->AddObserver(vtkCommand::ErrorEvent, quiet);
  codec->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, quiet);
  codec->UpdatePiece(writer->GetPiece(), writer->GetNumberOfPieces(), 0);
  return codec->GetFailureMessage();
}
} // namespace

void vtkCompressedSequenceWriter::WriteData()
{
  const std::string name = this->FileName ? this->FileName : "";
  if (name.empty())
  {
    vtkErrorMacro(<< "no FileName to write to");
    this->SetErrorCode(vtkErrorCode::NoFileNameError);
    return;
  }
  const bool glb = endsWith(name, ".glb");
  vtkNew<vtkPCACompressFilter> codec;
  std::string failure = compress(this, codec, glb);
  const dp::CompressedSequence* sequence = codec->GetCompressedSequence();
  if (failure.empty() && sequence) // none on pieces other than 0: process 0 writes
  {
    // The engine's writers write beside the name and rename when complete: a failure never
    // leaves a broken file behind.
    try
    {
      if (glb)
      {
        dp::GlbOptions options;
        options.meshopt = this->MeshoptCompression;
        dp::writeGlb(name, *sequence, options);
      }
      else
        dp::writeCompressedSequence(name, *sequence);
    }
    catch (const std::exception& e)
    {
      failure = e.what();
    }
  }
  if (!failure.empty())
  {
    vtkErrorMacro(<< name << ": not written: " << failure);
    this->SetErrorCode(vtkErrorCode::UserError);
  }
}

void vtkCompressedSequenceWriter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
  os << indent << "Layout: " << this->Layout << "\n";
  os << indent << "ErrorMeasure: " << this->ErrorMeasure << "\n";
  os << indent << "ErrorTarget: " << this->ErrorTarget << "\n";
  os << indent << "NumberOfComponents: " << this->NumberOfComponents << "\n";
  os << indent << "ColourTolerance: " << this->ColourTolerance << "\n";
  os << indent << "MeshoptCompression: " << this->MeshoptCompression << "\n";
  os << indent << "Piece: " << this->Piece << " of " << this->NumberOfPieces << "\n";
}
