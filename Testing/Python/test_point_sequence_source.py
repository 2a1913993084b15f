"""vtkPointSequenceSource from Python, on files written by other tools (Open3D, VTK's writers)
and by the product's own sampler, and on bad input."""
import json
import os
import subprocess
import unittest

import numpy as np
import open3d as o3d
from vtkmodules.numpy_interface import dataset_adapter as dsa
from vtkmodules.vtkCommonCore import vtkPoints, vtkFloatArray, vtkUnsignedCharArray
from vtkmodules.vtkCommonDataModel import vtkPolyData, vtkUnstructuredGrid, vtkCellArray
from vtkmodules.vtkCommonExecutionModel import vtkAlgorithm, vtkStreamingDemandDrivenPipeline
from vtkmodules.vtkIOGeometry import vtkOBJWriter
from vtkmodules.vtkIOLegacy import vtkPolyDataWriter, vtkSimplePointsWriter
from vtkmodules.vtkIOPLY import vtkPLYWriter
from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter, vtkXMLUnstructuredGridWriter

import dynamicpoints
from dp_testing import MessageRecorder, TempDirTestCase, run_tool

RNG = np.random.default_rng(7)
XYZ = RNG.uniform(-2.0, 3.0, size=(257, 3))
NORMALS = RNG.normal(size=(257, 3))
NORMALS /= np.linalg.norm(NORMALS, axis=1, keepdims=True)
COLORS = RNG.integers(0, 256, size=(257, 3)).astype(np.uint8)


def read_one(path):
    """Reads one file with the source; returns (polydata as dsa, source, recorder)."""
    source = dynamicpoints.vtkPointSequenceSource()
    recorder = MessageRecorder(source)
    source.SetFileName(path)
    source.Update()
    return dsa.WrapDataObject(source.GetOutput()), source, recorder


def vtk_polydata(with_faces=False):
    """XYZ/NORMALS/COLORS as vtkPolyData (optionally a triangle fan over the first points)."""
    pd = vtkPolyData()
    points = vtkPoints()
    points.SetData(dsa.numpyTovtkDataArray(XYZ, "Points"))
    pd.SetPoints(points)
    normals = dsa.numpyTovtkDataArray(NORMALS.astype(np.float32), "Normals")
    pd.GetPointData().SetNormals(normals)
    colors = vtkUnsignedCharArray()
    colors.SetName("RGB")
    colors.SetNumberOfComponents(3)
    for c in COLORS:
        colors.InsertNextTuple3(*c)
    pd.GetPointData().SetScalars(colors)
    if with_faces:
        polys = vtkCellArray()
        for i in range(1, 20):
            polys.InsertNextCell(3, [0, i, i + 1])
        pd.SetPolys(polys)
    return pd


class TestImport(unittest.TestCase):
    def test_classes_are_exposed_by_their_vtk_names(self):
        self.assertTrue(issubclass(dynamicpoints.vtkPointSequenceSource, vtkAlgorithm))
        source = dynamicpoints.vtkPointSequenceSource()
        self.assertEqual(source.GetClassName(), "vtkPointSequenceSource")
        self.assertTrue(source.CanReadFile("scan.PCD"))
        self.assertTrue(source.CanReadFile("frames.series"))
        self.assertFalse(source.CanReadFile("scan.las"))


class TestFilesFromDraco(TempDirTestCase):
    """Google Draco's own tools (Debian's draco): draco_encoder writes the .drc frames a capture
    tool would, draco_decoder gives the reference; and our .drc files are read by Draco."""

    def draco(self, tool, *args):
        result = subprocess.run([tool, *map(str, args)], capture_output=True, text=True,
                                timeout=120)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)

    def expect_same(self, drc, reference_ply, faces):
        ours, _, rec = read_one(drc)
        self.assertEqual(rec.errors, [])
        theirs, _, _ = read_one(reference_ply)
        self.assertGreater(ours.GetNumberOfPoints(), 100)
        np.testing.assert_array_equal(ours.Points, theirs.Points)
        np.testing.assert_array_equal(ours.PointData["RGB"], theirs.PointData["RGB"])
        self.assertEqual(ours.GetNumberOfPolys(), faces)
        if faces:
            np.testing.assert_array_equal(ours.Polygons, theirs.Polygons)
        return ours

    def test_draco_encoder_meshes_and_point_clouds_read_as_draco_decoder_gives_them(self):
        run_tool("dynamicpoints-sample", "--frames", 1, "--per-frame-mesh", 2000, "--colour",
                 self.path("meshes"))
        run_tool("dynamicpoints-sample", "--frames", 1, "--points", 3000, "--colour",
                 self.path("points"))
        mesh_ply = self.path("meshes", "frame_0000.ply")
        faces = read_one(mesh_ply)[0].GetNumberOfPolys()
        self.assertGreater(faces, 3000)
        for name, source, extra, expected_faces in (
                ("mesh", mesh_ply, ["-cl", 7], faces),
                ("cloud", self.path("points", "frame_0000.ply"), ["-point_cloud"], 0)):
            drc, back = self.path(name + ".drc"), self.path(name + "_decoded.ply")
            self.draco("draco_encoder", "-i", source, "-o", drc, "-qp", 14, *extra)
            self.draco("draco_decoder", "-i", drc, "-o", back)
            self.expect_same(drc, back, expected_faces)

    def test_our_drc_frames_are_read_by_draco_decoder(self):
        run_tool("dynamicpoints-sample", "--frames", 2, "--per-frame-mesh", 2000, "--colour",
                 "--format", "drc", self.path("take"))
        drc = self.path("take", "frame_0001.drc")
        back = self.path("decoded.ply")
        self.draco("draco_decoder", "-i", drc, "-o", back)
        ours = self.expect_same(drc, back, read_one(back)[0].GetNumberOfPolys())
        self.assertGreater(ours.GetNumberOfPolys(), 3000)


