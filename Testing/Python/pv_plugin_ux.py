"""pvpython: the plugin's proxies carry ParaView-style labels and Python names, a fresh
filter's trace records nothing the user did not set (beyond what ParaView traces for every
filter: its inputs and file names), Deformable Track's panel is grouped with the rarely needed
properties advanced and those of other modes shown only in their mode, numeric fields whose
range is too wide for a slider get none, and long work reports progress in the user's words."""
import os
import re
import subprocess
import tempfile

from paraview import servermanager, smtrace
from paraview.simple import LoadPlugin, OpenDataFile, Sphere

# Names as ParaView's own readers and writers read (PLYReader, glTFReader): simple.py makes
# them from the labels, so a label in Title Case gives a readable name.
FILTERS = ("PointSequenceReader", "PointSequenceFolder", "PointDistanceField",
           "DeformableTrack", "PCACompress", "CompressedSequenceReader")
WRITERS = ("CompressedSequenceWriter", "glTFMorphAnimationWriter")


def check_labels(proxy):
    """Every property label reads as words: no acronym split by ParaView's automatic labelling
    of CamelCase names ("G LBFile Name" from a property named GLBFileName)."""
    for name in proxy.ListProperties():
        label = proxy.GetProperty(name).SMProperty.GetXMLLabel()
        assert not re.search(r"(^|\s)[A-Z] [A-Z]", label), (proxy.GetXMLLabel(), name, label)
    return {name: proxy.GetProperty(name).SMProperty.GetXMLLabel()
            for name in proxy.ListProperties()}


def check_names_and_labels(ns):
    for name in FILTERS:
        assert name in ns, (name, sorted(k for k in ns if not k.startswith("_")))
    for name in WRITERS:
        assert name in dir(servermanager.writers), (name, dir(servermanager.writers))
    sphere = Sphere()
    compress = ns["PCACompress"](Input=ns["DeformableTrack"](Input=sphere))
    check_labels(compress)
    check_labels(ns["PointDistanceField"](Input=sphere))
    for name in WRITERS:
        writer = getattr(servermanager.writers, name)()
        assert writer.GetXMLLabel() in ("Compressed Sequence Writer",
                                        "glTF Morph Animation Writer"), writer.GetXMLLabel()
        labels = check_labels(writer)
        if name == "glTFMorphAnimationWriter":
            assert labels["MeshoptCompression"] == "Meshopt Compression", labels


def check_creation_trace(ns):
    smtrace.start_trace()
    sphere = Sphere()
    ns["PointDistanceField"](Input=sphere)
    compress = ns["PCACompress"](Input=ns["DeformableTrack"](Input=sphere))
    del compress
    trace = smtrace.stop_trace()
    created = trace.split("# addendum")[0]
    # Nothing assigned after creation: every property still holds its default.
    assigned = re.findall(r"^\w+\.(\w+) = .*$", created, re.MULTILINE)
    assert not assigned, (assigned, created)
    # In the constructors only what ParaView traces for every filter (inputs, file names).
    arguments = set(re.findall(r"(\w+)=", created))
    assert arguments <= {"registrationName", "Input", "Template", "FileName"}, \
        (arguments, created)


def check_panel(ns):
    track = ns["DeformableTrack"](Input=Sphere())
    groups = {}
    for i in range(track.SMProxy.GetNumberOfPropertyGroups()):
        group = track.SMProxy.GetPropertyGroup(i)
        groups[group.GetXMLLabel()] = [group.GetProperty(k).GetXMLName()
                                       for k in range(group.GetNumberOfProperties())]
    assert list(groups) == ["Template", "Tracking", "Failed frames", "The paper's energy",
                            "Solver", "Distance field"], groups
    grouped = [name for members in groups.values() for name in members]
    shown = [name for name in track.ListProperties()
             if track.GetProperty(name).SMProperty.GetPanelVisibility() == "default"]
    # Every property the panel shows sits in a group (the inputs excepted), and the default
    # view is short: the rest is behind the panel's advanced (gear) button.
    assert set(shown) - {"Input", "Template"} <= set(grouped), (shown, groups)
    assert len(shown) <= 12, shown
    assert "TemplateVertices" in shown and "Recovery" in shown, shown
    # The optional template is chosen in the panel (a list of the pipeline's sources and
    # "(none)"), not only through Edit > Change Input.
    assert groups["Template"] == ["Template", "TemplateVertices", "TemplateSource"], groups
    assert track.GetProperty("Template").SMProperty.GetPanelWidget() == "input_selector"
    for name in ("ProvisionalDetermination", "Tolerance", "VoxelSize", "FailureMargin"):
        assert name not in shown, name

    def shown_when(name):
        hints = track.GetProperty(name).SMProperty.GetHints()
        decorator = hints.FindNestedElementByName("PropertyWidgetDecorator") if hints else None
        assert decorator is not None, name
        assert decorator.GetAttribute("mode") == "visibility", name
        return decorator.GetAttribute("property"), decorator.GetAttribute("value")
    solvers = track.GetProperty("Solver").SMProperty.GetDomain("enum")
    steepest = [solvers.GetEntryValue(i) for i in range(solvers.GetNumberOfEntries())
                if solvers.GetEntryText(i).startswith("Steepest")]
    assert shown_when("ProvisionalDetermination") == ("Solver", str(steepest[0]))
    assert shown_when("RigidAlignment") == ("CoarseLevel", "0")
    for name in ("GraphNodes", "GraphRigidity", "Plasticity", "FineIterations"):
        assert shown_when(name) == ("CoarseLevel", "1"), name
    assert shown_when("FailureMargin") == ("Recovery", "1")

    # A slider over 20 .. 10 000 000 cannot be used: such fields are plain numbers.
    vertices = track.GetProperty("TemplateVertices").SMProperty.GetDomain("range")
    assert vertices.GetMinimumExists(0) and not vertices.GetMaximumExists(0)
    # Each error measure has its own target, a plain number field shown only while its measure
    # is chosen; the codec filter's and the writers' alike.
    compress = servermanager.filters.PCACompress(Input=track)
    proxies = [compress] + [getattr(servermanager.writers, name)() for name in WRITERS]
    for proxy in proxies:
        for measure, name in enumerate(("KGTarget", "MaxVertexTarget", "FitGrowth")):
            prop = proxy.GetProperty(name).SMProperty
            target = prop.GetDomain("range")
            assert target.GetMinimumExists(0) and not target.GetMaximumExists(0), name
            decorator = prop.GetHints().FindNestedElementByName("PropertyWidgetDecorator")
            assert decorator.GetAttribute("property") == "ErrorMeasure", name
            assert decorator.GetAttribute("value") == str(measure), name
        assert proxy.GetProperty("ErrorTarget") is None  # one target for all: gone


