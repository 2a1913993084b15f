// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkDPTemporalFilter
 * @brief   base of the filters that read a temporal input frame by frame in one update
 *
 * The time bookkeeping vtkDeformableTrackFilter and vtkPCACompressFilter share (VTK 9.3's
 * vtkTemporalAlgorithm is the model; this project builds on VTK 9.2): the input's time steps are
 * published on the output; while a subclass needs input frames it names the next one
 * (NextInputFrame), the executive is asked to run again (CONTINUE_EXECUTING) and upstream is
 * asked for that frame's time; otherwise upstream is asked for the time it already has, so that
 * nothing upstream re-executes. Pieces other than 0 get an empty output: the sources hand the
 * whole frame to piece 0, so under MPI the work runs on process 0 alone.
 *
 * A subclass implements ClearTemporalState (called from RequestInformation: a property, the
 * input or anything upstream changed), NextInputFrame and RequestFrameData (RequestData on
 * piece 0), calling ContinueExecuting while it needs more frames.
 */
#ifndef vtkDPTemporalFilter_h
#define vtkDPTemporalFilter_h

#include "DynamicPointsFiltersModule.h" // for export macro
#include "vtkPolyDataAlgorithm.h"

#include <cstddef> // for std::size_t
#include <vector>  // for std::vector

class DYNAMICPOINTSFILTERS_EXPORT vtkDPTemporalFilter : public vtkPolyDataAlgorithm
{
public:
  vtkTypeMacro(vtkDPTemporalFilter, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

protected:
  vtkDPTemporalFilter();
  ~vtkDPTemporalFilter() override;

  /** Drops what was computed: the input or a property changed. */
  virtual void ClearTemporalState() = 0;
  /** The input frame the next pass needs for the output's `requestedFrame`, or -1 when the
   *  output is answered from what was computed (upstream then stays where it is). */
  virtual long long NextInputFrame(std::size_t requestedFrame) = 0;
  /** RequestData on piece 0. */
  virtual int RequestFrameData(vtkInformation* request, vtkInformationVector** inputVector,
                               vtkInformationVector* outputVector) = 0;

  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  /** Frames of the input: its time steps, 1 for a static input. */
  std::size_t GetNumberOfInputFrames() const;
  /** Time of input frame `frame` (0 for a static input). */
  double GetInputFrameTime(std::size_t frame) const;
  /** The frame the output request asks for (0 without a time). */
  std::size_t GetRequestedFrame(vtkInformation* outInfo) const;
  /** Asks the executive to run this filter again (true) or not (false) for the same request. */
  static void ContinueExecuting(vtkInformation* request, bool more);

private:
  vtkDPTemporalFilter(const vtkDPTemporalFilter&) = delete;
  void operator=(const vtkDPTemporalFilter&) = delete;

  std::vector<double> TimeSteps; // the input's; empty for a static input
  double LastInputTime = 0;      // the time upstream was last asked for
};

#endif
