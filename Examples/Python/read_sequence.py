"""Read a point sequence with DynamicPoints from plain Python and look at it with numpy.

    PYTHONPATH=build/lib/python3/dist-packages /usr/bin/python3 \
        Examples/Python/read_sequence.py FOLDER_OR_SERIES

Without an argument it makes a small sequence first with dynamicpoints-sample (found next to
this build, or on PATH).
"""
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np
from vtkmodules.numpy_interface import dataset_adapter as dsa

import dynamicpoints


def main(argv):
    if len(argv) > 1:
        target = argv[1]
    else:
        sampler = shutil.which("dynamicpoints-sample") or os.path.join(
            os.environ.get("DP_BIN_DIR", "build/bin"), "dynamicpoints-sample")
        target = os.path.join(tempfile.mkdtemp(prefix="dp-example-"), "seq")
        subprocess.run([sampler, "--mesh", "sheet", "--frames", "8", "--points", "5000",
                        "--noise", "0.002", target], check=True)

    source = dynamicpoints.vtkPointSequenceSource()
    if os.path.isdir(target):
        source.SetDirectoryName(target)
    else:
        source.SetFileName(target)
    frames = source.GetNumberOfFrames()
    if frames < 0:
        return 1
    print(f"{frames} frames")
    for frame in range(frames):
        source.UpdateTimeStep(source.GetFrameTime(frame))
        data = dsa.WrapDataObject(source.GetOutput())
        points = np.asarray(data.Points)
        centroid = points.mean(axis=0)
        spread = np.sqrt(((points - centroid) ** 2).sum(axis=1).mean())
        print(f"frame {frame:3d}  t={source.GetFrameTime(frame):6.2f}  {len(points):6d} points  "
              f"centroid {np.round(centroid, 3)}  rms spread {spread:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
