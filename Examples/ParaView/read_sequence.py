"""pvpython / pvbatch: load the plugin, open a point sequence, play it, save a screenshot.

    pvpython Examples/ParaView/read_sequence.py PLUGIN.so SERIES_FILE OUTPUT.png
"""
import sys

from paraview.simple import (Delete, LoadPlugin, OpenDataFile, Show, GetActiveViewOrCreate,
                             GetAnimationScene, SaveScreenshot, ResetCamera)


def main(plugin, series, screenshot):
    LoadPlugin(plugin, remote=False, ns=globals())
    reader = OpenDataFile(series)
    print("time steps:", list(reader.TimestepValues))
    view = GetActiveViewOrCreate("RenderView")
    display = Show(reader, view)
    display.PointSize = 2.0
    GetAnimationScene().UpdateAnimationUsingDataTimeSteps()
    # Show the middle frame; SaveScreenshot renders by itself.
    view.ViewTime = reader.TimestepValues[len(reader.TimestepValues) // 2]
    ResetCamera(view)
    SaveScreenshot(screenshot, view, ImageResolution=[800, 600])
    # Release the view while the GL context is alive: under Xvfb, leaving it to interpreter
    # shutdown ends in a GLXBadContext error and a non-zero exit.
    Delete(view)
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
