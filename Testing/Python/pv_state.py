"""pvpython: runs the main job's ParaView state (the file given) as ParaView's --state does, then
prints what it built, for test_views.py: "DP-STATE {json}" with the sources (registration name ->
proxy), each one's representation and colouring, the animation scene's times and play mode, the
view's time and the tracked mesh's point count."""
import json
import sys

from paraview import servermanager
from paraview.simple import (GetActiveViewOrCreate, GetAnimationScene, GetDisplayProperties,
                             GetSources, GetTimeKeeper)

state = sys.argv[1]
with open(state) as f:
    exec(compile(f.read(), state, "exec"), {"__name__": "__main__", "__file__": state})

view = GetActiveViewOrCreate("RenderView")
seen = {"sources": {}}
for (name, _), proxy in GetSources().items():
    seen["sources"][name] = proxy.GetXMLName()
    display = GetDisplayProperties(proxy, view)
    seen[name] = {"representation": str(display.Representation).strip("'"),
                  "colour": [str(c) for c in display.ColorArrayName]}
scene = GetAnimationScene()
seen["times"] = list(GetTimeKeeper().TimestepValues)
seen["playMode"] = str(scene.PlayMode).strip("'")
seen["viewTime"] = view.ViewTime
tracked = [p for (n, _), p in GetSources().items() if n == "tracked"][0]
seen["trackedPoints"] = servermanager.Fetch(tracked).GetNumberOfPoints()
print("DP-STATE " + json.dumps(seen))
