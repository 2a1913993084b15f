"""The ParaView plugin's XML says the same defaults as the classes it drives.

Each filter takes its defaults from the engine's option structs (its constructor); the XML's
default_values are a second statement of them that ParaView shows and traces. A property whose
XML default differs from a fresh object's value would make the GUI and a Python script track
differently with "the defaults"."""
import json
import os
import subprocess
import unittest
import xml.etree.ElementTree as ET

import dynamicpoints

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
PLUGIN_DIR = os.path.join(ROOT, "ParaViewPlugin")
TRACK_XML = os.path.join(PLUGIN_DIR, "DeformableTrackFilter.xml")
COMPRESS_XML = os.path.join(PLUGIN_DIR, "PCACompressFilter.xml")
OPTIONS_DOC = os.path.join(ROOT, "Documentation", "TrackerOptions.md")
COMPRESSION_DOC = os.path.join(ROOT, "Documentation", "Compression.md")
# A range whose maximum is this or more has no max in the XML: ParaView would draw a slider over
# it, and no one can pick 1 000 vertices on a slider to 10 million (pv_plugin_ux.py checks this).
SLIDER_LIMIT = 1000
# A real option whose range's top is this many times its default is a plain number field too: a
# slider over 0.0001 .. 50 cannot pick a KG target of 0.2.
SLIDER_SPAN = 100
# The track filter's properties that are not tracker options.
NOT_TRACKER_OPTIONS = {"Input", "Template", "TemplateVertices", "TemplateSource", "TimestepValues"}
# The codec filter's and the writers' properties that are not compression options.
NOT_COMPRESSION_OPTIONS = {"Input", "FileName", "TimestepValues", "MeshoptCompression"}


def describe_options(form):
    exe = os.path.join(os.environ["DP_BIN_DIR"], "dynamicpoints")
    return subprocess.run([exe, "--describe-options", form], check=True, capture_output=True,
                          text=True).stdout


def describe_options_limits():
    exe = os.path.join(os.environ["DP_BIN_DIR"], "dynamicpoints")
    return subprocess.run([exe, "--describe-limits"], check=True, capture_output=True,
                          text=True).stdout


def close(a, b):
    return abs(float(a) - float(b)) <= 1e-12 * max(1.0, abs(float(b)))


def plugin_properties():
    """(class name, property name, setter, default values) of every property of the plugin's
    proxies that has a default and a setter."""
    found = []
    for name in sorted(os.listdir(PLUGIN_DIR)):
        if not name.endswith(".xml"):
            continue
        root = ET.parse(os.path.join(PLUGIN_DIR, name)).getroot()
        for proxy in root.iter():
            cls = proxy.get("class")
            if not cls:
                continue
            for prop in proxy:
                command, default = prop.get("command"), prop.get("default_values")
                if command and default is not None and not prop.get("information_only"):
                    found.append((cls, prop.get("name"), command, default.split()))
    return found


def same(xml_values, value):
    if value is None or value == "":  # an unset string property: the XML's default is empty
        return xml_values == []
    values = value if isinstance(value, (tuple, list)) else [value]
    if len(values) != len(xml_values):
        return False
    for text, actual in zip(xml_values, values):
        if isinstance(actual, str):
            if actual != text:
                return False
        elif abs(float(text) - float(actual)) > 1e-12 * max(1.0, abs(float(actual))):
            return False
    return True


