"""Runs inside the ParaView GUI for test_paraview_gui.py: loads the plugin and turns on Auto Apply
(so a file opened by the test's keystrokes is shown at once), then writes DP_OUTPUT/ready."""
import os

from paraview.simple import GetSettingsProxy, LoadPlugin

LoadPlugin(os.environ["DP_PLUGIN"], remote=False, ns={"__name__": "dp_plugin_proxies"})
GetSettingsProxy("GeneralSettings").AutoApply = 1
open(os.path.join(os.environ["DP_OUTPUT"], "ready"), "w").close()
