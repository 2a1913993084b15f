"""Shared helpers for the Python tests: where the build put things, an error recorder, and an X
server with its windows (for the ParaView GUI tests)."""
import contextlib
import json
import os
import shutil
import struct
import subprocess
import tempfile
import time
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


def run_node_tool(package, script, *args, timeout=120):
    """Runs Utilities/gltf/SCRIPT (or Utilities/SCRIPT when it names a folder) with node, the npm
    PACKAGE found in DP_NODE_TOOLS; returns what it printed as JSON."""
    module = os.path.join(NODE_TOOLS, "node_modules")
    if not os.path.isdir(os.path.join(module, package)):
        raise AssertionError(f"npm package {package} not found in {NODE_TOOLS!r}: "
                             "Utilities/dp.sh test installs it")
    where = os.path.join(UTILITIES, script if os.sep in script else os.path.join("gltf", script))
    result = subprocess.run(["node", where, *args], capture_output=True, text=True,
                            timeout=timeout, env=dict(os.environ, NODE_PATH=module))
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


def glb_colours(path):
    """Each animation key's vertex colours (bytes, frames x vertices x 3) as a glTF player
    computes them from a plain .glb: the base's COLOR_0 plus each morph target's COLOR_0 times
    its weight at that key, rounded to bytes; a file without animation gives its one COLOR_0.
    None when the mesh has no COLOR_0."""
    import numpy as np
    with open(path, "rb") as f:
        data = f.read()
    json_length = struct.unpack_from("<I", data, 12)[0]
    gltf = json.loads(data[20:20 + json_length])
    binary = data[20 + json_length + 8:]
    types = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5126: np.float32}
    widths = {"SCALAR": 1, "VEC3": 3}

    def accessor(index):
        a = gltf["accessors"][index]
        view = gltf["bufferViews"][a["bufferView"]]
        dtype = np.dtype(types[a["componentType"]])
        width = widths[a["type"]]
        stride = view.get("byteStride", dtype.itemsize * width)
        start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
        rows = np.ndarray((a["count"], width), dtype, binary, start, (stride, dtype.itemsize))
        values = rows.astype(np.float64)
        if a.get("normalized"):
            values = np.maximum(values / np.iinfo(dtype).max, -1.0)
        return values

    primitive = gltf["meshes"][0]["primitives"][0]
    if "COLOR_0" not in primitive["attributes"]:
        return None
    base = accessor(primitive["attributes"]["COLOR_0"])
    targets = [accessor(t["COLOR_0"]) if "COLOR_0" in t else np.zeros_like(base)
               for t in primitive.get("targets", [])]
    if not gltf.get("animations") or not targets:
        return np.rint(255 * base[None]).astype(np.uint8)
    sampler = gltf["animations"][0]["samplers"][0]
    weights = accessor(sampler["output"]).reshape(-1, len(targets))
    frames = [base + sum(w * t for w, t in zip(key, targets)) for key in weights]
    return np.rint(255 * np.clip(np.stack(frames), 0, 1)).astype(np.uint8)


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


def run_blender(what, blend, arguments, env=None):
    """Runs Blender in batch mode with a factory setup and ARGUMENTS, which must write BLEND;
    returns its output, or fails naming WHAT."""
    result = subprocess.run(
        [shutil.which("blender") or "blender", "-b", "--factory-startup", "--python-exit-code",
         "1", *arguments], capture_output=True, text=True, timeout=300, env=env)
    if result.returncode != 0 or not os.path.exists(blend):
        raise AssertionError(f"{what} failed:\n{result.stdout[-2000:]}\n{result.stderr[-2000:]}")
    return result.stdout


def blender_open_tracked(glb, blend):
    """Runs Utilities/blender/open_tracked.py as a user would (batch mode), saving BLEND."""
    script = os.path.join(UTILITIES, "blender", "open_tracked.py")
    return run_blender(f"open_tracked.py on {glb}", blend,
                       ["-P", script, "--", glb, "--save", blend])


@contextlib.contextmanager
def x_display(size="1600x1200"):
    """An Xvfb server of our own, announced ready through -displayfd (xvfb-run's readiness wait
    proved racy on a loaded machine). The pipe stays open while the server runs: Xvfb may write
    to it again, and dies ("Cannot write display number") if it is closed."""
    ready_read, ready_write = os.pipe()
    server = subprocess.Popen(["Xvfb", "-displayfd", str(ready_write), "-screen", "0",
                               size + "x24", "-nolisten", "tcp", "-noreset"],
                              pass_fds=(ready_write,), stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, start_new_session=True)
    os.close(ready_write)
    try:
        display = os.read(ready_read, 64).decode().strip()
        if not display.isdigit():
            raise AssertionError(f"Xvfb did not start ({display!r})")
        yield ":" + display
    finally:
        server.terminate()
        server.wait(timeout=30)
        os.close(ready_read)


