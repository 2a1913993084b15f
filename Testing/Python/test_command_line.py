"""The command-line tools as a user meets them: help, the default run, bad paths and options."""
import os
import unittest

from dp_testing import TempDirTestCase, run_tool


class TestMainJob(TempDirTestCase):
    def test_default_run_generates_and_summarises_the_builtin_sequence(self):
        result = run_tool("dynamicpoints", "--output", self.path("out"))
        self.assertIn("Sequence: 30 frame(s)", result.stdout)
        self.assertIn("30 of 30 frame(s) read.", result.stdout)
        lines = [l for l in result.stdout.splitlines() if l.strip().startswith("29 ")]
        self.assertEqual(len(lines), 1, result.stdout)
        self.assertIn("20000", lines[0])
        self.assertIn("Normals", lines[0])
        self.assertTrue(os.path.exists(self.path("out", "input", "points.series")))

    def test_help_reads_like_a_unix_tool(self):
        for tool in ("dynamicpoints", "dynamicpoints-sample"):
            result = run_tool(tool, "--help")
            self.assertTrue(result.stdout.startswith("Usage: " + tool), result.stdout)
            self.assertEqual(result.stderr, "")

    def test_missing_folder_is_a_clear_error(self):
        missing = self.path("no-such-folder")
        os.makedirs(self.path("empty"))
        for argument, message in ((missing, "does not exist"),
                                  (self.path("empty"), "no point files match")):
            result = run_tool("dynamicpoints", argument, check=False)
            if argument == missing:
                # Not a folder, so it is taken as a file name.
                self.assertIn(missing, result.stderr)
            else:
                self.assertIn(message, result.stderr)
            self.assertEqual(result.returncode, 1)
            self.assertNotIn("Segmentation", result.stderr)

    def test_unreadable_frame_fails_that_frame_only(self):
        run_tool("dynamicpoints-sample", "--frames", 3, "--points", 100, self.path("seq"))
        with open(self.path("seq", "frame_0001.ply"), "r+b") as f:
            f.truncate(300)
        result = run_tool("dynamicpoints", self.path("seq", "points.series"), check=False)
        self.assertEqual(result.returncode, 1)
        self.assertIn("frame_0001.ply", result.stderr)
        self.assertIn("truncated", result.stderr)
        self.assertIn("2 of 3 frame(s) read, 1 failed", result.stdout)

    def test_wrong_options_exit_2_with_a_hint(self):
        for args, message in ((["--bogus"], "unknown option '--bogus'"),
                              (["--output"], "option --output needs a value"),
                              (["a", "b"], "more than one INPUT")):
            result = run_tool("dynamicpoints", *args, check=False)
            self.assertEqual(result.returncode, 2, args)
            self.assertIn(message, result.stderr)
            self.assertIn("--help", result.stderr)
        for args, message in ((["--points", "-5", "x"], "is not a whole number"),
                              (["--noise", "abc", "x"], "is not a number"),
                              (["--format", "las", "x"], "not one of ply pcd xyz csv obj"),
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


if __name__ == "__main__":
    unittest.main()
