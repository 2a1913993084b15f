"""The engine's layers: each concern (a folder of Filters/Engine/dp and its CMake object library)
uses only what it declares in Filters/Engine/CMakeLists.txt, and what those declare in turn; and
Documentation/Development.md's map says the same dependencies. Every #include of the engine's
sources is checked, so a unit that reaches upward (the tracker into the codec, say) fails here."""
import os
import re
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
ENGINE = os.path.join(ROOT, "Filters", "Engine")
SHARED = "support"  # header-only helpers every concern may use


def read(path):
    with open(path) as f:
        return f.read()


def declared_concerns():
    """{concern: set of concerns it names} from the dp_engine_concern() calls."""
    text = read(os.path.join(ENGINE, "CMakeLists.txt"))
    concerns = {}
    for name, body in re.findall(r"dp_engine_concern\((\w+)(.*?)\)\n", text, re.S):
        concerns[name] = set(re.findall(r"\bdp_(\w+)", body))
    return concerns


def reachable(concerns, name):
    seen, todo = set(), [name]
    while todo:
        for used in concerns[todo.pop()]:
            if used not in seen:
                seen.add(used)
                todo.append(used)
    return seen


def documented_concerns():
    """{concern: set of concerns its Development.md entry says it is on}."""
    lines = read(os.path.join(ROOT, "Documentation", "Development.md")).split("\n")
    entries, current = {}, None
    for line in lines:
        start = re.match(r"  - `(\w+)/` — ", line)
        if start:
            current = start.group(1)
            entries[current] = line
        elif current and line.startswith("    "):
            entries[current] += " " + line.strip()
        else:
            current = None
    documented = {}
    for name, entry in entries.items():
        on = re.search(r"\(on ([^;)]*)", entry)
        documented[name] = set(re.findall(r"`(\w+)`", on.group(1))) if on else set()
    return documented


def engine_includes(concern):
    """(file, included concern) for every #include "dp/..." of the concern's files."""
    folder = os.path.join(ENGINE, "dp", concern)
    for file in sorted(os.listdir(folder)):
        for used in re.findall(r'#include "dp/(\w+)/', read(os.path.join(folder, file))):
            yield file, used


class TestEngineLayers(unittest.TestCase):
    def test_every_include_is_of_a_declared_concern(self):
        concerns = declared_concerns()
        self.assertGreaterEqual(set(concerns), {"io", "geometry", "field", "track", "compress",
                                                "export", "detail"})
        for concern in concerns:
            allowed = reachable(concerns, concern) | {concern, SHARED}
            for file, used in engine_includes(concern):
                with self.subTest(file=f"{concern}/{file}"):
                    self.assertIn(used, allowed, f"dp/{concern}/{file} includes dp/{used}/, "
                                  f"which {concern} does not declare in its CMake library")

    def test_the_shared_helpers_use_no_concern(self):
        for file, used in engine_includes(SHARED):
            self.assertEqual(used, SHARED, f"dp/{SHARED}/{file} includes dp/{used}/")

    def test_the_documentation_draws_the_same_map(self):
        concerns = declared_concerns()
        documented = documented_concerns()
        for concern, uses in concerns.items():
            with self.subTest(concern=concern):
                self.assertIn(concern, documented, "Development.md has no entry for it")
                self.assertEqual(documented[concern], uses)

    def test_the_layers_run_one_way(self):
        # No concern reaches itself again through what it uses (a cycle), and the codec and the
        # tracker stay apart: compression is one room below the tracker and the detail layer.
        concerns = declared_concerns()
        for concern in concerns:
            self.assertNotIn(concern, reachable(concerns, concern))
        self.assertNotIn("compress", reachable(concerns, "track"))
        self.assertNotIn("track", reachable(concerns, "compress"))
        self.assertNotIn("track", reachable(concerns, "detail"))


class TestEngineUnitsAreTested(unittest.TestCase):
    # Headers that are no unit of their own, with the reason; every other engine header is
    # included by a GoogleTest file (Development.md: one test file per engine unit).
    NOT_UNITS = {
        "dp/track/TrackerParts.h": "Tracker's private parts, shared by its two source files",
    }

    def test_every_engine_header_is_included_by_a_test(self):
        tests = os.path.join(ROOT, "Testing", "Cxx")
        included = set()
        for name in os.listdir(tests):
            included |= set(re.findall(r'#include "(dp/[\w/]+\.h)"', read(os.path.join(tests, name))))
        headers = set()
        for folder, _, files in os.walk(os.path.join(ENGINE, "dp")):
            headers |= {os.path.relpath(os.path.join(folder, f), ENGINE) for f in files
                        if f.endswith(".h")}
        self.assertEqual(sorted(headers - included - set(self.NOT_UNITS)), [],
                         "engine headers no test includes")
        self.assertEqual(sorted(set(self.NOT_UNITS) - headers), [], "exempted headers that are gone")


if __name__ == "__main__":
    unittest.main()