class TestFilesFromOpen3D(TempDirTestCase):
    """Open3D writes PLY, PCD (ascii, binary, LZF-compressed), XYZ, XYZN and PTS."""

    def cloud(self):
        pc = o3d.geometry.PointCloud()
        pc.points = o3d.utility.Vector3dVector(XYZ)
        pc.normals = o3d.utility.Vector3dVector(NORMALS)
        pc.colors = o3d.utility.Vector3dVector(COLORS / 255.0)
        return pc

    def check(self, name, normals=True, colors=True, **kwargs):
        path = self.path(name)
        self.assertTrue(o3d.io.write_point_cloud(path, self.cloud(), **kwargs), path)
        out, source, rec = read_one(path)
        self.assertEqual(rec.errors, [], name)
        # Open3D's text writers keep 6 significant digits.
        tol = 1e-5 if kwargs.get("write_ascii") or not name.endswith((".ply", ".pcd")) else 2e-7
        np.testing.assert_allclose(out.Points, XYZ, rtol=tol, atol=tol, err_msg=name)
        self.assertEqual(out.GetNumberOfVerts(), len(XYZ))
        if normals:
            np.testing.assert_allclose(out.PointData["Normals"], NORMALS, rtol=tol, atol=tol,
                                       err_msg=name)
        if colors:
            np.testing.assert_array_equal(out.PointData["RGB"], COLORS, err_msg=name)
        return out

    def test_ply_ascii_and_binary(self):
        self.check("o3d_ascii.ply", write_ascii=True)
        self.check("o3d_binary.ply", write_ascii=False)

    def test_pcd_ascii_binary_and_compressed(self):
        self.check("o3d_ascii.pcd", write_ascii=True)
        self.check("o3d_binary.pcd", write_ascii=False)
        self.check("o3d_lzf.pcd", write_ascii=False, compressed=True)

    def test_xyz_family(self):
        self.check("o3d.xyz", normals=False, colors=False)
        # Open3D's .xyzn is "x y z nx ny nz": the same layout as our .xyz with normals.
        path = self.path("o3d.xyzn")
        o3d.io.write_point_cloud(path, self.cloud())
        os.rename(path, self.path("o3d_normals.xyz"))
        out, _, rec = read_one(self.path("o3d_normals.xyz"))
        self.assertEqual(rec.errors, [])
        np.testing.assert_allclose(out.PointData["Normals"], NORMALS, rtol=1e-5, atol=1e-5)

    def test_pts(self):
        out = self.check("o3d.pts", normals=False, colors=True)
        self.assertEqual(out.GetNumberOfPoints(), len(XYZ))


