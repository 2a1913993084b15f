// SPDX-License-Identifier: BSD-3-Clause
#include "vtkCompressedSequenceWriter.h"

#include "dp/compress/CompressionOptions.h"
#include "dp/compress/PcaCompression.h"
#include "dp/export/GltfExport.h"

#include "vtkCallbackCommand.h"
#include "vtkCommand.h"
#include "vtkDPOptions.h"
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

vtkCompressedSequenceWriter::vtkCompressedSequenceWriter() : Options(new dp::CompressionOptions)
{
  this->MeshoptCompression = dp::GlbOptions().meshopt;
}

vtkCompressedSequenceWriter::~vtkCompressedSequenceWriter()
{
  this->SetFileName(nullptr);
  delete this->Options;
}

void vtkCompressedSequenceWriter::SetCompressionOption(const char* name, double value)
{
  std::string error;
  if (name && dp::compressionOptions().has(name) &&
      dp::compressionOptions().find(name).name == "compression.quantise")
    error = "the writers always quantise (compression.quantise is vtkPCACompressFilter's)";
  else if (vtkDP::setOption(dp::compressionOptions(), *this->Options, name, value, error))
    this->Modified();
  if (!error.empty())
    vtkErrorMacro(<< error);
}

double vtkCompressedSequenceWriter::GetCompressionOption(const char* name)
{
  std::string error;
  const double v = vtkDP::getOption(dp::compressionOptions(), *this->Options, name, error);
  if (!error.empty())
    vtkErrorMacro(<< error);
  return v;
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
std::string compress(vtkCompressedSequenceWriter* writer, vtkPCACompressFilter* codec,
                     const dp::CompressionOptions& writerOptions, bool glb)
{
  // The codec is a consumer of the writer's input of its own: it asks for every time step.
  codec->SetInputConnection(writer->GetInputConnection(0, 0));
  dp::CompressionOptions options = writerOptions;
  if (glb)
    options.layout = dp::PcaLayout::Shapes; // what glTF's morph targets hold
  codec->SetCompressionOptions(options);
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
  std::string failure = compress(this, codec, *this->Options, glb);
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
  for (const auto& option : dp::compressionOptions())
    if (option.name != "compression.quantise")
      os << indent << option.name << ": " << option.said(option.get(*this->Options)) << "\n";
  os << indent << "MeshoptCompression: " << this->MeshoptCompression << "\n";
  os << indent << "Piece: " << this->Piece << " of " << this->NumberOfPieces << "\n";
}
