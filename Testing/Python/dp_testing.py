"""Shared helpers for the Python tests: where the build put things, and an error recorder."""
import json
import os
import shutil
import subprocess
import tempfile
import unittest

from vtkmodules.vtkCommonCore import vtkCommand

BIN_DIR = os.environ.get("DP_BIN_DIR", "")
PLUGIN = os.environ.get("DP_PLUGIN", "")
NODE_TOOLS = os.environ.get("DP_NODE_TOOLS", "")
UTILITIES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "Utilities")


def tool(name):
    """Full path of one of the product's command-line tools."""
    path = os.path.join(BIN_DIR, name)
    if not os.path.exists(path):
        raise AssertionError(f"{path} not found: run the tests through ctest (it sets DP_BIN_DIR)")
    return path


def run_tool(name, *args, check=True):
    """Runs a tool; returns the CompletedProcess (text output)."""
    result = subprocess.run([tool(name), *map(str, args)], capture_output=True, text=True,
                            timeout=300)
    if check and result.returncode != 0:
        raise AssertionError(f"{name} {args} failed ({result.returncode}):\n{result.stderr}")
    return result


def run_node_tool(package, script, *args):
    """Runs Utilities/gltf/SCRIPT with node, the npm PACKAGE found in DP_NODE_TOOLS."""
    module = os.path.join(NODE_TOOLS, "node_modules")
    if not os.path.isdir(os.path.join(module, package)):
        raise AssertionError(f"npm package {package} not found in {NODE_TOOLS!r}: "
                             "Utilities/dp.sh test installs it")
    result = subprocess.run(["node", os.path.join(UTILITIES, "gltf", script), *args],
                            capture_output=True, text=True, timeout=120,
                            env=dict(os.environ, NODE_PATH=module))
    if result.returncode != 0:
        raise AssertionError(f"{script} {args} failed:\n{result.stderr}")
    return json.loads(result.stdout)


def validate_gltf(path):
    """The Khronos glTF validator's report on a file (dict: errors, warnings, messages, info)."""
    return run_node_tool("gltf-validator", "validate_gltf.js", path)


def decode_meshopt(path, output):
    """Decodes a meshopt .glb's buffer views with meshoptimizer's decoder into OUTPUT (the
    fallback buffer's bytes); returns {"views": n, "bytes": size}."""
    return run_node_tool("meshoptimizer", "decode_meshopt.js", path, output)


def blender_report(path, frames=()):
    """What Blender (batch mode) makes of a .glb: see Utilities/gltf/blender_glb_report.py."""
    blender = shutil.which("blender")
    if not blender:
        raise AssertionError("blender not found: Utilities/dp.sh test installs it (apt)")
    result = subprocess.run(
        [blender, "-b", "--factory-startup", "--python-exit-code", "1", "-P",
         os.path.join(UTILITIES, "gltf", "blender_glb_report.py"), "--", path,
         *map(str, frames)], capture_output=True, text=True, timeout=300)
    lines = [l for l in result.stdout.splitlines() if l.startswith("DP-REPORT ")]
    if result.returncode != 0 or not lines:
        raise AssertionError(f"Blender could not import {path}:\n{result.stdout[-2000:]}\n"
                             f"{result.stderr[-2000:]}")
    return json.loads(lines[-1][len("DP-REPORT "):])


def blender_open_tracked(glb, blend):
    """Runs Utilities/blender/open_tracked.py as a user would (batch mode), saving BLEND."""
    result = subprocess.run(
        [shutil.which("blender") or "blender", "-b", "--factory-startup", "--python-exit-code",
         "1", "-P", os.path.join(UTILITIES, "blender", "open_tracked.py"), "--", glb, "--save",
         blend], capture_output=True, text=True, timeout=300)
    if result.returncode != 0 or not os.path.exists(blend):
        raise AssertionError(f"open_tracked.py failed on {glb}:\n{result.stdout[-2000:]}\n"
                             f"{result.stderr[-2000:]}")
    return result.stdout


class MessageRecorder:
    """Collects ErrorEvent / WarningEvent texts of a VTK object instead of printing them."""

    def __init__(self, obj):
        self.errors = []
        self.warnings = []
        from vtkmodules.util.misc import calldata_type
        from vtkmodules.util.vtkConstants import VTK_STRING

        @calldata_type(VTK_STRING)
        def on_error(_obj, _event, text):
            self.errors.append(text)

        @calldata_type(VTK_STRING)
        def on_warning(_obj, _event, text):
            self.warnings.append(text)

        obj.AddObserver(vtkCommand.ErrorEvent, on_error)
        obj.AddObserver(vtkCommand.WarningEvent, on_warning)
        self._keep = (on_error, on_warning)

    def clear(self):
        self.errors.clear()
        self.warnings.clear()

    @property
    def error_text(self):
        return "\n".join(self.errors)

    @property
    def warning_text(self):
        return "\n".join(self.warnings)


class TempDirTestCase(unittest.TestCase):
    def setUp(self):
        self._tmp = tempfile.TemporaryDirectory(prefix="dp-pytest-")
        self.tmp = self._tmp.name

    def tearDown(self):
        self._tmp.cleanup()

    def path(self, *parts):
        return os.path.join(self.tmp, *parts)
