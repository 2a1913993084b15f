"""pvpython: ParaView opens what the main job wrote. Prints one JSON line "DP-PV {...}" with the
time steps and point/cell counts ParaView reads from OUTPUT/tracked.pvd (its own PVD reader)
and OUTPUT/tracked.dpz (the plugin's reader, picked by ParaView's reader factory); saves the
tracked sequence with File > Save Data as OUTPUT/saved.dpz and saved.glb (the plugin's writers)
and reads saved.dpz back.
Usage: pvpython pv_main_job_outputs.py OUTPUT_FOLDER   (DP_PLUGIN: the plugin library)"""
import json
import os
import sys

from paraview.simple import LoadPlugin, OpenDataFile, SaveData, UpdatePipeline, servermanager


def read_back(path, times):
    proxy = OpenDataFile(path)
    if proxy is None:
        raise SystemExit(f"ParaView cannot open {path}")
    steps = list(proxy.TimestepValues)
    counts = []
    for t in (steps[0], steps[-1]) if steps else ():
        UpdatePipeline(time=t, proxy=proxy)
        data = servermanager.Fetch(proxy)
        counts.append([data.GetNumberOfPoints(), data.GetNumberOfCells()])
    return {"reader": proxy.GetXMLName(), "steps": steps, "first_last_counts": counts}


def main():
    LoadPlugin(os.environ["DP_PLUGIN"], remote=False, ns={"__name__": "dp_plugin_proxies"})
    folder = sys.argv[1]
    result = {name: read_back(os.path.join(folder, name), None)
              for name in ("tracked.pvd", "tracked.dpz")}
    # File > Save Data: the plugin's writers, chosen by extension, write the whole sequence.
    tracked = OpenDataFile(os.path.join(folder, "tracked.pvd"))
    SaveData(os.path.join(folder, "saved.dpz"), proxy=tracked, KGTarget=0.5)
    SaveData(os.path.join(folder, "saved.glb"), proxy=tracked)
    result["saved.dpz"] = read_back(os.path.join(folder, "saved.dpz"), None)
    print("DP-PV " + json.dumps(result))


if __name__ == "__main__":
    main()
