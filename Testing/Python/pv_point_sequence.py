"""pvpython: the plugin loads, ParaView's reader factory picks the Point Sequence Reader for a
.series file, and the reader answers every time step with that frame's points."""
import os
import re
import subprocess
import sys
import tempfile

from paraview.simple import (LoadPlugin, OpenDataFile, GetAnimationScene, GetTimeKeeper,
                             servermanager)


def ply_vertex_count(path):
    with open(path, "rb") as f:
        header = f.read(512).split(b"end_header")[0].decode("ascii")
    return int(re.search(r"element vertex (\d+)", header).group(1))


def main():
    plugin = os.environ["DP_PLUGIN"]
    sampler = os.path.join(os.environ["DP_BIN_DIR"], "dynamicpoints-sample")
    ns = {"__name__": "dp_plugin_proxies"}  # LoadPlugin fills a non-empty namespace only
    LoadPlugin(plugin, remote=False, ns=ns)
    # simple.py names proxies by their labels.
    for name in ("PointSequenceReader", "PointSequenceFolder", "PointDistanceField",
                 "DeformableTrack"):
        assert name in ns, sorted(ns)

    with tempfile.TemporaryDirectory(prefix="dp-pv-") as tmp:
        subprocess.run([sampler, "--mesh", "sheet", "--frames", "5", "--points", "800",
                        "--holes", "1", "--hole-radius", "0.25", "--moving-holes",
                        "--interval", "0.5", "--truth", tmp], check=True, capture_output=True)
        frames = sorted(f for f in os.listdir(tmp) if f.endswith(".ply"))
        expected = [ply_vertex_count(os.path.join(tmp, f)) for f in frames]
        assert len(set(expected)) > 1, expected

        reader = OpenDataFile(os.path.join(tmp, "points.series"))
        assert reader is not None and reader.GetXMLName() == "DynamicPointsSequenceReader", reader
        assert list(reader.TimestepValues) == [0.0, 0.5, 1.0, 1.5, 2.0], reader.TimestepValues
        doc = reader.GetProperty("FrameInterval").GetDocumentation().GetDescription()
        assert "positive" in doc, doc

        scene = GetAnimationScene()
        scene.UpdateAnimationUsingDataTimeSteps()
        assert len(GetTimeKeeper().TimestepValues) == 5
        for t, count in zip(reader.TimestepValues, expected):
            reader.UpdatePipeline(t)
            data = servermanager.Fetch(reader)
            assert data.GetNumberOfPoints() == count, (t, data.GetNumberOfPoints(), count)
            assert data.GetPointData().GetNormals() is not None

        # The first of the readers ParaView offers for a frame file (its Open Data With dialog
        # preselects it, and OpenDataFile takes it), ahead of ParaView's PLY, PTS and XYZ ones.
        ply = OpenDataFile([os.path.join(tmp, f) for f in frames])
        assert ply.GetXMLName() == "DynamicPointsSequenceReader", ply.GetXMLName()
        factory = servermanager.vtkSMProxyManager.GetProxyManager().GetReaderFactory()
        offered = factory.GetReaders(os.path.join(tmp, frames[0]),
                                     servermanager.ActiveConnection.Session)
        assert offered.GetString(1) == "DynamicPointsSequenceReader", offered.GetString(1)
        assert "PLYReader" in [offered.GetString(i)
                               for i in range(1, offered.GetNumberOfStrings(), 3)]
        # The file dialog passes a numbered group as a list; the folder proxy takes a pattern.
        listed = ns["PointSequenceReader"](FileNames=[os.path.join(tmp, f) for f in frames])
        listed.UpdatePipeline(4.0)
        assert servermanager.Fetch(listed).GetNumberOfPoints() == expected[4]
        folder = ns["PointSequenceFolder"](DirectoryName=tmp, FilePattern="frame_000[0-2].ply")
        assert list(folder.TimestepValues) == [0.0, 1.0, 2.0], folder.TimestepValues
        folder.UpdatePipeline(2.0)
        assert servermanager.Fetch(folder).GetNumberOfPoints() == expected[2]
        # The distance field filter on the reader's current time step.
        field = ns["PointDistanceField"](Input=reader, Dimensions=[24, 24, 24])
        field.UpdatePipeline(1.0)
        image = servermanager.Fetch(field)
        assert image.GetDimensions() == (24, 24, 24), image.GetDimensions()
        distance = image.GetPointData().GetArray("Distance")
        assert distance is not None and distance.GetRange()[1] > 0
        assert "exact" in field.GetProperty("BandWidth").GetDocumentation().GetDescription()
        assert image.GetFieldData().GetArray("BandVoxels").GetValue(0) > 0
        # The tracker: the template is the first truth mesh; track to the third time step. On
        # the sheet without its hole: where a hole as wide as a fifth of an open sheet takes its
        # edge away, the tracked edge strays and tears, and the frame is rightly flagged.
        whole = os.path.join(tmp, "whole")
        subprocess.run([sampler, "--mesh", "sheet", "--frames", "5", "--points", "800",
                        "--interval", "0.5", "--truth", whole], check=True, capture_output=True)
        sheet = OpenDataFile(os.path.join(whole, "points.series"))
        template = OpenDataFile(os.path.join(whole, "truth", "frame_0000.ply"))
        track = ns["DeformableTrack"](Input=sheet, Template=template)
        assert list(track.TimestepValues) == list(sheet.TimestepValues)
        track.UpdatePipeline(1.0)
        mesh = servermanager.Fetch(track)
        assert mesh.GetNumberOfPolys() > 0 and mesh.GetPointData().GetArray("Residual")
        assert mesh.GetFieldData().GetArray("FrameIndex").GetValue(0) == 2
        # The frame's quality is field data, and the robust-tracking settings are properties
        # whose defaults are the engine's and whose documentation says what they do.
        for name in ("Unexplained", "Unsupported", "LargestStretch", "Retries", "Failed"):
            assert mesh.GetFieldData().GetArray(name) is not None, name
        assert 0 <= mesh.GetFieldData().GetArray("LargestStretch").GetValue(0) < 2
        assert mesh.GetFieldData().GetArray("Failed").GetValue(0) == 0
        assert track.CoverageWeight == 50 and track.CoarseLevel == 1 and track.Recovery == 1
        assert abs(track.Plasticity - 0.3) < 1e-12 and track.GraphNodes == 0
        assert "limb" in track.GetProperty("CoverageWeight").GetDocumentation().GetDescription()
        # Switched off, the paper's energy alone still tracks (a different result).
        track.CoverageWeight = 0
        track.CoarseLevel = 0
        track.UpdatePipeline(1.0)
        paper = servermanager.Fetch(track)
        assert paper.GetNumberOfPoints() == mesh.GetNumberOfPoints()
        assert paper.GetFieldData().GetArray("CoarseIterations").GetValue(0) == 0
        assert mesh.GetFieldData().GetArray("CoarseIterations").GetValue(0) > 0
    print("pvpython point sequence test passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