class TestFilesFromVTKWriters(TempDirTestCase):
    def test_ply_writer_big_endian_and_ascii_with_faces(self):
        for name, configure in (("be.ply", lambda w: (w.SetFileTypeToBinary(),
                                                      w.SetDataByteOrderToBigEndian())),
                                ("ascii.ply", lambda w: w.SetFileTypeToASCII())):
            writer = vtkPLYWriter()
            writer.SetInputData(vtk_polydata(with_faces=True))
            writer.SetFileName(self.path(name))
            writer.SetArrayName("RGB")
            configure(writer)
            self.assertEqual(writer.Write(), 1)
            out, _, rec = read_one(self.path(name))
            self.assertEqual(rec.errors, [], name)
            np.testing.assert_allclose(out.Points, XYZ, atol=1e-5, err_msg=name)
            np.testing.assert_allclose(out.PointData["Normals"], NORMALS, atol=1e-6)
            np.testing.assert_array_equal(out.PointData["RGB"], COLORS)
            self.assertEqual(out.GetNumberOfPolys(), 19, name)

    def test_xml_and_legacy_and_obj_writers(self):
        # The XML writers' default "appended" data is what VTK 9.2 fails to read with
        # expat >= 2.6 unless reparse deferral is off (see Filters/Private/vtkDPXMLReaders.h).
        pd = vtk_polydata(with_faces=True)
        extra = vtkFloatArray()
        extra.SetName("Confidence")
        for i in range(len(XYZ)):
            extra.InsertNextValue(i * 0.5)
        pd.GetPointData().AddArray(extra)
        ug = vtkUnstructuredGrid()
        ug.SetPoints(pd.GetPoints())
        ug.GetPointData().ShallowCopy(pd.GetPointData())
        for name, writer, data in (("poly.vtp", vtkXMLPolyDataWriter(), pd),
                                   ("grid.vtu", vtkXMLUnstructuredGridWriter(), ug),
                                   ("legacy.vtk", vtkPolyDataWriter(), pd)):
            writer.SetInputData(data)
            writer.SetFileName(self.path(name))
            self.assertEqual(writer.Write(), 1)
            out, _, rec = read_one(self.path(name))
            self.assertEqual(rec.errors, [], name)
            np.testing.assert_allclose(out.Points, XYZ, atol=1e-12, err_msg=name)
            np.testing.assert_allclose(out.PointData["Confidence"], np.arange(len(XYZ)) * 0.5)
            self.assertEqual(out.GetNumberOfVerts(), len(XYZ))

        obj = vtkOBJWriter()
        obj.SetInputData(pd)
        obj.SetFileName(self.path("mesh.obj"))
        self.assertEqual(obj.Write(), 1)
        out, _, rec = read_one(self.path("mesh.obj"))
        self.assertEqual(rec.errors, [])
        # vtkOBJWriter writes only the points that the faces use.
        self.assertEqual(out.GetNumberOfPolys(), 19)
        self.assertGreaterEqual(out.GetNumberOfPoints(), 21)

        simple = vtkSimplePointsWriter()
        simple.SetInputData(pd)
        simple.SetFileName(self.path("simple.xyz"))
        simple.SetDecimalPrecision(17)
        self.assertEqual(simple.Write(), 1)
        out, _, rec = read_one(self.path("simple.xyz"))
        np.testing.assert_allclose(out.Points, XYZ, atol=1e-12)


class TestSequences(TempDirTestCase):
    def test_sampler_sequence_reads_through_time(self):
        result = run_tool("dynamicpoints-sample", "--mesh", "sheet", "--frames", 6, "--points",
                          2000, "--holes", 2, "--hole-radius", 0.1, "--moving-holes", "--noise",
                          0.001, "--interval", 0.04, self.path("seq"))
        self.assertIn("wrote 6 frames", result.stdout)
        source = dynamicpoints.vtkPointSequenceSource()
        source.SetFileName(self.path("seq", "points.series"))
        source.UpdateInformation()
        info = source.GetOutputInformation(0)
        times = [info.Get(vtkStreamingDemandDrivenPipeline.TIME_STEPS(), i)
                 for i in range(info.Length(vtkStreamingDemandDrivenPipeline.TIME_STEPS()))]
        np.testing.assert_allclose(times, np.arange(6) * 0.04)
        counts = []
        for t in times:
            source.UpdateTimeStep(t)
            out = dsa.WrapDataObject(source.GetOutput())
            self.assertAlmostEqual(out.GetInformation().Get(out.DATA_TIME_STEP()), t)
            counts.append(out.GetNumberOfPoints())
            np.testing.assert_allclose(np.linalg.norm(out.PointData["Normals"], axis=1), 1, atol=1e-5)
        self.assertTrue(all(0 < c < 2000 for c in counts), counts)  # holes removed points
        self.assertGreater(len(set(counts)), 1, "moving holes give different counts per frame")

    def test_sampler_is_deterministic(self):
        for name in ("a", "b"):
            run_tool("dynamicpoints-sample", "--frames", 2, "--points", 500, "--seed", 42,
                     "--noise", 0.01, self.path(name))
        for f in ("frame_0000.ply", "frame_0001.ply", "points.series"):
            with open(self.path("a", f), "rb") as a, open(self.path("b", f), "rb") as b:
                self.assertEqual(a.read(), b.read(), f)
        run_tool("dynamicpoints-sample", "--frames", 2, "--points", 500, "--seed", 43,
                 "--noise", 0.01, self.path("c"))
        with open(self.path("a", "frame_0001.ply"), "rb") as a, \
                open(self.path("c", "frame_0001.ply"), "rb") as c:
            self.assertNotEqual(a.read(), c.read())

    def test_folder_and_pattern_natural_order(self):
        for i in (10, 2, 1):
            np.savetxt(self.path(f"scan{i}.xyz"), np.full((i, 3), float(i)))
        np.savetxt(self.path("other1.xyz"), np.zeros((3, 3)))
        source = dynamicpoints.vtkPointSequenceSource()
        source.SetDirectoryName(self.tmp)
        source.SetFilePattern("scan*.xyz")
        self.assertEqual(source.GetNumberOfFrames(), 3)
        sizes = []
        for f in range(3):
            source.UpdateTimeStep(source.GetFrameTime(f))
            sizes.append(source.GetOutput().GetNumberOfPoints())
        self.assertEqual(sizes, [1, 2, 10])


