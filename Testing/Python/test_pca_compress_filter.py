"""vtkPCACompressFilter, vtkCompressedSequenceWriter and vtkCompressedSequenceReader in a VTK
pipeline: the error target on a generated animated mesh, the file round trip, a damaged file, the
glTF export read back by VTK's own glTF reader, and a sequence whose connectivity changes."""
import json
import os
import unittest

import numpy as np
from vtkmodules.numpy_interface import dataset_adapter as dsa
from vtkmodules.vtkIOGeometry import vtkGLTFReader

import dynamicpoints
from dp_testing import (MessageRecorder, TempDirTestCase, blender_report, decode_meshopt,
                        glb_colours, run_tool, validate_gltf)

FRAMES = 16


def first_polydata(data):
    """The first vtkPolyData leaf of a composite data set."""
    it = data.NewIterator()
    it.InitTraversal()
    while not it.IsDoneWithTraversal():
        leaf = it.GetCurrentDataObject()
        if leaf.IsA("vtkPolyData"):
            return leaf
        it.GoToNextItem()
    raise AssertionError("no polydata in the glTF reader's output")


class TestPCACompressFilter(TempDirTestCase):
    def setUp(self):
        super().setUp()
        # The ground-truth meshes of the built-in bending tube: one connectivity, 16 frames.
        run_tool("dynamicpoints-sample", "--mesh", "tube", "--frames", FRAMES, "--points", 100,
                 "--truth", self.path("seq"))
        truth = self.path("seq", "truth")
        self.files = sorted(os.path.join(truth, f) for f in os.listdir(truth) if f.endswith(".ply"))
        self.assertEqual(len(self.files), FRAMES)
        self.source = dynamicpoints.vtkPointSequenceSource()
        for f in self.files:
            self.source.AddFileName(f)

    def original(self, frame):
        self.source.UpdateTimeStep(frame)
        return np.array(dsa.WrapDataObject(self.source.GetOutput()).Points)

    def compressor(self, **settings):
        f = dynamicpoints.vtkPCACompressFilter()
        f.SetInputConnection(self.source.GetOutputPort())
        for name, value in settings.items():
            getattr(f, "Set" + name)(value)
        return f

    def write(self, path, source=None, **settings):
        """Writes the sequence (the tube's unless `source`) to `path` with the writer."""
        writer = dynamicpoints.vtkCompressedSequenceWriter()
        writer.SetInputConnection((source or self.source).GetOutputPort())
        for name, value in settings.items():
            getattr(writer, "Set" + name)(value)
        writer.SetFileName(path)
        self.assertEqual(writer.Write(), 1)
        self.assertTrue(os.path.exists(path))
        self.assertFalse(os.path.exists(path + ".partial"))
        return writer

    def test_meets_the_error_target_and_reports_it(self):
        originals = np.stack([self.original(t) for t in range(FRAMES)])
        for layout in (0, 1):
            f = self.compressor(Layout=layout, KGTarget=0.2)
            rebuilt = []
            for t in range(FRAMES):
                f.UpdateTimeStep(t)
                out = dsa.WrapDataObject(f.GetOutput())
                rebuilt.append(np.array(out.Points))
                np.testing.assert_allclose(
                    out.PointData["CompressionError"],
                    np.linalg.norm(rebuilt[-1] - originals[t], axis=1), rtol=1e-5, atol=1e-7)
                self.assertEqual(out.GetNumberOfPolys(), self.source.GetOutput().GetNumberOfPolys())
            rebuilt = np.stack(rebuilt)
            centred = originals - originals.mean(axis=1, keepdims=True)
            kg = 100 * np.linalg.norm(originals - rebuilt) / np.linalg.norm(centred)
            fd = dsa.WrapDataObject(f.GetOutput()).FieldData
            self.assertLessEqual(kg, 0.2)
            self.assertGreater(kg, 0.02)
            self.assertAlmostEqual(fd["KGError"][0], kg, places=6)
            k = fd["Components"][0]
            nv = originals.shape[1]
            self.assertEqual(fd["PaperD0"][0], 3 * FRAMES * nv)
            self.assertEqual(fd["PaperD1"][0], 3 * FRAMES * k + nv * k)
            self.assertLess(fd["BitsPerVertexFrame"][0], fd["QuantizedPlainBitsPerVertexFrame"][0])

    def test_the_file_reads_back_the_filters_sequence(self):
        path = self.path("tube.dpz")
        self.write(path)
        f = self.compressor()  # the same settings: the writer runs this filter's codec
        reader = dynamicpoints.vtkCompressedSequenceReader()
        self.assertEqual(reader.CanReadFile(path), 1)
        self.assertEqual(reader.CanReadFile(self.files[0]), 0)
        reader.SetFileName(path)
        reader.UpdateInformation()
        steps = reader.GetOutputInformation(0).Get(reader.GetExecutive().TIME_STEPS())
        self.assertEqual(len(steps), FRAMES)
        for t in (0, 5, FRAMES - 1):
            f.UpdateTimeStep(t)
            reader.UpdateTimeStep(steps[t])
            np.testing.assert_array_equal(dsa.WrapDataObject(reader.GetOutput()).Points,
                                          dsa.WrapDataObject(f.GetOutput()).Points)
            self.assertEqual(reader.GetOutput().GetNumberOfPolys(),
                             f.GetOutput().GetNumberOfPolys())

    def test_pieces_other_than_zero_are_empty_and_write_nothing(self):
        f = self.compressor()
        rec = MessageRecorder(f)
        f.UpdatePiece(1, 2, 0)
        self.assertEqual(f.GetOutput().GetNumberOfPoints(), 0)
        self.assertEqual(rec.errors, [])
        self.assertEqual(f.GetFailureMessage(), "")
        # The writer on a process other than the first (ParaView sets its piece): no file, no
        # error; piece 0 writes.
        writer = dynamicpoints.vtkCompressedSequenceWriter()
        writer.SetInputConnection(self.source.GetOutputPort())
        writer.SetFileName(self.path("piece1.dpz"))
        writer.SetPiece(1)
        writer.SetNumberOfPieces(2)
        rec = MessageRecorder(writer)
        self.assertEqual(writer.Write(), 1)
        self.assertEqual(rec.errors, [])
        self.assertFalse(os.path.exists(self.path("piece1.dpz")))
        writer.SetPiece(0)
        self.assertEqual(writer.Write(), 1)
        self.assertTrue(os.path.exists(self.path("piece1.dpz")))

    def test_the_writer_names_the_file_and_the_reason_when_it_cannot_write(self):
        writer = self.write(self.path("first.dpz"), KGTarget=0.5)
        # A file that cannot be written: an error naming it, nothing left behind.
        rec = MessageRecorder(writer)
        writer.SetFileName(self.path("no-such-folder", "x.dpz"))
        self.assertEqual(writer.Write(), 0)
        self.assertIn("no-such-folder/x.dpz", rec.error_text)
        self.assertFalse(os.path.exists(self.path("no-such-folder")))
        writer.SetFileName(None)
        self.assertEqual(writer.Write(), 0)
        self.assertIn("no FileName", rec.error_text)
        # A sequence the codec refuses: the writer's error says which file and why, once.
        self.add_another_connectivity()
        rec = MessageRecorder(writer)
        writer.SetFileName(self.path("changed.glb"))
        self.assertEqual(writer.Write(), 0)
        self.assertEqual(len(rec.errors), 1, rec.errors)
        self.assertIn(f"changed.glb: not written: frame {FRAMES} has", rec.error_text)
        self.assertFalse(os.path.exists(self.path("changed.glb")))

    def test_a_damaged_file_is_named_in_the_error_and_gives_no_geometry(self):
        path = self.path("tube.dpz")
        self.write(path)
        with open(path, "rb") as f:
            data = f.read()
        for name, content in (("cut.dpz", data[: len(data) // 2]),
                              ("flipped.dpz", data[:-10] + bytes([data[-10] ^ 0xFF]) + data[-9:]),
                              ("text.dpz", b"hello")):
            with open(self.path(name), "wb") as out:
                out.write(content)
            reader = dynamicpoints.vtkCompressedSequenceReader()
            reader.SetFileName(self.path(name))
            rec = MessageRecorder(reader)
            reader.Update()
            self.assertIn(name, rec.error_text)
            self.assertEqual(reader.GetOutput().GetNumberOfPoints(), 0)

    def test_a_header_claiming_billions_of_vertices_is_refused_by_the_budget(self):
        # The report's 144-byte file: version 1, trajectories, one frame, no components, no
        # triangles, 2^31 vertices, its checksums right. It grew to 17 GB and aborted the reader.
        import struct
        import zlib
        header = struct.pack("<BQQQQdd", 0, 2**31, 1, 0, 0, 1e-3, 1e-3) + struct.pack("<d", 0.0)
        data = (b"\x89DPZ\r\n\x1a\n" + struct.pack("<IQ", 1, len(header)) + header +
                struct.pack("<I", zlib.crc32(header)) + bytes(64))  # sections never reached
        path = self.path("billions.dpz")
        with open(path, "wb") as out:
            out.write(data)
        reader = dynamicpoints.vtkCompressedSequenceReader()
        reader.SetFileName(path)
        rec = MessageRecorder(reader)
        reader.Update()
        self.assertIn("billions.dpz: reading it needs", rec.error_text)
        self.assertIn("more than the memory budget of 8.0 GiB", rec.error_text)
        self.assertIn("DP_MEMORY_BUDGET", rec.error_text)
        self.assertEqual(reader.GetOutput().GetNumberOfPoints(), 0)

    def test_the_gltf_export_plays_back_in_vtk_within_the_target(self):
        glb = self.path("tube.glb")
        self.write(glb, KGTarget=0.2)
        f = self.compressor(KGTarget=0.2)
        f.Update()
        k = int(dsa.WrapDataObject(f.GetOutput()).FieldData["Components"][0])
        reader = vtkGLTFReader()
        reader.SetFileName(glb)
        reader.UpdateInformation()
        self.assertEqual(reader.GetNumberOfAnimations(), 1)
        reader.EnableAnimation(0)
        reader.SetApplyDeformationsToGeometry(True)
        reader.SetFrameRate(24)  # the export keys one frame every 1/24 s
        reader.UpdateInformation()
        steps = reader.GetOutputInformation(0).Get(reader.GetExecutive().TIME_STEPS())
        self.assertEqual(len(steps), FRAMES)
        originals = np.stack([self.original(t) for t in range(FRAMES)])
        played = []
        for t in range(FRAMES):
            reader.UpdateTimeStep(steps[t])
            mesh = first_polydata(reader.GetOutput())
            played.append(np.array(dsa.WrapDataObject(mesh).Points))
        played = np.stack(played)
        self.assertEqual(played.shape, originals.shape)
        centred = originals - originals.mean(axis=1, keepdims=True)
        kg = 100 * np.linalg.norm(originals - played) / np.linalg.norm(centred)
        self.assertLessEqual(kg, 0.2 * 1.01)  # float32 storage
        self.assertGreater(k, 0)

    def test_vtk_plays_each_frame_once_whatever_the_count(self):
        # Key times sit at or below t/24 s, so a player stepping 1/24 s from 0 ends on the
        # last key (float32 rounding above it once gave an extra step for 2, 3, 5, 9... frames).
        for n in (2, 3, 5, 9, 12, FRAMES):
            source = dynamicpoints.vtkPointSequenceSource()
            for f in self.files[:n]:
                source.AddFileName(f)
            glb = self.path(f"tube{n}.glb")
            self.write(glb, source, NumberOfComponents=2)
            reader = vtkGLTFReader()
            reader.SetFileName(glb)
            reader.UpdateInformation()
            reader.EnableAnimation(0)
            reader.SetFrameRate(24)
            reader.UpdateInformation()
            steps = reader.GetOutputInformation(0).Get(reader.GetExecutive().TIME_STEPS())
            self.assertEqual(len(steps), n)

    def test_the_gltf_export_passes_the_khronos_validator(self):
        glb = self.path("tube.glb")
        self.write(glb, KGTarget=0.2)
        report = validate_gltf(glb)
        self.assertEqual((report["errors"], report["warnings"]), (0, 0), report["messages"])
        self.assertEqual(report["info"]["animationCount"], 1)
        self.assertEqual(report["info"]["drawCallCount"], 1)
        # A deliberately broken copy is caught, so the check above can fail.
        with open(glb, "rb") as f:
            data = bytearray(f.read())
        data[8:12] = (len(data) + 4).to_bytes(4, "little")  # header length disagrees with size
        with open(self.path("broken.glb"), "wb") as out:
            out.write(data)
        self.assertGreater(validate_gltf(self.path("broken.glb"))["errors"], 0)

    def test_the_meshopt_variant_is_smaller_and_decodes_to_the_same_data(self):
        writer = self.write(self.path("plain.glb"))
        writer.MeshoptCompressionOn()
        writer.SetFileName(self.path("meshopt.glb"))
        self.assertEqual(writer.Write(), 1)
        self.assertLess(os.path.getsize(self.path("meshopt.glb")),
                        0.7 * os.path.getsize(self.path("plain.glb")))
        report = validate_gltf(self.path("meshopt.glb"))
        self.assertEqual((report["errors"], report["warnings"]), (0, 0), report["messages"])
        self.assertEqual(report["info"]["extensionsRequired"], ["EXT_meshopt_compression"])
        # meshoptimizer's own decoder gives back the plain file's buffer: every view byte for
        # byte, the triangles as the same triangles (the index codec may rotate each one).
        decoded = decode_meshopt(self.path("meshopt.glb"), self.path("decoded.bin"))
        with open(self.path("plain.glb"), "rb") as f:
            plain = f.read()
        json_length = int.from_bytes(plain[12:16], "little")
        layout = json.loads(plain[20:20 + json_length])
        binary = plain[28 + json_length:]
        with open(self.path("decoded.bin"), "rb") as f:
            unpacked = f.read()
        self.assertEqual(decoded["views"], len(layout["bufferViews"]))
        indices = layout["accessors"][layout["meshes"][0]["primitives"][0]["indices"]]["bufferView"]
        for v, view in enumerate(layout["bufferViews"]):
            start, end = view.get("byteOffset", 0), view.get("byteOffset", 0) + view["byteLength"]
            if v != indices:
                self.assertEqual(unpacked[start:end], binary[start:end], f"view {v}")
                continue
            canonical = [np.array([np.roll(t, -int(np.argmin(t))) for t in
                                   np.frombuffer(b[start:end], "<u4").reshape(-1, 3)])
                         for b in (binary, unpacked)]
            np.testing.assert_array_equal(canonical[0], canonical[1])

    def test_blender_imports_every_frame_and_morph_target(self):
        glb = self.path("tube.glb")
        self.write(glb, KGTarget=0.2)
        f = self.compressor(KGTarget=0.2, Layout=1)  # a .glb holds the shape layout
        f.Update()
        k = int(dsa.WrapDataObject(f.GetOutput()).FieldData["Components"][0])
        report = blender_report(glb, (0, 7, FRAMES - 1))
        self.assertEqual(report["mesh_objects"], 1)
        self.assertEqual(report["morph_targets"], k)
        self.assertEqual(report["frames"], FRAMES)
        self.assertEqual(report["fps"], 24)
        for t in (0, 7, FRAMES - 1):
            f.UpdateTimeStep(t)
            rebuilt = np.array(dsa.WrapDataObject(f.GetOutput()).Points)
            played = np.array(report["positions"][str(t)])
            self.assertEqual(played.shape, rebuilt.shape)
            # Same vertices in the same order, at Blender's float32 precision.
            np.testing.assert_allclose(played, rebuilt, atol=1e-5)

    def coloured(self, components=3, uncoloured_frame=None, flicker=False):
        """The tube's frames written as .vtp with point array "Colors" (bytes, COMPONENTS per
        point; every frame's different, wrapping past 255; with FLICKER each point's own colour
        with +-2 levels of noise a frame, as tracked colour has), except UNCOLOURED_FRAME;
        returns the source reading them and each frame's r g b."""
        from vtkmodules.util.numpy_support import numpy_to_vtk
        from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter
        source, colours = dynamicpoints.vtkPointSequenceSource(), []
        for t, name in enumerate(self.files):
            self.source.UpdateTimeStep(t)
            frame = self.source.GetOutput().NewInstance()
            frame.DeepCopy(self.source.GetOutput())
            n = frame.GetNumberOfPoints()
            values = (np.arange(n)[:, None] * [7, 13, 29, 31][:components] + 11 * t) % 256
            if flicker:
                noise = np.random.default_rng(t).integers(-2, 3, size=(n, components))
                values = np.clip(20 + np.arange(n)[:, None] * [7, 13, 29, 31][:components] % 216
                                 + noise, 0, 255)
            colours.append(values[:, :3].astype(np.uint8))
            if t != uncoloured_frame:
                array = numpy_to_vtk(values.astype(np.uint8), deep=1)
                array.SetName("Colors")
                frame.GetPointData().AddArray(array)
            writer = vtkXMLPolyDataWriter()
            writer.SetInputData(frame)
            writer.SetFileName(self.path(f"coloured_{t:02d}.vtp"))
            writer.Write()
            source.AddFileName(self.path(f"coloured_{t:02d}.vtp"))
        return source, np.stack(colours)

    def test_the_colours_go_through_the_dpz_exactly(self):
        for components in (3, 4):  # the alpha of r g b a is dropped
            source, colours = self.coloured(components)
            path = self.path(f"coloured{components}.dpz")
            self.write(path, source)
            f = dynamicpoints.vtkPCACompressFilter()
            f.SetInputConnection(source.GetOutputPort())
            reader = dynamicpoints.vtkCompressedSequenceReader()
            reader.SetFileName(path)
            reader.UpdateInformation()
            steps = reader.GetOutputInformation(0).Get(reader.GetExecutive().TIME_STEPS())
            for t in range(FRAMES):
                reader.UpdateTimeStep(steps[t])
                out = reader.GetOutput()
                self.assertEqual(out.GetPointData().GetScalars().GetName(), "Colors")
                np.testing.assert_array_equal(dsa.WrapDataObject(out).PointData["Colors"],
                                              colours[t])
                f.UpdateTimeStep(t)  # the decompressed mesh carries them too
                np.testing.assert_array_equal(dsa.WrapDataObject(f.GetOutput()).PointData["Colors"],
                                              colours[t])
            # The file grew by what both say the colour takes.
            colour_bytes = dsa.WrapDataObject(reader.GetOutput()).FieldData["ColourBytes"][0]
            self.assertEqual(dsa.WrapDataObject(f.GetOutput()).FieldData["ColourBytes"][0],
                             colour_bytes)
            self.write(self.path("plain.dpz"))
            self.assertEqual(os.path.getsize(path),
                             os.path.getsize(self.path("plain.dpz")) + colour_bytes)

    def test_a_colour_tolerance_holds_each_colour_and_shrinks_the_stream(self):
        source, colours = self.coloured(flicker=True)
        stored, sizes = {}, {}
        for tolerance in (0, 4):  # 0: lossless; 4: the default
            path = self.path(f"flicker{tolerance}.dpz")
            settings = {"ColourTolerance": tolerance} if tolerance == 0 else {}
            self.assertEqual(self.write(path, source, **settings).GetColourTolerance(), tolerance)
            reader = dynamicpoints.vtkCompressedSequenceReader()
            reader.SetFileName(path)
            reader.UpdateInformation()
            steps = reader.GetOutputInformation(0).Get(reader.GetExecutive().TIME_STEPS())
            stored[tolerance] = []
            for t in range(FRAMES):
                reader.UpdateTimeStep(steps[t])
                stored[tolerance].append(np.array(dsa.WrapDataObject(reader.GetOutput())
                                                  .PointData["Colors"]))
            stored[tolerance] = np.stack(stored[tolerance])
            sizes[tolerance] = dsa.WrapDataObject(reader.GetOutput()).FieldData["ColourBytes"][0]
        np.testing.assert_array_equal(stored[0], colours)
        error = np.abs(stored[4].astype(int) - colours.astype(int))
        self.assertLessEqual(error.max(), 4)
        np.testing.assert_array_equal(stored[4], stored[4][:1].repeat(FRAMES, axis=0))  # no flicker
        self.assertLess(3 * sizes[4], sizes[0])
        # The filter says the tolerance and shows the stored colours.
        f = dynamicpoints.vtkPCACompressFilter()
        f.SetInputConnection(source.GetOutputPort())
        f.UpdateTimeStep(5)
        out = dsa.WrapDataObject(f.GetOutput())
        self.assertEqual(out.FieldData["ColourTolerance"][0], 4)
        np.testing.assert_array_equal(out.PointData["Colors"], stored[4][5])

    def test_colour_in_some_frames_only_is_left_out(self):
        source, _ = self.coloured(uncoloured_frame=FRAMES // 2)
        self.write(self.path("partly.dpz"), source)
        reader = dynamicpoints.vtkCompressedSequenceReader()
        reader.SetFileName(self.path("partly.dpz"))
        reader.Update()
        self.assertIsNone(reader.GetOutput().GetPointData().GetArray("Colors"))
        self.assertIsNone(reader.GetOutput().GetFieldData().GetArray("ColourBytes"))
        with open(self.path("partly.dpz"), "rb") as f:
            self.assertEqual(f.read(12)[8:], (5).to_bytes(4, "little"))  # format version 5
        # No colour stream in it: the file is as large as the colourless sequence's.
        self.write(self.path("plain.dpz"))
        self.assertEqual(os.path.getsize(self.path("partly.dpz")),
                         os.path.getsize(self.path("plain.dpz")))

    def test_the_gltf_export_plays_each_frames_colours(self):
        source, colours = self.coloured()
        glb = self.path("coloured.glb")
        self.write(glb, source)
        report = validate_gltf(glb)
        self.assertEqual((report["errors"], report["warnings"]), (0, 0), report["messages"])
        np.testing.assert_array_equal(glb_colours(glb), colours)
        # VTK's reader still plays the shapes (it takes COLOR_0, not the colour targets).
        reader = vtkGLTFReader()
        reader.SetFileName(glb)
        reader.UpdateInformation()
        reader.EnableAnimation(0)
        reader.SetApplyDeformationsToGeometry(True)
        reader.SetFrameRate(24)
        reader.UpdateInformation()
        steps = reader.GetOutputInformation(0).Get(reader.GetExecutive().TIME_STEPS())
        self.assertEqual(len(steps), FRAMES)
        reader.UpdateTimeStep(steps[9])
        played = dsa.WrapDataObject(first_polydata(reader.GetOutput()))
        self.assertLess(np.abs(np.array(played.Points) - self.original(9)).max(), 0.01)
        np.testing.assert_array_equal(np.rint(255 * np.array(played.PointData["COLOR_0"])),
                                      colours[0])

    def add_another_connectivity(self):
        """Appends a frame of another mesh (the sheet) to the tube's sequence."""
        run_tool("dynamicpoints-sample", "--mesh", "sheet", "--frames", 1, "--points", 100,
                 "--truth", self.path("sheet"))
        sheet = self.path("sheet", "truth")
        self.source.AddFileName(os.path.join(sheet, sorted(os.listdir(sheet))[0]))

    def test_a_change_of_connectivity_is_refused_by_frame(self):
        self.add_another_connectivity()
        f = self.compressor()
        rec = MessageRecorder(f)
        f.Update()
        self.assertIn(f"frame {FRAMES} has", rec.error_text)
        self.assertIn("one connectivity", rec.error_text)
        self.assertIn(f"frame {FRAMES} has", f.GetFailureMessage())
        self.assertEqual(f.GetOutput().GetNumberOfPoints(), 0)

    def test_a_mesh_moving_smoothly_compresses_without_a_warning(self):
        f = self.compressor(KGTarget=0.2)
        rec = MessageRecorder(f)
        f.Update()
        fd = dsa.WrapDataObject(f.GetOutput()).FieldData
        per_frame = 3 if fd["Layout"][0] == 0 else 1  # trajectories: x y z a frame
        self.assertAlmostEqual(fd["ComponentsPerFrame"][0],
                               fd["Components"][0] / (per_frame * FRAMES))
        self.assertLessEqual(fd["ComponentsPerFrame"][0], 0.5)
        self.assertEqual(rec.warnings, [])

    def test_raw_points_are_named_and_weak_compression_is_said(self):
        # The sampled points themselves (the same count every frame, new points each frame):
        # what a user gets by compressing the reader's output instead of the tracked mesh.
        raw = dynamicpoints.vtkPointSequenceSource()
        frames = sorted(f for f in os.listdir(self.path("seq")) if f.endswith(".ply"))
        self.assertEqual(len(frames), FRAMES)
        for name in frames:
            raw.AddFileName(self.path("seq", name))
        f = dynamicpoints.vtkPCACompressFilter()
        f.SetInputConnection(raw.GetOutputPort())
        rec = MessageRecorder(f)
        f.Update()
        self.assertEqual(rec.errors, [])
        text = " ".join(rec.warnings)
        self.assertIn("frame 0 has no polygons", text)
        self.assertIn("Deformable Track", text)
        fd = dsa.WrapDataObject(f.GetOutput()).FieldData
        self.assertGreater(fd["ComponentsPerFrame"][0], 0.5)
        possible = 3 * FRAMES if fd["Layout"][0] == 0 else FRAMES
        self.assertIn(f"kept {int(fd['Components'][0])} of {possible} possible components", text)
        self.assertIn("the compression is weak", text)

    def test_against_the_data_the_distance_to_the_points_grows_at_most_as_asked(self):
        # Deformable Track's output carries each frame's points; DISTANCE_TO_DATA's target is
        # the share by which the decompressed mesh's distance to them may grow.
        run_tool("dynamicpoints-sample", "--mesh", "tube", "--frames", FRAMES, "--points", 4000,
                 "--noise", 0.002, self.path("noisy"))
        points = dynamicpoints.vtkPointSequenceSource()
        points.SetFileName(self.path("noisy", "points.series"))
        template = dynamicpoints.vtkPointSequenceSource()
        template.SetFileName(self.files[0])
        tracker = dynamicpoints.vtkDeformableTrackFilter()
        tracker.SetInputConnection(points.GetOutputPort())
        tracker.SetTemplateConnection(template.GetOutputPort())
        figures = {}
        for target in (5, 20):
            f = dynamicpoints.vtkPCACompressFilter()
            f.SetInputConnection(tracker.GetOutputPort())
            f.SetErrorMeasure(f.DISTANCE_TO_DATA)
            f.SetFitGrowth(target)
            rec = MessageRecorder(f)
            f.Update()
            self.assertEqual(rec.errors + rec.warnings, [])
            fd = dsa.WrapDataObject(f.GetOutput()).FieldData
            growth = fd["DistanceToDataGrowth"][0]
            self.assertLessEqual(growth, target)
            self.assertGreater(growth, 0.2 * target)  # what is allowed is used
            self.assertAlmostEqual(growth, 100 * (fd["DistanceToDataDecompressed"][0] /
                                                  fd["DistanceToDataInput"][0] - 1), places=6)
            figures[target] = fd["BitsPerVertexFrame"][0]
        self.assertLess(figures[20], figures[5])  # a looser target costs fewer bits
        # The writer takes the same target.
        writer = self.write(self.path("data.dpz"), source=tracker, ErrorMeasure=2, FitGrowth=10)
        self.assertEqual(writer.GetErrorMeasure(), 2)

    def test_against_the_data_without_the_tracked_points_it_says_what_is_missing(self):
        f = self.compressor(ErrorMeasure=2, FitGrowth=10)  # the true meshes carry no points
        rec = MessageRecorder(f)
        f.Update()
        self.assertIn("frame 0 has no DataSamples", rec.error_text)
        self.assertIn("Deformable Track", rec.error_text)
        self.assertEqual(f.GetOutput().GetNumberOfPoints(), 0)

    def test_each_option_by_name_clamped_and_absurd_values_named(self):
        # The codec filter's and the writer's options are dp::compressionOptions(): reached by
        # name or property, clamped to their ranges, a NaN or an unknown name an error by name.
        for obj in (dynamicpoints.vtkPCACompressFilter(), dynamicpoints.vtkCompressedSequenceWriter()):
            with self.subTest(cls=obj.GetClassName()):
                rec = MessageRecorder(obj)
                obj.SetCompressionOption("compression.layout", 1)
                self.assertEqual(obj.GetLayout(), 1)
                obj.SetKGTarget(500)  # above the range's 50 %: clamped
                self.assertEqual(obj.GetCompressionOption("compression.kgTarget"), 50)
                obj.SetColourTolerance(-3)
                self.assertEqual(obj.GetColourTolerance(), 0)
                obj.SetFitGrowth(float("nan"))
                self.assertIn("compression option compression.fitGrowth: NaN is no value",
                              rec.error_text)
                self.assertEqual(obj.GetFitGrowth(), 10)  # the default kept
                obj.SetCompressionOption("compression.psnr", 1)
                self.assertIn("no compression option 'compression.psnr'", rec.error_text)
        writer = dynamicpoints.vtkCompressedSequenceWriter()
        rec = MessageRecorder(writer)
        writer.SetCompressionOption("Quantize", 0)
        self.assertIn("the writers always quantise", rec.error_text)


if __name__ == "__main__":
    unittest.main()
