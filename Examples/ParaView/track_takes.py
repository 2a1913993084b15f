"""pvbatch: a batch of takes spread over MPI ranks, each take tracked and compressed whole by
the rank that takes it (the main job's batch, `mpirun -np N dynamicpoints A B C`, from ParaView's
own engine). Every rank runs this script (--symmetric); the takes are handed out largest first
(bytes on disk) to whichever rank is free, through an MPI one-sided counter on rank 0.

    PYTHONPATH=build/lib/python3/dist-packages \\
        mpirun -np 2 pvbatch --symmetric Examples/ParaView/track_takes.py [--vertices N] \\
        OUTPUT TAKE...

TAKE: a folder of point files, a .series file or one point file; --vertices: of the template
reconstructed from each take's first frame (default 1000, as the main job's); the detail layer
as the main job chooses it. Written:
OUTPUT/<name>/tracked.dpz and tracked.glb (<name>: the folder's name, a .series file's
folder's, a file's stem; repeated names get -2, -3), the same bytes as the main job writes for
that take; one line per take. The exit status is 1 when a take failed (named on stderr), after
the others are written.

The work per take runs in the VTK classes of the `dynamicpoints` Python module (the build's
lib/python3/dist-packages), not through ParaView proxies: a proxy's pipeline is data-parallel
over all ranks (each rank asks for its own piece), while here each rank tracks a whole take.
"""
import os
import sys
from array import array

from mpi4py import MPI

import dynamicpoints


def describe(paths):
    """(path, name, bytes) per take, as the main job names and weighs its inputs: a folder by
    its name and files, a .series file by its folder's, another file by its stem and size;
    repeated names get -2, -3 in the order given."""
    def files_in(folder):
        return sum(os.path.getsize(os.path.join(folder, f)) for f in os.listdir(folder)
                   if os.path.isfile(os.path.join(folder, f)))

    takes, seen = [], {}
    for path in paths:
        path = os.path.normpath(path)
        if os.path.isdir(path):
            name, size = os.path.basename(path), files_in(path)
        elif path.endswith(".series"):
            folder = os.path.dirname(os.path.abspath(path))
            name, size = os.path.basename(folder), files_in(folder)
        else:
            name = os.path.splitext(os.path.basename(path))[0]
            size = os.path.getsize(path) if os.path.isfile(path) else 0
        name = name if name not in ("", ".", "..") else "input"
        seen[name] = seen.get(name, 0) + 1
        takes.append((path, name if seen[name] == 1 else f"{name}-{seen[name]}", size))
    return takes


def track(path, output, vertices):
    """Tracks and compresses one take into OUTPUT; returns an error text or None."""
    source = dynamicpoints.vtkPointSequenceSource()
    if os.path.isdir(path):
        source.SetDirectoryName(path)
    else:
        source.SetFileName(path)
    if source.GetNumberOfFrames() < 1:
        return f"{path}: no readable frames"
    tracker = dynamicpoints.vtkDeformableTrackFilter()
    tracker.SetInputConnection(source.GetOutputPort())
    tracker.SetTemplateVertices(vertices)
    # The detail layer, as the main job makes it (levels measured on the first frame); its data
    # through a source of its own, so that neither source re-reads what the other asked for.
    data = dynamicpoints.vtkPointSequenceSource()
    data.SetDirectoryName(source.GetDirectoryName())
    data.SetFileName(source.GetFileName())
    detail = dynamicpoints.vtkSurfaceDetailFilter()
    detail.SetInputConnection(0, tracker.GetOutputPort())
    detail.SetInputConnection(1, data.GetOutputPort())
    os.makedirs(output, exist_ok=True)
    for name in ("tracked.dpz", "tracked.glb"):
        writer = dynamicpoints.vtkCompressedSequenceWriter()
        writer.SetInputConnection(detail.GetOutputPort())
        # The main job's target: the distance to the points may grow by 10 %.
        writer.SetErrorMeasure(dynamicpoints.vtkPCACompressFilter.DISTANCE_TO_DATA)
        writer.SetFitGrowth(10)
        writer.SetFileName(os.path.join(output, name))
        writer.Write()  # an input that failed upstream leaves no file (VTK said why)
        if writer.GetErrorCode() or not os.path.exists(os.path.join(output, name)):
            return f"{path}: {name} not written"
    return None


def main(output, paths, vertices):
    comm = MPI.COMM_WORLD
    takes = describe(paths)
    order = sorted(range(len(takes)), key=lambda k: -takes[k][2])  # stable: ties keep order
    # The counter: one int on rank 0; every rank fetches and adds 1 to take the next take.
    counter = MPI.Win.Allocate(4 if comm.rank == 0 else 0, 4, comm=comm)
    if comm.rank == 0:
        counter.Lock(0)
        counter.Put([array("i", [0]), MPI.INT], 0)
        counter.Unlock(0)
    comm.Barrier()
    failed = []
    one, taken = array("i", [1]), array("i", [0])
    while True:
        counter.Lock(0, MPI.LOCK_SHARED)
        counter.Fetch_and_op([one, MPI.INT], [taken, MPI.INT], 0, 0, MPI.SUM)
        counter.Unlock(0)
        turn = taken[0]
        if turn >= len(takes):
            break
        path, name, _ = takes[order[turn]]
        error = track(path, os.path.join(output, name), vertices)
        print(f"[rank {comm.rank}] {name}: {'failed: ' + error if error else 'done'}", flush=True)
        if error:
            failed.append(error)
    counter.Free()
    failed = [f for mine in comm.allgather(failed) for f in mine]
    if comm.rank == 0 and failed:
        print(f"{len(failed)} of {len(takes)} takes failed:\n  " + "\n  ".join(failed),
              file=sys.stderr)
    return 1 if failed else 0


# No __main__ guard and no sys.exit on success: pvbatch runs the script under another name and
# must return from it to finalise MPI.
arguments = sys.argv[1:]
template_vertices = 1000
if arguments[:1] == ["--vertices"] and len(arguments) > 1 and arguments[1].isdigit():
    template_vertices, arguments = int(arguments[1]), arguments[2:]
if len(arguments) < 2:
    sys.exit("usage: mpirun -np N pvbatch --symmetric track_takes.py [--vertices N] OUTPUT "
             "TAKE...")
if main(arguments[0], arguments[1:], template_vertices) != 0:
    sys.exit(1)
