"""vtkDistanceFieldFilter from Python: values against exact nearest-point distances (scipy's
kd-tree), its arrays, bounds, time, and bad input."""
import unittest

import numpy as np
from scipy.spatial import cKDTree
from vtkmodules.numpy_interface import dataset_adapter as dsa
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkPolyData

import dynamicpoints
from dp_testing import MessageRecorder, TempDirTestCase, run_tool


def image_points(image):
    """Coordinates of an image's points, x fastest (VTK's order)."""
    nx, ny, nz = image.GetDimensions()
    ox, oy, oz = image.GetOrigin()
    sx, sy, sz = image.GetSpacing()
    z, y, x = np.meshgrid(oz + sz * np.arange(nz), oy + sy * np.arange(ny), ox + sx * np.arange(nx),
                          indexing="ij")
    return np.column_stack([x.ravel(), y.ravel(), z.ravel()])


def polydata(xyz):
    pd = vtkPolyData()
    points = vtkPoints()
    points.SetData(dsa.numpyTovtkDataArray(np.ascontiguousarray(xyz, dtype=np.float64)))
    pd.SetPoints(points)
    return pd


class TestDistanceFieldFilter(TempDirTestCase):
    def setUp(self):
        super().setUp()
        run_tool("dynamicpoints-sample", "--frames", 6, "--points", 4000, self.path("seq"))
        self.source = dynamicpoints.vtkPointSequenceSource()
        self.source.SetFileName(self.path("seq", "points.series"))

    def field(self, **settings):
        f = dynamicpoints.vtkDistanceFieldFilter()
        f.SetInputConnection(self.source.GetOutputPort())
        f.SetDimensions(30, 30, 30)
        for name, value in settings.items():
            getattr(f, "Set" + name)(*value) if isinstance(value, tuple) else getattr(f, "Set" + name)(value)
        return f

    def test_distances_match_exact_nearest_points_within_the_stated_bound(self):
        voxel = 0.02
        f = self.field(VoxelSize=voxel, BandWidth=0.06)
        f.Update()
        image = dsa.WrapDataObject(f.GetOutput())
        grid = image_points(f.GetOutput())
        cloud = dsa.WrapDataObject(self.source.GetOutput())
        tree = cKDTree(np.asarray(cloud.Points))
        exact, nearest = tree.query(grid)
        distance = np.asarray(image.PointData["Distance"])
        error = np.abs(distance - exact)
        # Trilinear interpolation of exact voxel-centre distances: bound stated in voxels.
        self.assertLess(error.max(), 0.75 * voxel)
        self.assertLess(np.sqrt((error ** 2).mean()), 0.2 * voxel)
        # The reported nearest point is (about) as near as the true one.
        ids = np.asarray(image.PointData["NearestPointId"])
        via_ids = np.linalg.norm(grid - np.asarray(cloud.Points)[ids], axis=1)
        self.assertLess(np.abs(via_ids - exact).max(), 0.75 * voxel)
        # Far from the data the gradient is a unit vector pointing away from the nearest point.
        far = exact > 4 * voxel
        self.assertGreater(far.sum(), 1000)
        gradient = np.asarray(image.PointData["Gradient"])[far]
        away = (grid - np.asarray(cloud.Points)[nearest])[far]
        away /= np.linalg.norm(away, axis=1, keepdims=True)
        cosine = (gradient * away).sum(axis=1) / np.linalg.norm(gradient, axis=1)
        self.assertGreater(np.mean(cosine > 0.95), 0.95)
        self.assertEqual(image.PointData["InBand"].max(), 1)
        self.assertEqual(image.PointData["InBand"].min(), 0)
        self.assertGreater(f.GetOutput().GetFieldData().GetArray("ActiveVoxels").GetValue(0), 1000)

    def test_nearest_normals_come_from_the_input_or_are_estimated(self):
        f = self.field(VoxelSize=0.03)
        f.Update()
        image = dsa.WrapDataObject(f.GetOutput())
        cloud = dsa.WrapDataObject(self.source.GetOutput())
        ids = np.asarray(image.PointData["NearestPointId"])
        np.testing.assert_allclose(image.PointData["NearestNormal"],
                                   np.asarray(cloud.PointData["Normals"])[ids], atol=1e-6)
        # Without input normals: estimated, unit length, mostly agreeing with the true ones.
        bare = polydata(cloud.Points)
        g = dynamicpoints.vtkDistanceFieldFilter()
        g.SetInputData(bare)
        g.SetDimensions(20, 20, 20)
        g.Update()
        estimated = dsa.WrapDataObject(g.GetOutput()).PointData["NearestNormal"]
        ids = np.asarray(dsa.WrapDataObject(g.GetOutput()).PointData["NearestPointId"])
        np.testing.assert_allclose(np.linalg.norm(estimated, axis=1), 1, atol=1e-5)
        agree = (np.asarray(estimated) * np.asarray(cloud.PointData["Normals"])[ids]).sum(axis=1)
        self.assertGreater(np.mean(agree > 0.8), 0.9)
        g.ComputeNormalsOff()
        g.Update()
        self.assertIsNone(g.GetOutput().GetPointData().GetArray("NearestNormal"))

    def test_bounds_follow_the_input_and_the_time_step(self):
        f = self.field(AdjustDistance=0.1)
        f.UpdateTimeStep(0)
        bounds0 = f.GetOutput().GetBounds()
        points = self.source.GetOutput().GetBounds()
        diagonal = np.linalg.norm(np.subtract(points[1::2], points[0::2]))
        np.testing.assert_allclose(bounds0[0::2], np.array(points[0::2]) - 0.1 * diagonal, rtol=1e-6)
        f.UpdateTimeStep(2)
        self.assertNotEqual(f.GetOutput().GetBounds(), bounds0)  # the tube bent
        f.AdjustBoundsOff()
        f.SetBounds(-1, 1, -1, 1, 0, 2)
        f.Update()
        np.testing.assert_allclose(f.GetOutput().GetBounds(), (-1, 1, -1, 1, 0, 2))

    def test_bad_input_and_absurd_parameters_are_clear_errors(self):
        cases = []
        empty = dynamicpoints.vtkDistanceFieldFilter()
        empty.SetInputData(vtkPolyData())
        cases.append((empty, "has no points"))
        negative = self.field(VoxelSize=-0.5)
        cases.append((negative, "VoxelSize must be positive"))
        huge = self.field(VoxelSize=1e-5, BandWidth=0.5)
        cases.append((huge, "use a larger voxel size"))
        too_many_samples = self.field(Dimensions=(3000, 3000, 3000))
        cases.append((too_many_samples, "output samples"))
        for f, message in cases:
            rec = MessageRecorder(f)
            f.Update()
            self.assertIn(message, rec.error_text)
        nan = np.random.default_rng(1).uniform(size=(100, 3))
        nan[[5, 7]] = np.nan
        f = dynamicpoints.vtkDistanceFieldFilter()
        f.SetInputData(polydata(nan))
        f.SetDimensions(10, 10, 10)
        rec = MessageRecorder(f)
        f.Update()
        self.assertEqual(rec.errors, [])
        self.assertIn("dropped 2 input point(s)", rec.warning_text)
        ids = dsa.WrapDataObject(f.GetOutput()).PointData["NearestPointId"]
        self.assertNotIn(5, np.asarray(ids))


if __name__ == "__main__":
    unittest.main()