def observe_progress(proxy, values=False):
    """The progress texts (with values: (text, progress) pairs) the VTK algorithm behind `proxy`
    reports, as ParaView shows them."""
    texts = []
    algorithm = proxy.GetClientSideObject()

    def record(caller, _event):
        text = caller.GetProgressText()
        texts.append((text, caller.GetProgress()) if values else text)
    algorithm.AddObserver("ProgressEvent", record)
    return texts


def check_progress(ns, bin_dir):
    with tempfile.TemporaryDirectory(prefix="dp-pv-progress-") as tmp:
        subprocess.run([os.path.join(bin_dir, "dynamicpoints-sample"), "--frames", "4",
                        "--points", "3000", tmp], check=True, capture_output=True)
        reader = OpenDataFile(os.path.join(tmp, "points.series"))
        track = ns["DeformableTrack"](Input=reader, TemplateVertices=200)
        read_texts = observe_progress(reader)
        track_texts = observe_progress(track)
        track.UpdatePipeline(3.0)
        assert "Point Sequence Reader: frame 4 of 4" in read_texts, read_texts
        # (The executive's own start and end events repeat the text around them.)
        said = list(dict.fromkeys(t for t in track_texts if t))
        assert said == [f"Deformable Track: frame {k} of 4" for k in range(1, 5)], track_texts

        # Save Data on a fresh track: the writer walks the take one frame per request, and the
        # tracker's progress rises over the whole take instead of reading 100 % every frame.
        fresh = ns["DeformableTrack"](Input=reader, TemplateVertices=200)
        walked = observe_progress(fresh, values=True)
        saver = servermanager.writers.CompressedSequenceWriter(
            Input=fresh, FileName=os.path.join(tmp, "walked.dpz"))
        saver.UpdatePipeline()
        said = list(dict.fromkeys(text for text, _ in walked if text))
        assert said == [f"Deformable Track: frame {k} of 4" for k in range(1, 5)], walked
        # Frame k's events stay within its quarter of the bar; 100 % only at the end.
        for text, value in walked:
            if text:
                k = int(text.split()[3])
                assert (k - 1) / 4 - 0.25 <= value <= k / 4, (text, value, walked)
        assert walked[-1][1] == 1.0, walked

        path = os.path.join(tmp, "tracked.dpz")
        writer = servermanager.writers.CompressedSequenceWriter(Input=track, FileName=path)
        write_texts = observe_progress(writer)
        writer.UpdatePipeline()
        assert os.path.getsize(path) > 0
        for k in range(1, 5):
            assert f"Saving tracked.dpz: PCA Compress: frame {k} of 4" in write_texts, write_texts
        assert "Saving tracked.dpz: PCA Compress: compressing" in write_texts, write_texts


def main():
    ns = {"__name__": "dp_plugin_proxies"}  # LoadPlugin fills a non-empty namespace only
    LoadPlugin(os.environ["DP_PLUGIN"], remote=False, ns=ns)
    check_names_and_labels(ns)
    check_creation_trace(ns)
    check_panel(ns)
    check_progress(ns, os.environ["DP_BIN_DIR"])
    print("names, labels, creation trace, panel and progress texts as expected")


main()
