"""Runs inside the ParaView GUI (`paraview --dr --script=gui_session.py`, started by
test_paraview_gui.py): what a user does in one session, recorded in DP_OUTPUT/session.json for
the test to judge.

- File > Open on the point sequence: which reader ParaView picks.
- File > Save Data of a fresh Deformable Track as .dpz: the progress (text, value) the GUI's
  progress bar is given, frame by frame over the whole take.
- An abort while frame 3 is tracked, raised as ParaView 6.1's abort button does (the
  algorithm's SetAbortExecuteAndUpdateTime; 5.11's button is not wired to anything): the frames
  kept.
- The tracked mesh over the points, Deformable Track active so that its panel shows, for the
  test's screenshot.

A script cannot reach the GUI's widgets, so the test drives and photographs them with xdotool
and xwd after "done" is written.
"""
import json
import os

from paraview.simple import (ColorBy, GetActiveViewOrCreate, LoadPlugin, OpenDataFile, Render,
                             ResetCamera, SaveData, SetActiveSource, Show)

OUTPUT = os.environ["DP_OUTPUT"]
ns = {"__name__": "dp_plugin_proxies"}
LoadPlugin(os.environ["DP_PLUGIN"], remote=False, ns=ns)
session = {}

points = OpenDataFile(os.environ["DP_SERIES"])
session["reader"] = points.GetXMLName()
times = list(points.TimestepValues)
session["frames"] = len(times)


def observe(proxy, record):
    """Records (text, value) of every progress event of the algorithm behind PROXY."""
    algorithm = proxy.GetClientSideObject()
    algorithm.AddObserver("ProgressEvent", lambda caller, _event: record.append(
        (caller.GetProgressText(), caller.GetProgress())))
    return algorithm


saved = ns["DeformableTrack"](Input=points, TemplateVertices=300)
session["save_progress"] = []
observe(saved, session["save_progress"])
SaveData(os.path.join(OUTPUT, "saved.dpz"), proxy=saved)

stopped = ns["DeformableTrack"](Input=points, TemplateVertices=300)
session["abort_progress"] = []
algorithm = observe(stopped, session["abort_progress"])


def frame_held(proxy):
    """The frame the filter's output holds (the GUI runs in one process: the algorithm's own
    output, not a new request)."""
    output = proxy.GetClientSideObject().GetOutputDataObject(0)
    return int(output.GetFieldData().GetArray("FrameIndex").GetValue(0))


def abort_during_frame_3(caller, _event):
    if caller.GetProgressText() == f"Deformable Track: frame 3 of {len(times)}":
        caller.SetAbortExecuteAndUpdateTime()


algorithm.AddObserver("ProgressEvent", abort_during_frame_3)
stopped.UpdatePipeline(times[-1])
session["abort_output_frame"] = frame_held(stopped)
# Going on: another time is tracked from the frames kept (the plugin's class is not wrapped in
# the GUI's Python, so the cache is judged by the frames tracked again).
algorithm.RemoveAllObservers()
session["resume_progress"] = []
observe(stopped, session["resume_progress"])
stopped.UpdatePipeline(times[-2])
session["resume_output_frame"] = frame_held(stopped)

view = GetActiveViewOrCreate("RenderView")
cloud = Show(points, view)
cloud.SetRepresentationType("Points")
cloud.AmbientColor = cloud.DiffuseColor = [0.15, 0.15, 0.15]
mesh = Show(saved, view)
ColorBy(mesh, ("POINTS", "Residual"))
mesh.SetScalarBarVisibility(view, True)
view.ViewTime = times[len(times) // 2]
view.CameraPosition, view.CameraFocalPoint, view.CameraViewUp = [0, -4, 0], [0, 0, 0], [0, 0, 1]
ResetCamera(view)
SetActiveSource(saved)
Render(view)

with open(os.path.join(OUTPUT, "session.json"), "w") as f:
    json.dump(session, f)
