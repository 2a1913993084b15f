"""The examples run as documented and produce what they say (Python, C++, pvpython)."""
import glob
import os
import shutil
import subprocess
import sys
import unittest

from vtkmodules.vtkIOImage import vtkPNGReader

import dynamicpoints
from dp_testing import BIN_DIR, PLUGIN, TempDirTestCase, run_tool

EXAMPLES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "Examples")


class TestExamples(TempDirTestCase):
    def make_sequence(self, frames=5):
        run_tool("dynamicpoints-sample", "--mesh", "sheet", "--frames", frames, "--points", 3000,
                 self.path("seq"))
        return self.path("seq", "points.series")

    def test_python_example(self):
        env = dict(os.environ, DP_BIN_DIR=BIN_DIR)
        result = subprocess.run([sys.executable, os.path.join(EXAMPLES, "Python", "read_sequence.py")],
                                capture_output=True, text=True, env=env, timeout=300)
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertIn("8 frames", result.stdout)
        self.assertEqual(result.stdout.count("5000 points"), 8, result.stdout)

    def test_cxx_example_writes_a_playable_vtp_sequence(self):
        series = self.make_sequence()
        result = run_tool("ReadSequence", series, self.path("out"))
        self.assertIn("wrote 5 frames", result.stdout)
        self.assertTrue(os.path.exists(self.path("out", "sequence.pvd")))
        source = dynamicpoints.vtkPointSequenceSource()
        source.SetDirectoryName(self.path("out"))
        source.SetFilePattern("frame_*.vtp")
        self.assertEqual(source.GetNumberOfFrames(), 5)
        source.UpdateTimeStep(4)
        self.assertEqual(source.GetOutput().GetNumberOfPoints(), 3000)

    def test_paraview_example_renders_a_screenshot(self):
        series = self.make_sequence()
        shot = self.path("shot.png")
        # Our own X server, announced ready through -displayfd (xvfb-run's readiness wait
        # proved racy on a loaded machine). The pipe stays open while the server runs: Xvfb
        # may write to it again, and dies ("Cannot write display number") if it is closed.
        ready_read, ready_write = os.pipe()
        server = subprocess.Popen(["Xvfb", "-displayfd", str(ready_write), "-screen", "0",
                                   "1280x1024x24", "-nolisten", "tcp", "-noreset"],
                                  pass_fds=(ready_write,), stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL, start_new_session=True)
        os.close(ready_write)
        try:
            display = os.read(ready_read, 64).decode().strip()
            self.assertTrue(display.isdigit(), f"Xvfb did not start ({display!r})")
            result = subprocess.run(
                [shutil.which("pvpython"), "--dr",
                 os.path.join(EXAMPLES, "ParaView", "read_sequence.py"), PLUGIN, series, shot],
                capture_output=True, text=True, timeout=300,
                env=dict(os.environ, DISPLAY=":" + display))
        finally:
            server.terminate()
            server.wait(timeout=30)
            os.close(ready_read)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        self.assertIn("time steps: [0.0, 1.0, 2.0, 3.0, 4.0]", result.stdout)
        reader = vtkPNGReader()
        reader.SetFileName(shot)
        reader.Update()
        image = reader.GetOutput()
        self.assertEqual(image.GetDimensions()[:2], (800, 600))
        # Not a blank view: the points differ from the background.
        low, high = image.GetPointData().GetScalars().GetRange(0)
        self.assertGreater(high - low, 50)


if __name__ == "__main__":
    unittest.main()
