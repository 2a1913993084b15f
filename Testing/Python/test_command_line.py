"""The command-line tools: help for both, the sampler's options and inputs (the main job's run
and its bad input: test_main_job.py)."""
import json
import os
import unittest

from dp_testing import TempDirTestCase, run_tool


class TestCommandLineTools(TempDirTestCase):
    def test_help_reads_like_a_unix_tool(self):
        for tool in ("dynamicpoints", "dynamicpoints-sample"):
            result = run_tool(tool, "--help")
            self.assertTrue(result.stdout.startswith("Usage: " + tool), result.stdout)
            self.assertEqual(result.stderr, "")

    def test_sampler_wrong_options_exit_2_with_a_hint(self):
        for args, message in ((["--points", "-5", "x"], "is not a whole number"),
                              (["--noise", "abc", "x"], "is not a number"),
                              (["--format", "las", "x"], "not one of ply pcd xyz csv obj drc"),
                              ([], "no OUTPUT_FOLDER")):
            result = run_tool("dynamicpoints-sample", *args, check=False)
            self.assertEqual(result.returncode, 2, args)
            self.assertIn(message, result.stderr)

    def test_sampler_reads_a_folder_of_meshes(self):
        run_tool("dynamicpoints-sample", "--frames", 3, "--points", 100, "--truth", self.path("a"))
        result = run_tool("dynamicpoints-sample", "--mesh", self.path("a", "truth"), "--points",
                          50, "--format", "pcd", self.path("b"))
        self.assertIn("wrote 3 frames of 50 samples", result.stdout)
        self.assertTrue(os.path.exists(self.path("b", "frame_0002.pcd")))
        missing = run_tool("dynamicpoints-sample", "--mesh", self.path("nowhere"), self.path("c"),
                           check=False)
        self.assertEqual(missing.returncode, 1)
        self.assertIn("nowhere: folder does not exist", missing.stderr)

    def test_options_by_name_from_flags_and_a_file(self):
        printed = json.loads(run_tool("dynamicpoints", "--print-options").stdout)
        self.assertEqual(printed["graph.yieldRate"], 0.3)
        self.assertEqual(printed["solver"], "gauss-newton")
        # The main job judges its compression against the data by default.
        self.assertEqual(printed["compression.measure"], "data")
        self.assertEqual(printed["compression.fitGrowth"], 10)
        self.assertGreaterEqual(len(printed), 53)
        # What --print-options writes, --options reads; --set after it wins.
        printed["graph.yieldRate"] = 0.5
        printed["solver"] = "lbfgs"
        with open(self.path("options.json"), "w") as f:
            json.dump(printed, f)
        changed = json.loads(run_tool("dynamicpoints", "--options", self.path("options.json"),
                                      "--set", "colourWeight=7", "--set", "CoarseLevel=off",
                                      "--set", "compression.layout=shapes",
                                      "--error-target", "0.1", "--colour-tolerance", "0",
                                      "--print-options").stdout)
        self.assertEqual((changed["graph.yieldRate"], changed["solver"]), (0.5, "lbfgs"))
        self.assertEqual((changed["colourWeight"], changed["graph.enabled"]), (7, False))
        self.assertEqual((changed["compression.layout"], changed["compression.measure"],
                          changed["compression.kgTarget"], changed["compression.colourTolerance"]),
                         ("shapes", "kg", 0.1, 0))
        for args, message in (
                (["--set", "graph.yieldRate=1.5"],
                 "tracker option graph.yieldRate: 1.5 is out of its range [0, 1]"),
                (["--set", "graph.yieldrate=1"], "no tracker option 'graph.yieldrate'"),
                (["--set", "solver"], "--set wants NAME=VALUE"),
                (["--options", self.path("missing.json")], "cannot read"),
                (["--set", "compression.colourTolerance=99"],
                 "compression option compression.colourTolerance: 99 is out of its range [0, 64]"),
                (["--describe-options", "yaml"], "wants json or markdown")):
            result = run_tool("dynamicpoints", *args, "--print-options", check=False)
            self.assertEqual(result.returncode, 2, args)
            self.assertIn(message, result.stderr)

    def test_help_describes_every_compression_option_from_the_table(self):
        help_text = run_tool("dynamicpoints", "--help").stdout
        table = json.loads(run_tool("dynamicpoints", "--describe-options", "json").stdout)
        for row in table["compression"]:
            self.assertIn("\n  " + row["name"] + "\n", help_text)
            # Its range and its first words, as the table says them (wrapped).
            first = " ".join(row["doc"].split()[:4])
            self.assertIn(first, " ".join(help_text.split()), row["name"])
        self.assertIn("compression.measure\n                      kg|max-vertex|data (default data)",
                      help_text)

    def test_the_documentation_lists_the_per_frame_figures_of_the_report(self):
        per_frame, compression = run_tool("dynamicpoints", "--describe-report").stdout.split("\n\n")
        self.assertIn("| `LargestStretch` | `largestStretch` |", per_frame)
        self.assertIn("| `DistanceToDataGrowth` |", compression)
        doc = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                           "Documentation", "MainJob.md")
        with open(doc, encoding="utf-8") as f:
            text = f.read()
        for table in (per_frame, compression):
            self.assertIn(table.strip(), text, "MainJob.md's tables of the report's figures are "
                          "stale: regenerate them with dynamicpoints --describe-report")


if __name__ == "__main__":
    unittest.main()
