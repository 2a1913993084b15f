#!/usr/bin/env python3
"""Decoding time a frame of .dpz files, as a player reads them: vtkCompressedSequenceReader.

For each file: the file read and decoded (the reader's RequestInformation: read, every checksum
checked, the geometry, colour and detail layer range-decoded), then every frame given in order
(UpdateTimeStep: the frame reconstructed from its components; with a detail layer the fine mesh
subdivided, displaced and given normals), once with the detail layer (the reader's default) and
once without it (Read Detail off: the tracked mesh). Prints each pass's figures, the medians of
--repeats runs (a fresh reader each): the whole file's decoding in ms, the frames in ms a frame,
and their sum over the frames (what a player pays a frame, file included). VTK's and TBB's own
threads as they come (all the machine's).

    PYTHONPATH=build/lib/python3/dist-packages /usr/bin/python3 \\
        Testing/Benchmarks/BenchmarkDecoding.py [--repeats 5] FILE.dpz [FILE.dpz ...]
"""
import argparse
import os
import statistics
import sys
import time

try:
    import dynamicpoints
except ImportError:
    sys.exit("dynamicpoints not found: PYTHONPATH=build/lib/python3/dist-packages, "
             "/usr/bin/python3")


def machine():
    try:
        with open("/proc/cpuinfo") as f:
            model = next(line.split(":", 1)[1].strip() for line in f
                         if line.startswith("model name"))
    except (OSError, StopIteration):
        model = "unknown CPU"
    return f"{model}, {os.cpu_count()} hardware threads"


def one_pass(path, detail):
    """One fresh reader over the file: (decode s, frames s, frames, vertices given, whether they
    are a detail layer's)."""
    reader = dynamicpoints.vtkCompressedSequenceReader()
    reader.SetFileName(path)
    reader.SetReadDetail(detail)
    started = time.perf_counter()
    reader.UpdateInformation()
    decoded = time.perf_counter()
    times = reader.GetOutputInformation(0).Get(reader.GetExecutive().TIME_STEPS())
    if not times:
        sys.exit(f"{path}: the reader gave no frames")
    for t in times:
        reader.UpdateTimeStep(t)
    done = time.perf_counter()
    output = reader.GetOutput()
    layered = output.GetFieldData().GetArray("DetailLevels") is not None
    return decoded - started, done - decoded, len(times), output.GetNumberOfPoints(), layered


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("files", nargs="+", metavar="FILE.dpz")
    a = parser.parse_args()
    print(f"machine: {machine()}; medians of {a.repeats} runs, a fresh reader each")
    for path in a.files:
        print(f"\n== {path}: {os.path.getsize(path)} bytes")
        has_layer = False
        for detail in (True, False):
            runs = [one_pass(path, detail) for _ in range(a.repeats)]
            _, _, frames, vertices, layered = runs[0]
            if detail and not layered:
                continue  # no detail layer: the pass without it gives the same
            has_layer = has_layer or layered
            decode_ms = 1000 * statistics.median(r[0] for r in runs)
            frame_ms = 1000 * statistics.median(r[1] for r in runs) / frames
            whole_ms = 1000 * statistics.median(r[0] + r[1] for r in runs) / frames
            what = ("the detail layer's fine mesh" if detail else
                    "the tracked mesh (Read Detail off)" if has_layer else "the tracked mesh")
            print(f"{what}: {frames} frames of {vertices} vertices; the file decoded in "
                  f"{decode_ms:.2f} ms, a frame given in {frame_ms:.3f} ms; decoding: "
                  f"{whole_ms:.3f} ms a frame, the file's decoding included")
            sys.stdout.flush()


if __name__ == "__main__":
    main()