class XWindows:
    """The windows of an X display, driven as a user would (xdotool: x11 keyboard and window
    sizes) and photographed (xwd). Xvfb has no window manager, so a dialog may open below the
    main window: find it by title and photograph it alone."""

    def __init__(self, display):
        self.env = dict(os.environ, DISPLAY=display)
        for program in ("xdotool", "xwd"):
            if not shutil.which(program):
                raise AssertionError(f"{program} not found: Utilities/dp.sh test installs it")

    def run(self, *args):
        return subprocess.run(list(map(str, args)), capture_output=True, text=True,
                              env=self.env, timeout=60)

    def visible(self, title):
        """Ids of the visible windows whose title matches the regular expression TITLE."""
        result = self.run("xdotool", "search", "--onlyvisible", "--name", title)
        return [int(w) for w in result.stdout.split()]

    def wait_for(self, title, timeout=120):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            found = self.visible(title)
            if found:
                return found[0]
            time.sleep(0.5)
        raise AssertionError(f"no window titled {title!r} after {timeout} s")

    def key(self, window, *keys):
        """Presses KEYS in WINDOW, focused first (events sent to an unfocused window are
        dropped by Qt)."""
        self.run("xdotool", "windowfocus", window)
        time.sleep(0.5)
        self.run("xdotool", "key", *keys)

    def type(self, window, text):
        """Types TEXT into WINDOW, focused first."""
        self.run("xdotool", "windowfocus", window)
        time.sleep(0.5)
        self.run("xdotool", "type", "--delay", 20, text)

    def resize(self, window, width, height):
        self.run("xdotool", "windowsize", window, width, height)

    def photograph(self, window, png):
        """Writes WINDOW (or "root": the whole screen) as a PNG; returns it as rows x columns x
        RGB (numpy)."""
        import numpy as np
        from vtkmodules.util.numpy_support import numpy_to_vtk
        from vtkmodules.vtkCommonDataModel import vtkImageData
        from vtkmodules.vtkIOImage import vtkPNGWriter
        target = ["-root"] if window == "root" else ["-id", str(window)]
        raw = subprocess.run(["xwd", "-silent", *target], capture_output=True, env=self.env,
                             timeout=60, check=True).stdout
        # XWD: a header of big-endian 32-bit fields, the window name, the colour map, then
        # ZPixmap rows of 32-bit pixels (blue, green, red, pad in LSB-first byte order).
        header = struct.unpack(">25I", raw[:100])
        size, width, height, lsb_first = header[0], header[4], header[5], header[7] == 0
        bits, row_bytes, colours = header[11], header[12], header[19]
        if bits != 32:
            raise AssertionError(f"xwd wrote {bits} bits per pixel; 32 expected")
        rows = np.frombuffer(raw, np.uint8, height * row_bytes, size + 12 * colours)
        pixels = rows.reshape(height, row_bytes)[:, :width * 4].reshape(height, width, 4)
        rgb = np.ascontiguousarray(pixels[:, :, [2, 1, 0]] if lsb_first else pixels[:, :, 1:])
        image = vtkImageData()
        image.SetDimensions(width, height, 1)
        flat = np.ascontiguousarray(rgb[::-1].reshape(-1, 3))  # VTK's rows go bottom-up
        image.GetPointData().SetScalars(numpy_to_vtk(flat, deep=True))
        writer = vtkPNGWriter()
        writer.SetFileName(png)
        writer.SetInputData(image)
        writer.Write()
        return rgb


def blender_addon_import(glb, blend, user_folder):
    """Installs Utilities/blender/dynamicpoints_import.py as a user does (Preferences > Add-ons >
    Install, then enable) into a fresh Blender user folder, imports GLB into Blender's default
    scene with File > Import > DynamicPoints animation (.glb) (batch mode) and saves BLEND;
    returns Blender's output."""
    addon = os.path.join(UTILITIES, "blender", "dynamicpoints_import.py")
    script = "\n".join([
        "import bpy",
        f"bpy.ops.preferences.addon_install(filepath={addon!r})",
        "bpy.ops.preferences.addon_enable(module='dynamicpoints_import')",
        f"result = bpy.ops.import_scene.dynamicpoints_glb(filepath={glb!r})",
        "assert 'FINISHED' in result, result",
        f"bpy.ops.wm.save_as_mainfile(filepath={blend!r})"])
    return run_blender(f"the add-on's import of {glb}", blend, ["--python-expr", script],
                       env=dict(os.environ, BLENDER_USER_SCRIPTS=user_folder))


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


def sheet_with_an_unexplained_frame(folder, frame=3, frames=6):
    """Samples the waving sheet into FOLDER (FRAMES frames of 4000 points, no .series) and gives
    frame FRAME a ball of points beside the sheet that no deformation of a template explains:
    the tracker flags that frame."""
    import numpy as np
    from vtkmodules.numpy_interface import dataset_adapter as dsa
    import dynamicpoints
    run_tool("dynamicpoints-sample", "--mesh", "sheet", "--frames", frames, "--points", 4000,
             folder)
    os.remove(os.path.join(folder, "points.series"))
    name = os.path.join(folder, "frame_%04d.ply" % frame)
    reader = dynamicpoints.vtkPointSequenceSource()
    reader.SetFileName(name)
    reader.Update()
    data = dsa.WrapDataObject(reader.GetOutput())
    points, normals = np.asarray(data.Points), np.asarray(data.PointData["Normals"])
    size = np.linalg.norm(points.max(axis=0) - points.min(axis=0))
    outward = np.random.default_rng(3).normal(size=(1500, 3))
    outward /= np.linalg.norm(outward, axis=1)[:, None]
    ball = points.max(axis=0) + 0.3 * size + 0.1 * size * outward
    with open(name, "w") as out:
        out.write("ply\nformat ascii 1.0\nelement vertex %d\n" % (len(points) + len(ball)))
        out.write("".join(f"property float {c}\n" for c in ("x", "y", "z", "nx", "ny", "nz")))
        out.write("end_header\n")
        np.savetxt(out, np.hstack([np.vstack([points, ball]), np.vstack([normals, outward])]),
                   fmt="%.7g")
