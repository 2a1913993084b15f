"""vtkSurfaceDetailFilter in a VTK pipeline: a tracked tube given the detail of its per-frame
meshes (the levels chosen from the data, the fine mesh closer to them, the arrays it carries),
each frame fitted once, colour carried, a smooth take left alone, bad inputs refused by name, and
the layer through PCA Compress and the .dpz (the fine mesh by default, the tracked one on
request)."""
import os
import unittest

import numpy as np
from vtkmodules.numpy_interface import dataset_adapter as dsa
from vtkmodules.vtkCommonCore import vtkCommand
from vtkmodules.vtkCommonDataModel import vtkPolyData

import dynamicpoints
from dp_testing import MessageRecorder, TempDirTestCase, run_tool

FRAMES = 4


def source_of(folder):
    source = dynamicpoints.vtkPointSequenceSource()
    source.SetDirectoryName(folder)
    source.SetFilePattern("*.ply")
    return source


class Pipeline:
    """points -> tracker (300 vertices) -> detail, the detail's data from a source of its own."""

    def __init__(self, folder, levels=-1):
        self.source = source_of(folder)
        self.data = source_of(folder)
        self.tracker = dynamicpoints.vtkDeformableTrackFilter()
        self.tracker.SetInputConnection(self.source.GetOutputPort())
        self.tracker.SetTemplateVertices(300)
        self.detail = dynamicpoints.vtkSurfaceDetailFilter()
        self.detail.SetInputConnection(0, self.tracker.GetOutputPort())
        self.detail.SetDataConnection(self.data.GetOutputPort())
        self.detail.SetDetailLevels(levels)
        self.reads = 0

        def count(*_):
            self.reads += 1
        self.data.AddObserver(vtkCommand.EndEvent, count)

    def frame(self, t):
        self.detail.UpdateTimeStep(self.source.GetFrameTime(t))
        out = vtkPolyData()
        out.ShallowCopy(self.detail.GetOutput())
        return dsa.WrapDataObject(out)


