// SPDX-License-Identifier: BSD-3-Clause
#include "vtkDPTemporalFilter.h"

#include "vtkDPPointSetAccess.h"

#include "vtkDataObject.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkStreamingDemandDrivenPipeline.h"

vtkDPTemporalFilter::vtkDPTemporalFilter() = default;
vtkDPTemporalFilter::~vtkDPTemporalFilter() = default;

int vtkDPTemporalFilter::RequestInformation(vtkInformation*, vtkInformationVector** inputVector,
                                            vtkInformationVector* outputVector)
{
  // Called again whenever this filter, an input or anything upstream changed.
  this->ClearTemporalState();
  this->TimeSteps = vtkDP::forwardTimeSteps(inputVector[0]->GetInformationObject(0),
                                            outputVector->GetInformationObject(0));
  return 1;
}

int vtkDPTemporalFilter::RequestUpdateExtent(vtkInformation*, vtkInformationVector** inputVector,
                                             vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  if (this->TimeSteps.empty() || vtkDP::isSecondaryPiece(outInfo))
    return 1;
  const long long next = this->NextInputFrame(this->GetRequestedFrame(outInfo));
  const double time =
      next >= 0 ? this->GetInputFrameTime(static_cast<std::size_t>(next)) : this->LastInputTime;
  inputVector[0]->GetInformationObject(0)->Set(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP(),
                                               time);
  this->LastInputTime = time;
  return 1;
}

int vtkDPTemporalFilter::RequestData(vtkInformation* request, vtkInformationVector** inputVector,
                                     vtkInformationVector* outputVector)
{
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  if (vtkDP::isSecondaryPiece(outInfo))
  {
    ContinueExecuting(request, false);
    vtkDataObject::GetData(outInfo)->Initialize();
    return 1;
  }
  return this->RequestFrameData(request, inputVector, outputVector);
}

std::size_t vtkDPTemporalFilter::GetNumberOfInputFrames() const
{
  return this->TimeSteps.empty() ? 1 : this->TimeSteps.size();
}

double vtkDPTemporalFilter::GetInputFrameTime(std::size_t frame) const
{
  return this->TimeSteps.empty() ? 0.0 : this->TimeSteps[frame];
}

std::size_t vtkDPTemporalFilter::GetRequestedFrame(vtkInformation* outInfo) const
{
  return vtkDP::requestedFrame(this->TimeSteps, outInfo);
}

void vtkDPTemporalFilter::ContinueExecuting(vtkInformation* request, bool more)
{
  if (more)
    request->Set(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING(), 1);
  else
    request->Remove(vtkStreamingDemandDrivenPipeline::CONTINUE_EXECUTING());
}

void vtkDPTemporalFilter::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "InputFrames: " << this->GetNumberOfInputFrames() << "\n";
}
