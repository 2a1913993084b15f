// SPDX-License-Identifier: BSD-3-Clause
// What the main job says once a stage is done: the frames it tracked, and the compression's
// figures (on the console and in report.json's "compression").
#pragma once

#include "JobState.h"

#include "dp/compress/CompressionOptions.h"
#include "dp/compress/PcaCompression.h"

class vtkPolyData;

namespace dp::cli
{

/** What was tracked, or that the run was interrupted, and a warning naming the frames that
 *  failed. */
void summariseTracking(const JobPaths& paths, const JobState& job);

/** The compressor's figures (`result`: vtkPCACompressFilter's output) into job.compression, and
 *  said: the detail layer's share, then the fit to the data or to the motion, as `options` judged
 *  the compression. */
void sayCompression(vtkPolyData* result, const dp::CompressedSequence& sequence,
                    const dp::CompressionOptions& options, const JobPaths& paths, JobState& job);

/** What the .glb holds: the tracked mesh, or a level of the detail layer. */
void sayGlb(const JobPaths& paths, const JobState& job);

} // namespace dp::cli