class TestSurfaceDetailFilter(TempDirTestCase):
    @classmethod
    def setUpClass(cls):
        import tempfile
        cls._data = tempfile.TemporaryDirectory(prefix="dp-detail-")
        # Per-frame meshes of 3000 vertices (each its own connectivity, as a capture's), with
        # colour fixed to the material.
        cls.meshes = os.path.join(cls._data.name, "meshes")
        run_tool("dynamicpoints-sample", "--frames", FRAMES, "--points", 12000,
                 "--per-frame-mesh", 3000, "--colour", cls.meshes)

    @classmethod
    def tearDownClass(cls):
        cls._data.cleanup()

    def test_the_detail_of_per_frame_meshes_comes_back(self):
        p = Pipeline(self.meshes)
        fine = p.frame(2)
        # 3000-vertex captures over a 300-vertex mesh: two levels (16x the triangles) measured to
        # bring the surface closer.
        self.assertEqual(p.detail.GetLevelsUsed(), 2)
        choice = fine.FieldData["DetailChoice"].GetValue(0)
        self.assertTrue(choice.startswith("2 level(s): frame 0's data lie"), choice)
        base = np.array(fine.FieldData["BasePoints"])
        self.assertEqual(base.shape, (p.tracker.GetOutput().GetNumberOfPoints(), 3))
        self.assertGreater(fine.GetNumberOfPoints(), 15 * len(base))
        self.assertEqual(fine.GetNumberOfPolys(), 16 * len(fine.FieldData["BaseTriangles"]))
        for name in ("Detail", "Normals", "Observed", "Residual", "Colors"):
            self.assertIsNotNone(fine.GetPointData().GetArray(name), name)
        normals = np.array(fine.PointData["Normals"])
        np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1, atol=1e-5)
        # Nearly every fine vertex met its frame's mesh, and lies closer to it than the tracked
        # mesh's vertices do to theirs.
        observed = np.array(fine.PointData["Observed"])
        self.assertGreater(observed.mean(), 0.9)
        residual = np.array(fine.PointData["Residual"])
        self.assertTrue(np.all((residual >= 0) == (observed == 1)))
        tracked = dsa.WrapDataObject(p.tracker.GetOutput())
        self.assertLess(np.sqrt((residual[observed == 1] ** 2).mean()),
                        0.5 * np.sqrt((np.array(tracked.PointData["Residual"]) ** 2).mean()))
        # The tracker's figures ride along (what the compressor and the main job read).
        for name in ("DataSamples", "DataReach", "FrameIndex", "DetailLevels", "DetailSeconds"):
            self.assertIsNotNone(fine.GetFieldData().GetArray(name), name)

    def test_each_frame_is_fitted_once_and_the_times_are_the_trackers(self):
        p = Pipeline(self.meshes, levels=1)
        p.detail.UpdateInformation()
        steps = p.detail.GetOutputInformation(0).Get(p.detail.GetExecutive().TIME_STEPS())
        self.assertEqual(list(steps), [p.source.GetFrameTime(t) for t in range(FRAMES)])
        first = np.array(p.frame(1).Points)
        reads = p.reads
        p.frame(3)
        again = np.array(p.frame(1).Points)
        np.testing.assert_array_equal(first, again)
        self.assertEqual(p.reads, reads + 1)  # frame 3 read once, frame 1 not again

    def test_colour_is_carried_from_the_tracked_mesh(self):
        p = Pipeline(self.meshes, levels=1)
        fine = p.frame(0)
        colours = np.array(fine.PointData["Colors"])
        base = np.array(fine.FieldData["BaseColors"])
        tracked = np.array(dsa.WrapDataObject(p.tracker.GetOutput()).PointData["Colors"])
        np.testing.assert_array_equal(base, tracked[:, :3])
        # The base's own vertices come first in the fine mesh; each colour is a blend of its
        # neighbours', within their range.
        self.assertEqual(colours.shape, (fine.GetNumberOfPoints(), 3))
        self.assertLessEqual(colours.max(), base.max())
        self.assertGreaterEqual(colours.min(), base.min())

    def test_zero_levels_pass_the_tracked_mesh_through(self):
        p = Pipeline(self.meshes, levels=0)
        out = p.frame(1)
        np.testing.assert_array_equal(np.array(out.Points),
                                      np.array(dsa.WrapDataObject(p.tracker.GetOutput()).Points))
        self.assertEqual(out.FieldData["DetailLevels"][0], 0)

    def test_a_smooth_noisy_take_gets_no_detail(self):
        # Points with noise around a smooth tube: the data hold nothing the tracked mesh cannot
        # carry, and the automatic choice says so.
        folder = self.path("noisy")
        run_tool("dynamicpoints-sample", "--frames", 2, "--points", 6000, "--noise", 0.004,
                 folder)
        p = Pipeline(folder)
        out = p.frame(0)
        self.assertEqual(p.detail.GetLevelsUsed(), 0)
        self.assertIn("no detail layer", out.FieldData["DetailChoice"].GetValue(0))

    def test_bad_inputs_are_refused_or_said(self):
        # A tracked "mesh" without polygons (a point frame): an error naming the input, no
        # output.
        folder = self.path("points")
        run_tool("dynamicpoints-sample", "--frames", 2, "--points", 2000, folder)
        points = source_of(folder)
        points_only = dynamicpoints.vtkSurfaceDetailFilter()
        points_only.SetInputConnection(0, points.GetOutputPort())
        data = source_of(folder)  # kept: a connection does not keep its producer alive
        points_only.SetDataConnection(data.GetOutputPort())
        said = MessageRecorder(points_only)
        points_only.SetDetailLevels(1)
        points_only.Update()
        self.assertIn("tracked mesh (input 0) cannot be subdivided: it has no polygons",
                      said.error_text)
        self.assertEqual(points_only.GetOutput().GetNumberOfPoints(), 0)
        # A frame whose data file is empty: said, the subdivided tracked mesh given, no crash.
        folder = self.path("holey")
        os.makedirs(folder)
        for name in sorted(os.listdir(self.meshes))[:3]:
            if name.endswith(".ply"):
                os.symlink(os.path.join(self.meshes, name), os.path.join(folder, name))
        p = Pipeline(folder, levels=1)
        p.frame(0)
        with open(os.path.join(p.data.GetFramePath(1)), "rb") as f:
            self.assertTrue(f.read(3) == b"ply")
        empty = os.path.join(folder, "frame_0001.ply")
        os.remove(empty)
        with open(empty, "w") as f:
            f.write("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n"
                    "property float y\nproperty float z\nend_header\n")
        data = source_of(folder)
        p.detail.SetDataConnection(data.GetOutputPort())
        said = MessageRecorder(p.detail)
        out = p.frame(1)
        self.assertIn("frame 1: no detail", said.warning_text)
        self.assertTrue(np.all(np.array(out.PointData["Observed"]) == 0))
        self.assertTrue(np.all(np.array(out.PointData["Detail"]) == 0))

    def test_the_layer_goes_through_the_dpz(self):
        p = Pipeline(self.meshes, levels=1)
        writer = dynamicpoints.vtkCompressedSequenceWriter()
        writer.SetInputConnection(p.detail.GetOutputPort())
        writer.SetErrorMeasure(dynamicpoints.vtkPCACompressFilter.DISTANCE_TO_DATA)
        writer.SetFitGrowth(10)
        path = self.path("detailed.dpz")
        writer.SetFileName(path)
        self.assertEqual(writer.Write(), 1)
        reader = dynamicpoints.vtkCompressedSequenceReader()
        reader.SetFileName(path)
        reader.UpdateTimeStep(p.source.GetFrameTime(2))
        read = dsa.WrapDataObject(reader.GetOutput())
        fine = p.frame(2)
        self.assertEqual(read.GetNumberOfPoints(), fine.GetNumberOfPoints())
        self.assertEqual(read.FieldData["DetailLevels"][0], 1)
        self.assertIsNotNone(read.GetPointData().GetArray("Normals"))
        # Within the step of the fitted fine mesh (the tracked one's coding error added).
        diagonal = np.linalg.norm(np.ptp(np.array(fine.Points), axis=0))
        self.assertLess(np.abs(np.array(read.Points) - np.array(fine.Points)).max(),
                        0.02 * diagonal)
        reader.SetReadDetail(False)
        reader.UpdateTimeStep(p.source.GetFrameTime(2))
        self.assertEqual(reader.GetOutput().GetNumberOfPoints(),
                         p.tracker.GetOutput().GetNumberOfPoints())


if __name__ == "__main__":
    unittest.main()
