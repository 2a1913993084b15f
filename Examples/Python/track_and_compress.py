"""The whole job from plain Python: read a point sequence, track it with one mesh, compress the
tracked sequence, and look at every stage with numpy.

    PYTHONPATH=build/lib/python3/dist-packages /usr/bin/python3 \\
        Examples/Python/track_and_compress.py [FOLDER_OR_SERIES [OUTPUT_FOLDER]]

Without arguments it makes a sequence first with dynamicpoints-sample (found next to this
build, or on PATH): the bending tube, 20 frames of 5000 noisy points. It writes
OUTPUT_FOLDER/tracked.dpz and tracked.glb, and OUTPUT_FOLDER/trajectories.npy (frames x
vertices x 3, the tracked vertex positions) for further work in numpy; then the detail layer
(the tracked mesh subdivided twice and displaced onto each frame's points) compressed with it
into OUTPUT_FOLDER/detailed.dpz.
"""
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np
from vtkmodules.numpy_interface import dataset_adapter as dsa

import dynamicpoints


def make_sequence(folder):
    sampler = shutil.which("dynamicpoints-sample") or os.path.join(
        os.environ.get("DP_BIN_DIR", "build/bin"), "dynamicpoints-sample")
    subprocess.run([sampler, "--frames", "20", "--points", "5000", "--noise", "0.001", folder],
                   check=True, capture_output=True)
    return os.path.join(folder, "points.series")


def main(argv):
    work = tempfile.mkdtemp(prefix="dp-example-")
    target = argv[1] if len(argv) > 1 else make_sequence(os.path.join(work, "seq"))
    output = argv[2] if len(argv) > 2 else os.path.join(work, "out")
    os.makedirs(output, exist_ok=True)

    source = dynamicpoints.vtkPointSequenceSource()
    if os.path.isdir(target):
        source.SetDirectoryName(target)
    else:
        source.SetFileName(target)
    frames = source.GetNumberOfFrames()
    if frames < 1:
        return 1  # the source has printed why

    tracker = dynamicpoints.vtkDeformableTrackFilter()
    tracker.SetInputConnection(source.GetOutputPort())
    tracker.SetTemplateVertices(600)  # no template: one is reconstructed from frame 0

    compressor = dynamicpoints.vtkPCACompressFilter()
    compressor.SetInputConnection(tracker.GetOutputPort())
    compressor.SetKGTarget(0.2)  # Karni-Gotsman error, percent

    print(f"{frames} frames from {target}")
    print(f"{'frame':>5} {'points':>7} {'rms dist':>10} {'moved':>8} {'max compr. err':>15}")
    trajectories = []
    for frame in range(frames):
        time = source.GetFrameTime(frame)
        tracker.UpdateTimeStep(time)  # frames are tracked in order and cached
        mesh = dsa.WrapDataObject(tracker.GetOutput())
        residual = np.asarray(mesh.PointData["Residual"])  # distance to the frame's points
        moved = np.linalg.norm(np.asarray(mesh.PointData["Displacement"]), axis=1)
        trajectories.append(np.array(mesh.Points))
        compressor.UpdateTimeStep(time)  # the first call compresses the whole sequence
        error = np.asarray(dsa.WrapDataObject(compressor.GetOutput()).PointData["CompressionError"])
        points = source.GetOutput().GetNumberOfPoints()
        print(f"{frame:5d} {points:7d} {np.sqrt((residual ** 2).mean()):10.3g} "
              f"{moved.mean():8.3f} {error.max():15.3g}")

    trajectories = np.stack(trajectories)
    np.save(os.path.join(output, "trajectories.npy"), trajectories)
    figures = dsa.WrapDataObject(compressor.GetOutput()).FieldData
    print(f"tracked mesh: {trajectories.shape[1]} vertices, "
          f"{tracker.GetOutput().GetNumberOfPolys()} triangles")
    print(f"compressed: {int(figures['Components'][0])} components, "
          f"{figures['BitsPerVertexFrame'][0]:.3g} bits per vertex per frame, "
          f"KG error {figures['KGError'][0]:.3g}%")

    # The files: a writer compresses with the same settings (the tracker answers every frame
    # from its cache) and writes the format its file name's extension says.
    writer = dynamicpoints.vtkCompressedSequenceWriter()
    writer.SetInputConnection(tracker.GetOutputPort())
    writer.SetKGTarget(compressor.GetKGTarget())
    for name in ("tracked.dpz", "tracked.glb"):
        writer.SetFileName(os.path.join(output, name))
        if writer.Write() != 1:
            return 1  # the writer has printed why
    # The detail layer: the tracked mesh subdivided twice (Loop), each fine vertex moved along
    # its normal onto the frame's points; its data from a source of its own.
    data = dynamicpoints.vtkPointSequenceSource()
    data.SetFileName(source.GetFileName())
    data.SetDirectoryName(source.GetDirectoryName())
    detail = dynamicpoints.vtkSurfaceDetailFilter()
    detail.SetInputConnection(0, tracker.GetOutputPort())
    detail.SetInputConnection(1, data.GetOutputPort())
    detail.SetDetailLevels(2)
    detail.UpdateTimeStep(source.GetFrameTime(frames - 1))
    fine = dsa.WrapDataObject(detail.GetOutput())
    residual = np.asarray(fine.PointData["Residual"])
    print(f"detail layer: {detail.GetOutput().GetNumberOfPoints()} vertices; the last frame's "
          f"lie {np.sqrt((residual[residual >= 0] ** 2).mean()):.3g} from its points (RMS)")
    writer.SetInputConnection(detail.GetOutputPort())
    writer.SetFileName(os.path.join(output, "detailed.dpz"))
    if writer.Write() != 1:
        return 1
    print(f"wrote {output}: tracked.dpz tracked.glb trajectories.npy detailed.dpz")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
