// SPDX-License-Identifier: BSD-3-Clause
#include "vtkCompressedSequenceWriter.h"

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
  this->MeshoptCompression = codec->GetGLBMeshoptCompression();
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
// Passes the codec's errors on as the writer's and its progress as the writer's progress.
struct Relay
{
  vtkCompressedSequenceWriter* Writer;
  std::string File; // as users see it in the progress text
  std::string Errors;
};
void relay(vtkObject* caller, unsigned long event, void* clientData, void* callData)
{
  auto* r = static_cast<Relay*>(clientData);
  if (event == vtkCommand::ProgressEvent)
  {
    // "Saving tracked.dpz: PCA Compress: frame 3 of 30", not the class names.
    auto* codec = vtkAlgorithm::SafeDownCast(caller);
    const std::string text =
        "Saving " + r->File +
        (codec && codec->GetProgressText() ? std::string(": ") + codec->GetProgressText()
                                           : std::string());
    r->Writer->SetProgressText(text.c_str());
    r->Writer->UpdateProgress(*static_cast<double*>(callData));
  }
  else if (event == vtkCommand::ErrorEvent && callData)
  {
    std::string text = static_cast<const char*>(callData);
    const std::size_t colon = text.find("): "); // drop VTK's "<class> (<address>): " prefix
    r->Errors += (r->Errors.empty() ? "" : "; ") +
                 (colon == std::string::npos ? text : text.substr(colon + 3));
  }
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
  const bool glb = name.size() > 4 && (name.compare(name.size() - 4, 4, ".glb") == 0 ||
                                       name.compare(name.size() - 4, 4, ".GLB") == 0);
  // The codec runs as its own consumer of our input: it asks the input for every time step.
  vtkNew<vtkPCACompressFilter> codec;
  codec->SetInputConnection(this->GetInputConnection(0, 0));
  codec->SetLayout(glb ? vtkPCACompressFilter::SHAPES : this->Layout);
  codec->SetErrorMeasure(this->ErrorMeasure);
  codec->SetErrorTarget(this->ErrorTarget);
  codec->SetNumberOfComponents(this->NumberOfComponents);
  codec->SetGLBMeshoptCompression(this->MeshoptCompression);
  if (glb)
    codec->SetGLBFileName(name.c_str());
  else
    codec->SetFileName(name.c_str());
  Relay state{this, vtksys::SystemTools::GetFilenameName(name), {}};
  vtkNew<vtkCallbackCommand> callback;
  callback->SetCallback(relay);
  callback->SetClientData(&state);
  codec->AddObserver(vtkCommand::ProgressEvent, callback);
  codec->AddObserver(vtkCommand::ErrorEvent, callback);
  codec->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, callback);
  codec->Update();
  if (!state.Errors.empty())
  {
    vtkErrorMacro(<< name << ": not written: " << state.Errors);
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
  os << indent << "MeshoptCompression: " << this->MeshoptCompression << "\n";
}
