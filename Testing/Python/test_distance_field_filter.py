"""vtkDistanceFieldFilter from Python: values against exact nearest-point distances (scipy's
kd-tree) within the band and beyond, its arrays, bounds, time, and bad input."""
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

    def test_exact_in_the_band_and_a_close_upper_bound_beyond(self):
        band = 0.06
        f = self.field(BandWidth=band)
        f.Update()
        image = dsa.WrapDataObject(f.GetOutput())
        voxel = max(f.GetOutput().GetSpacing())
        grid = image_points(f.GetOutput())
        cloud = dsa.WrapDataObject(self.source.GetOutput())
        tree = cKDTree(np.asarray(cloud.Points))
        exact, nearest = tree.query(grid)
        distance = np.asarray(image.PointData["Distance"])
        in_band = np.asarray(image.PointData["InBand"]) == 1
        # The band is exactly where the nearest point is within BandWidth (up to rounding).
        clear = np.abs(exact - band) > 1e-6
        np.testing.assert_array_equal(in_band[clear], (exact <= band)[clear])
        self.assertGreater(in_band.sum(), 1000)
        self.assertGreater((~in_band).sum(), 5000)
        # Within the band: exact (float32). Beyond: a real point, so never nearer than the
        # nearest, and within a voxel of it.
        np.testing.assert_allclose(distance[in_band], exact[in_band], atol=1e-6)
        error = distance[~in_band] - exact[~in_band]
        self.assertGreater(error.min(), -1e-6)
        self.assertLess(error.max(), voxel)
        self.assertLess(np.sqrt((error ** 2).mean()), 0.15 * voxel)
        # The reported nearest point is at the reported distance.
        ids = np.asarray(image.PointData["NearestPointId"])
        via_ids = np.linalg.norm(grid - np.asarray(cloud.Points)[ids], axis=1)
        np.testing.assert_allclose(via_ids, distance, atol=1e-6)
        # The gradient is the unit vector away from the reported nearest point; beyond the band
        # it points about the way the true nearest point's does.
        gradient = np.asarray(image.PointData["Gradient"])
        moved = distance > 1e-6
        np.testing.assert_allclose(gradient[moved], ((grid - np.asarray(cloud.Points)[ids])
                                                     / distance[:, None])[moved], atol=1e-4)
        far = ~in_band
        away = (grid - np.asarray(cloud.Points)[nearest])[far]
        away /= np.linalg.norm(away, axis=1, keepdims=True)
        cosine = (gradient[far] * away).sum(axis=1)
        self.assertGreater(cosine.mean(), 0.97)
        self.assertGreater(np.mean(cosine > 0.8), 0.95)
        fields = f.GetOutput().GetFieldData()
        self.assertEqual(fields.GetArray("BandVoxels").GetValue(0), in_band.sum())
        self.assertAlmostEqual(fields.GetArray("BandWidth").GetValue(0), band)

    def test_the_default_band_is_three_voxels_of_the_image(self):
        f = self.field()
        f.Update()
        voxel = max(f.GetOutput().GetSpacing())
        band = f.GetOutput().GetFieldData().GetArray("BandWidth").GetValue(0)
        self.assertAlmostEqual(band, 3 * voxel)

    def test_nearest_normals_come_from_the_input_or_are_estimated(self):
        f = self.field()
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
        negative = self.field(BandWidth=-0.5)
        cases.append((negative, "BandWidth must be positive"))
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
