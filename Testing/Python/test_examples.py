"""The examples do the whole job as documented (C++, Python, pvpython, pvbatch, the ParaView GUI,
and pvbatch on two MPI processes), and what they write reads back."""
import filecmp
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import numpy as np
from vtkmodules.numpy_interface import dataset_adapter as dsa
from vtkmodules.vtkIOImage import vtkPNGReader
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

import dynamicpoints
from dp_testing import BIN_DIR, PLUGIN, TempDirTestCase, run_tool, x_display

EXAMPLES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "Examples")
PARAVIEW_EXAMPLE = os.path.join(EXAMPLES, "ParaView", "track_and_compress.py")
FRAMES = 12


def read_dpz(path, detail=True):
    """All frames of a .dpz file, frames x vertices x 3 (of its detail layer's fine mesh, or with
    `detail` False of its tracked mesh)."""
    reader = dynamicpoints.vtkCompressedSequenceReader()
    reader.SetFileName(path)
    reader.SetReadDetail(detail)
    reader.UpdateInformation()
    frames = []
    for t in reader.GetOutputInformation(0).Get(reader.GetExecutive().TIME_STEPS()):
        reader.UpdateTimeStep(t)
        frames.append(np.array(dsa.WrapDataObject(reader.GetOutput()).Points))
    return np.stack(frames)


class TestExamples(TempDirTestCase):
    @classmethod
    def setUpClass(cls):
        cls._data = tempfile.TemporaryDirectory(prefix="dp-examples-")
        cls.series = os.path.join(cls._data.name, "seq", "points.series")
        run_tool("dynamicpoints-sample", "--frames", FRAMES, "--points", 5000,
                 os.path.dirname(cls.series))

    @classmethod
    def tearDownClass(cls):
        cls._data.cleanup()

    def check_screenshot(self, path):
        reader = vtkPNGReader()
        reader.SetFileName(path)
        reader.Update()
        image = reader.GetOutput()
        self.assertEqual(image.GetDimensions()[:2], (800, 600))
        # Not a blank view: the mesh and the points differ from the background.
        low, high = image.GetPointData().GetScalars().GetRange(0)
        self.assertGreater(high - low, 50)

    def run_paraview(self, command, output, timeout=300, env=None):
        with x_display() as display:
            result = subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                                    env=dict(os.environ, DISPLAY=display, **(env or {})))
        self.assertEqual(result.returncode, 0, result.stdout[-3000:] + result.stderr[-3000:])
        for name in ("tracked.dpz", "tracked.glb", "tracked.png"):
            self.assertTrue(os.path.exists(os.path.join(output, name)), name)
        self.check_screenshot(os.path.join(output, "tracked.png"))
        return result

    def paraview_example(self, program, output):
        return self.run_paraview([shutil.which(program), PARAVIEW_EXAMPLE, PLUGIN, self.series,
                                  output], output)

    def test_cxx_example_runs_the_whole_pipeline(self):
        result = run_tool("TrackAndCompress", self.series, self.path("out"), 400)
        self.assertIn(f"compressed {FRAMES} frames", result.stdout)
        frames = [os.path.join(self.path("out"), f"frame_{f:04d}.vtp") for f in range(FRAMES)]
        decoded = read_dpz(self.path("out", "tracked.dpz"))
        self.assertEqual(decoded.shape[0], FRAMES)
        for f in (0, FRAMES - 1):
            reader = vtkXMLPolyDataReader()
            reader.SetFileName(frames[f])
            reader.Update()
            # The .vtp frames are the compressor's output: the decompressed sequence.
            np.testing.assert_allclose(dsa.WrapDataObject(reader.GetOutput()).Points,
                                       decoded[f], atol=1e-12)
            self.assertGreater(reader.GetOutput().GetNumberOfPolys(), 300)
        self.assertTrue(os.path.exists(self.path("out", "sequence.pvd")))

    def test_python_example_does_the_whole_job_with_numpy(self):
        env = dict(os.environ, DP_BIN_DIR=BIN_DIR)
        result = subprocess.run([sys.executable, os.path.join(EXAMPLES, "Python",
                                                              "track_and_compress.py"),
                                 self.series, self.path("out")],
                                capture_output=True, text=True, env=env, timeout=300)
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertIn(f"{FRAMES} frames", result.stdout)
        tracked = np.load(self.path("out", "trajectories.npy"))
        self.assertEqual(tracked.shape[0], FRAMES)
        decoded = read_dpz(self.path("out", "tracked.dpz"))
        self.assertEqual(decoded.shape, tracked.shape)
        centred = tracked - tracked.mean(axis=1, keepdims=True)
        kg = 100 * np.linalg.norm(tracked - decoded) / np.linalg.norm(centred)
        self.assertLessEqual(kg, 0.2 * 1.001)
        # The detail layer's file: the same base, byte for byte as decoded, under a fine mesh of
        # two levels (about 16 times the triangles).
        self.assertIn("detail layer: ", result.stdout)
        detailed = self.path("out", "detailed.dpz")
        np.testing.assert_array_equal(read_dpz(detailed, detail=False), decoded)
        fine = read_dpz(detailed)
        self.assertEqual(fine.shape[0], FRAMES)
        self.assertGreater(fine.shape[1], 15 * tracked.shape[1])

    def test_paraview_example_gives_the_same_result_in_pvpython_and_pvbatch(self):
        result = self.paraview_example("pvpython", self.path("pvpython"))
        self.assertIn(f"{FRAMES} frames tracked", result.stdout)
        # pvpython has no progress bar: the example prints the tracker's progress texts.
        for k in (1, FRAMES):
            self.assertIn(f"Deformable Track: frame {k} of {FRAMES} (", result.stdout)
        self.paraview_example("pvbatch", self.path("pvbatch"))
        self.assertTrue(filecmp.cmp(self.path("pvpython", "tracked.dpz"),
                                    self.path("pvbatch", "tracked.dpz"), shallow=False))
        decoded = read_dpz(self.path("pvbatch", "tracked.dpz"))
        self.assertEqual(decoded.shape[0], FRAMES)

    def test_two_mpi_processes_give_the_same_result_as_one(self):
        self.paraview_example("pvbatch", self.path("one"))
        mpirun = shutil.which("mpirun")
        self.assertIsNotNone(mpirun, "mpirun (openmpi-bin) is missing")
        self.run_paraview([mpirun, "-np", "2", "--oversubscribe", "--allow-run-as-root",
                           shutil.which("pvbatch"), PARAVIEW_EXAMPLE, PLUGIN, self.series,
                           self.path("two")], self.path("two"))
        for name in ("tracked.dpz", "tracked.glb"):
            self.assertTrue(filecmp.cmp(self.path("one", name), self.path("two", name),
                                        shallow=False), name)

    def test_the_paraview_gui_runs_the_example(self):
        # The real GUI under Xvfb: the plugin loads, the pipeline runs, a screenshot is written.
        output = self.path("gui")
        os.makedirs(self.path("home"))  # fresh settings, as on a new machine
        self.run_paraview([shutil.which("paraview"), "--dr", "--script=" + PARAVIEW_EXAMPLE,
                           "--exit"],
                          output, env={"DP_PLUGIN": PLUGIN, "DP_SERIES": self.series,
                                       "DP_OUTPUT": output, "HOME": self.path("home")})
        self.paraview_example("pvbatch", self.path("pvbatch"))
        self.assertTrue(filecmp.cmp(self.path("gui", "tracked.dpz"),
                                    self.path("pvbatch", "tracked.dpz"), shallow=False))


if __name__ == "__main__":
    unittest.main()
