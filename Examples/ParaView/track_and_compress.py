"""ParaView: the whole job as a user would click it, as a script for pvpython, pvbatch
(also under mpirun) or the GUI (`paraview --dr --script=...`): open a point sequence, track it
(Filters > DynamicPoints > Deformable Track), compress it (PCA Compress), save it as .dpz and
.glb (File > Save Data), show the tracked mesh coloured by its distance to the points over the points, play it
over time, and save a screenshot of the middle frame.

    pvpython Examples/ParaView/track_and_compress.py PLUGIN.so SERIES_FILE OUTPUT_FOLDER

Inside the GUI, where a script gets no arguments, set DP_PLUGIN, DP_SERIES and DP_OUTPUT in
the environment instead.
"""
import os
import sys

from paraview.simple import (ColorBy, Delete, GetActiveViewOrCreate, GetColorTransferFunction,
                             GetScalarBar, LoadPlugin, OpenDataFile, Render, ResetCamera,
                             SaveData, SaveScreenshot, Show, servermanager)


def print_progress(proxy):
    """pvpython and pvbatch draw no progress bar: print the text the GUI's bar would show each time
    it changes ("Deformable Track: frame 3 of 12 (17%)"), from the algorithm's ProgressEvent.
    Under MPI only the first process prints."""
    if servermanager.vtkProcessModule.GetProcessModule().GetPartitionId() != 0:
        return
    shown = []

    def show(algorithm, _event):
        text = algorithm.GetProgressText()
        if text and (not shown or shown[-1] != text):
            shown.append(text)
            print(f"{text} ({algorithm.GetProgress():.0%})", flush=True)
    proxy.GetClientSideObject().AddObserver("ProgressEvent", show)


def main(plugin, series, output, in_gui=False):
    LoadPlugin(plugin, remote=False, ns=globals())
    os.makedirs(output, exist_ok=True)

    points = OpenDataFile(series)  # the plugin's Point Sequence Reader
    track = DeformableTrack(Input=points)  # noqa: F821 (defined by LoadPlugin)
    track.TemplateVertices = 600
    compress = PCACompress(Input=track)  # noqa: F821
    compress.KGTarget = 0.2
    if not in_gui:  # the GUI has its progress bar
        print_progress(track)

    view = GetActiveViewOrCreate("RenderView")
    cloud = Show(points, view)
    cloud.SetRepresentationType("Points")
    cloud.PointSize = 1.5
    cloud.ColorArrayName = [None, ""]
    cloud.AmbientColor = cloud.DiffuseColor = [0.15, 0.15, 0.15]
    mesh = Show(track, view)
    ColorBy(mesh, ("POINTS", "Residual"))
    mesh.RescaleTransferFunctionToDataRange(True, False)
    mesh.SetScalarBarVisibility(view, True)
    bar = GetScalarBar(GetColorTransferFunction("Residual"), view)
    bar.Title = "distance to the points"
    bar.ComponentTitle = ""
    bar.TitleColor = bar.LabelColor = [0.1, 0.1, 0.1]  # on the white background below

    # The view shows one time at a time; ParaView's time controls list the data's time steps.
    times = list(points.TimestepValues)
    for t in times:  # play it: each frame is tracked once, in order
        view.ViewTime = t
        Render(view)
    # Compress (runs once over the cached frames) and report what it reached.
    compress.UpdatePipeline(times[-1])
    figures = servermanager.Fetch(compress).GetFieldData()
    print(f"{len(times)} frames tracked; compressed to "
          f"{figures.GetArray('BitsPerVertexFrame').GetValue(0):.3g} bits per vertex per frame, "
          f"KG error {figures.GetArray('KGError').GetValue(0):.3g}%")
    # File > Save Data: the extension picks the plugin's writer, which compresses the same way.
    for name in ("tracked.dpz", "tracked.glb"):
        SaveData(os.path.join(output, name), proxy=track, KGTarget=0.2)

    view.ViewTime = times[len(times) // 2]
    # Look at the sequence from the side (-y), z up.
    b = points.GetDataInformation().GetBounds()
    centre = [(b[0] + b[1]) / 2, (b[2] + b[3]) / 2, (b[4] + b[5]) / 2]
    view.CameraFocalPoint = centre
    view.CameraPosition = [centre[0], centre[1] - 4 * (b[5] - b[4] + b[1] - b[0]), centre[2]]
    view.CameraViewUp = [0, 0, 1]
    view.UseColorPaletteForBackground = 0
    view.Background = [1, 1, 1]
    view.OrientationAxesVisibility = 0
    ResetCamera(view)
    SaveScreenshot(os.path.join(output, "tracked.png"), view, ImageResolution=[800, 600])
    if not in_gui:
        # Release the view while the GL context is alive: under Xvfb, leaving it to
        # interpreter shutdown ends in a GLXBadContext error and a non-zero exit.
        Delete(view)
    return 0


# No __main__ guard: the GUI runs --script files under another name.
# No sys.exit on success: pvbatch under mpirun must return from the script to finalise MPI.
if len(sys.argv) >= 4:
    if main(*sys.argv[1:4]) != 0:
        sys.exit(1)
else:
    # Inside the GUI: no command-line arguments, so the environment says what to open. Do not
    # exit: the GUI exits by itself after the script when started with --exit.
    main(os.environ["DP_PLUGIN"], os.environ["DP_SERIES"], os.environ["DP_OUTPUT"], in_gui=True)