class PluginDefaults(unittest.TestCase):
    def test_every_xml_default_is_the_class_default(self):
        properties = plugin_properties()
        classes = {cls for cls, *_ in properties}
        # Every proxy of the plugin, not an empty walk.
        self.assertTrue({"vtkDeformableTrackFilter", "vtkPCACompressFilter", "vtkDistanceFieldFilter",
                         "vtkPointSequenceSource", "vtkCompressedSequenceWriter"} <= classes, classes)
        self.assertGreaterEqual(len(properties), 50)
        for cls, name, command, xml_values in properties:
            with self.subTest(cls=cls, property=name):
                obj = getattr(dynamicpoints, cls)()
                self.assertTrue(command.startswith("Set"), command)
                getter = getattr(obj, "Get" + command[3:])
                self.assertTrue(same(xml_values, getter()),
                                f"{cls}.{name}: XML default {xml_values}, class default {getter()}")

    def check_properties(self, rows, xml, check_panel=True):
        """Each option's property in the XML says the same default, range, kind and (where the
        proxy has a panel of its own) visibility as the table."""
        for name, row in rows.items():
            with self.subTest(property=name):
                prop = xml[name]
                self.assertEqual(prop.get("command"), "Set" + name)
                if check_panel:
                    self.assertEqual(prop.get("panel_visibility") == "advanced",
                                     row["panel"] == "advanced", "panel visibility")
                self.assertTrue(close(prop.get("default_values"), row["value"]), "default")
                kind = row["kind"]
                self.assertEqual(prop.tag, "DoubleVectorProperty" if kind == "real"
                                 else "IntVectorProperty")
                if kind == "flag":
                    self.assertIsNotNone(prop.find("BooleanDomain"))
                elif kind == "choice":
                    entries = prop.find("EnumerationDomain").findall("Entry")
                    self.assertEqual([int(e.get("value")) for e in entries],
                                     list(range(len(row["choices"]))))
                else:
                    domain = prop.find("DoubleRangeDomain" if kind == "real" else "IntRangeDomain")
                    low = 0 if row["zero_allowed"] else row["minimum"]
                    self.assertTrue(close(domain.get("min"), low), "minimum")
                    top = row["maximum"]
                    if top is None or top >= SLIDER_LIMIT or (
                            kind == "real" and row["value"] > 0
                            and top / row["value"] >= SLIDER_SPAN):
                        # A slider over such a range could not be used: a plain number field.
                        self.assertIsNone(domain.get("max"), "a large range has no max")
                    else:
                        self.assertIsNotNone(domain.get("max"), "maximum")
                        self.assertTrue(close(domain.get("max"), top), "maximum")

    def test_the_track_filters_xml_agrees_with_the_option_table(self):
        # Every tracker option is described once (dp::trackerOptions()); the panel's property
        # of each says the same default, range, kind and visibility.
        table = json.loads(describe_options("json"))["tracker"]
        self.assertGreaterEqual(len(table), 40)
        rows = {row["property"]: row for row in table if row["property"]}
        proxy = next(p for p in ET.parse(TRACK_XML).getroot().iter("SourceProxy"))
        xml = {p.get("name"): p for p in proxy if p.get("command")}
        self.assertEqual(set(xml) - NOT_TRACKER_OPTIONS, set(rows),
                         "the XML's tracker properties and the table's differ")
        self.check_properties(rows, xml)

    def test_the_codec_and_writers_xml_agree_with_the_option_table(self):
        # Every compression option is described once (dp::compressionOptions()): the codec
        # filter has each as a property, the two writers each but Quantize (a file is always
        # quantised), with the table's default, range and kind.
        table = json.loads(describe_options("json"))["compression"]
        self.assertGreaterEqual(len(table), 8)
        rows = {row["property"]: row for row in table if row["property"]}
        proxies = {p.get("name"): p for p in ET.parse(COMPRESS_XML).getroot().iter()
                   if p.tag in ("SourceProxy", "WriterProxy")}
        for name in ("PCACompressFilter", "CompressedSequenceWriter", "GLBMorphAnimationWriter"):
            with self.subTest(proxy=name):
                xml = {p.get("name"): p for p in proxies[name] if p.get("command")}
                # A .glb is always in the shape layout: its writer has no Layout.
                expected = set(rows) - ({"Quantize"} if "Writer" in name else set()) - (
                    {"Layout"} if name.startswith("GLB") else set())
                self.assertEqual(set(xml) - NOT_COMPRESSION_OPTIONS, expected,
                                 "the XML's compression properties and the table's differ")
                self.check_properties({k: rows[k] for k in expected}, xml,
                                      check_panel=name == "PCACompressFilter")

    def test_the_shared_ranges_are_the_engines(self):
        # The template's vertex count: one range, the engine's, in the XML.
        limits = json.loads(describe_options_limits())
        root = ET.parse(TRACK_XML).getroot()
        vertices = next(p for p in root.iter("IntVectorProperty")
                        if p.get("name") == "TemplateVertices")
        domain = vertices.find("IntRangeDomain")
        self.assertEqual(int(vertices.get("default_values")), limits["templateVertices"]["default"])
        self.assertEqual(int(domain.get("min")), limits["templateVertices"]["minimum"])
        self.assertGreaterEqual(limits["templateVertices"]["maximum"], SLIDER_LIMIT)
        self.assertIsNone(domain.get("max"))  # a plain number field, not a slider

    def test_the_option_documentation_is_the_table(self):
        tracker, compression = describe_options("markdown").split("\n\n")
        for doc, table in ((OPTIONS_DOC, tracker), (COMPRESSION_DOC, compression)):
            with open(doc, encoding="utf-8") as f:
                self.assertIn(table.strip(), f.read(),
                              f"{doc} is stale: regenerate its table with dynamicpoints "
                              "--describe-options markdown")

    def test_a_changed_default_is_caught(self):
        # The comparison itself: a value off by a little, or of another length, is not the same.
        self.assertTrue(same(["0.3"], 0.3))
        self.assertFalse(same(["0.3"], 0.30001))
        self.assertFalse(same(["1", "2"], (1,)))
        self.assertTrue(same([], None))
        self.assertFalse(same([], "out.dpz"))
        self.assertFalse(same(["out.dpz"], None))


if __name__ == "__main__":
    unittest.main()