class TestBadInput(TempDirTestCase):
    def test_missing_file(self):
        _, source, rec = read_one(self.path("absent.ply"))
        self.assertIn(self.path("absent.ply"), rec.error_text)
        self.assertIn("cannot open", rec.error_text)
        self.assertNotEqual(source.GetErrorCode(), 0)

    def test_truncated_binary_pcd_from_open3d(self):
        pc = o3d.geometry.PointCloud()
        pc.points = o3d.utility.Vector3dVector(XYZ)
        path = self.path("cut.pcd")
        o3d.io.write_point_cloud(path, pc, write_ascii=False)
        data = open(path, "rb").read()
        open(path, "wb").write(data[:-100])
        out, _, rec = read_one(path)
        self.assertIn(path, rec.error_text)
        self.assertIn("truncated", rec.error_text)
        self.assertEqual(out.GetNumberOfPoints(), 0)

    def test_unknown_extension_in_a_series(self):
        with open(self.path("s.series"), "w") as f:
            json.dump({"file-series-version": "1.0", "files": [{"name": "a.e57", "time": 0}]}, f)
        _, _, rec = read_one(self.path("s.series"))
        self.assertIn("a.e57: unknown file extension", rec.error_text)

    def test_nan_points_are_dropped_with_a_count(self):
        xyz = XYZ.copy()
        xyz[[3, 50, 51], 1] = np.nan
        xyz[60, 2] = np.inf
        np.savetxt(self.path("nan.xyz"), xyz)
        out, source, rec = read_one(self.path("nan.xyz"))
        self.assertEqual(out.GetNumberOfPoints(), len(XYZ) - 4)
        self.assertEqual(source.GetNumberOfDroppedPoints(), 4)
        self.assertIn("dropped 4 point(s)", rec.warning_text)
        self.assertIn("nan.xyz", rec.warning_text)
        self.assertEqual(rec.errors, [])

    def test_nan_points_of_a_vtk_file_are_dropped_with_their_faces(self):
        # A fan of 19 triangles around point 0 over points 1..20: point 5 is NaN, so the two
        # triangles that use it go, the others keep their points, renumbered past the gap.
        pd = vtk_polydata(with_faces=True)
        xyz = XYZ.copy()  # the polydata's points share XYZ's memory: not in place
        xyz[5, 0] = np.nan
        points = vtkPoints()
        points.SetData(dsa.numpyTovtkDataArray(xyz, "Points"))
        pd.SetPoints(points)
        writer = vtkXMLPolyDataWriter()
        writer.SetInputData(pd)
        writer.SetFileName(self.path("nan.vtp"))
        self.assertEqual(writer.Write(), 1)
        out, source, rec = read_one(self.path("nan.vtp"))
        self.assertEqual(source.GetNumberOfDroppedPoints(), 1)
        self.assertIn("dropped 1 point(s)", rec.warning_text)
        kept = np.delete(XYZ, 5, axis=0)
        np.testing.assert_allclose(out.Points, kept, atol=1e-12)
        np.testing.assert_array_equal(out.PointData["RGB"], np.delete(COLORS, 5, axis=0))
        self.assertEqual(out.GetNumberOfVerts(), len(kept))
        faces = out.GetPolys()
        self.assertEqual(faces.GetNumberOfCells(), 17)
        ids = np.array(dsa.vtkDataArrayToVTKArray(faces.GetConnectivityArray())).reshape(-1, 3)
        expected = [[0, i, i + 1] for i in range(1, 20) if 5 not in (i, i + 1)]
        expected = [[v - (v > 5) for v in face] for face in expected]
        np.testing.assert_array_equal(ids, expected)

    def test_empty_frame_is_a_warning_and_an_empty_output(self):
        open(self.path("empty.ply"), "w").write(
            "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n"
            "property float y\nproperty float z\nend_header\n")
        out, _, rec = read_one(self.path("empty.ply"))
        self.assertEqual(out.GetNumberOfPoints(), 0)
        self.assertEqual(rec.errors, [])
        self.assertIn("empty.ply: empty frame", rec.warning_text)


if __name__ == "__main__":
    unittest.main()
