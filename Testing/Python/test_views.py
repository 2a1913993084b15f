"""Looking at a take: the main job's page (view.html) opened from the file system in real
browsers (Debian's Chromium, headless, driven by playwright-core: the built-in take, a coloured
take and a take with a flagged frame; Debian's Firefox ESR under Xvfb: the built-in take drawn);
its ParaView state builds the expected pipeline in pvpython; --no-view writes neither."""
import json
import os
import shutil
import subprocess
import time
import unittest

from dp_testing import (PLUGIN, TempDirTestCase, XWindows, run_node_tool, run_tool,
                        sheet_with_an_unexplained_frame, x_display)

HERE = os.path.dirname(os.path.abspath(__file__))


def drive_page(page, shots=None):
    """What Utilities/browser/drive_page.js saw of PAGE in headless Chromium."""
    return run_node_tool("playwright-core", os.path.join("browser", "drive_page.js"), page,
                         *([shots] if shots else []), timeout=400)


def shots(name):
    """Where the screenshots named NAME go: DP_SCREENSHOTS (for the notes), else nowhere."""
    folder = os.environ.get("DP_SCREENSHOTS")
    if not folder or not name:
        return None
    os.makedirs(folder, exist_ok=True)
    return os.path.join(folder, name)


# A Firefox profile that opens the page and nothing else (no first-run or welcome pages).
FIREFOX_PREFERENCES = {
    "browser.shell.checkDefaultBrowser": False,
    "browser.aboutwelcome.enabled": False,
    "browser.startup.homepage_override.mstone": "ignore",
    "datareporting.policy.dataSubmissionEnabled": False,
    "toolkit.telemetry.reportingpolicy.firstRun": False,
    "browser.sessionstore.resume_from_crash": False,
}


class TestViews(TempDirTestCase):
    def run_main(self, *args):
        out = self.path("out")
        result = run_tool("dynamicpoints", "--output", out, *args)
        with open(os.path.join(out, "report.json")) as f:
            return out, result, json.load(f)

    def check_page(self, page, report, name):
        seen = drive_page(page, shots(name))
        self.assertEqual(seen["errors"], [])
        self.assertTrue(seen["ready"], seen)
        self.assertEqual(seen["frames"], report["framesTracked"])
        self.assertEqual(seen["vertices"], report["compression"]["glb"]["vertices"])
        # The take is drawn (not a blank canvas), and moving the slider to a late frame changes
        # the picture.
        self.assertGreater(seen["frame0"]["lit"], 0.03 * seen["frame0"]["pixels"])
        self.assertEqual(seen["late"]["frame"], int(0.8 * (seen["frames"] - 1)))
        self.assertNotEqual(seen["late"]["canvas"]["checksum"], seen["frame0"]["checksum"])
        # A click on the report's plot goes to that frame; playing moves on.
        self.assertEqual(seen["plotClick"]["reached"], seen["plotClick"]["asked"])
        self.assertNotEqual(seen["played"]["to"], seen["played"]["from"])
        return seen

    def test_the_built_in_take_plays_in_chromium_and_the_last_lines_name_page_and_state(self):
        out, result, report = self.run_main()
        lines = result.stdout.strip().splitlines()
        self.assertEqual(lines[-2], f"Page: {out}/view.html (the take in a browser, from the "
                                    "file system)")
        self.assertEqual(lines[-1], f"ParaView: paraview --state={out}/paraview-state.py")
        self.assertEqual(report["outputs"]["page"], os.path.join(out, "view.html"))
        seen = self.check_page(os.path.join(out, "view.html"), report, "view-tube")
        self.assertFalse(seen["coloured"])
        self.assertEqual(seen["flagged"], [])
        # Everything it needs is inside: no other file of the folder is read.
        with open(os.path.join(out, "view.html")) as f:
            text = f.read()
        self.assertNotIn("src=", text.split("<script>")[0])

    def test_firefox_draws_the_built_in_take(self):
        out, _, _ = self.run_main("--frames", 10)
        profile = self.path("firefox-profile")
        os.makedirs(profile)
        with open(os.path.join(profile, "user.js"), "w") as f:
            f.writelines(f"user_pref({json.dumps(k)}, {json.dumps(v)});\n"
                         for k, v in FIREFOX_PREFERENCES.items())
        with x_display("1280x800") as display:
            windows = XWindows(display)
            firefox = subprocess.Popen(
                ["firefox-esr", "--kiosk", "--new-instance", "--profile", profile,
                 "file://" + os.path.join(out, "view.html")],
                env=windows.env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            try:
                # The title names the take once the page has read it; the view (the left two
                # thirds of the page) then shows the mesh on its background.
                window = windows.wait_for("points.series - DynamicPoints", timeout=120)
                end, drawn = time.monotonic() + 60, 0
                while drawn < 0.02 and time.monotonic() < end:
                    time.sleep(1)
                    picture = windows.photograph(window, shots("view-firefox.png") or
                                                 self.path("firefox.png"))
                    view = picture[:, : picture.shape[1] * 2 // 3].astype(int)
                    background = abs(view - [244, 244, 242]).sum(axis=2) < 10
                    drawn = 1 - background.mean()
            finally:
                firefox.terminate()
                firefox.wait(timeout=60)
        self.assertGreater(drawn, 0.02, "Firefox drew no take in the page's view")
        self.assertLess(drawn, 0.6, "the page's view is not its background colour")

    def test_a_coloured_take_shows_its_colours(self):
        run_tool("dynamicpoints-sample", "--colour", "--frames", 6, "--points", 6000,
                 self.path("seq"))
        out, _, report = self.run_main("--vertices", 300, self.path("seq", "points.series"))
        seen = self.check_page(os.path.join(out, "view.html"), report, "view-colour")
        self.assertTrue(seen["coloured"])
        self.assertGreater(seen["frame0"]["colours"], 40)

    def test_a_flagged_frame_is_reached_from_the_plot(self):
        # Frame 3 gets a ball of points beside the sheet that no deformation explains (as in
        # test_main_job): it is flagged, and the page's plot takes the user there.
        sheet_with_an_unexplained_frame(self.path("seq"))
        out, _, report = self.run_main("--detail-levels", 0, self.path("seq"))
        self.assertEqual(report["framesFailed"], [3])
        seen = self.check_page(os.path.join(out, "view.html"), report, None)
        self.assertEqual(seen["flagged"], [3])
        self.assertEqual(seen["plotClick"], {"asked": 3, "reached": 3})

    def test_no_view_writes_neither(self):
        out, result, report = self.run_main("--frames", 3, "--no-view")
        self.assertFalse(os.path.exists(os.path.join(out, "view.html")))
        self.assertFalse(os.path.exists(os.path.join(out, "paraview-state.py")))
        self.assertNotIn("page", report["outputs"])
        self.assertNotIn("ParaView:", result.stdout)

    def test_the_paraview_state_builds_the_pipeline(self):
        run_tool("dynamicpoints-sample", "--frames", 5, "--points", 4000, self.path("seq"))
        out, _, report = self.run_main("--vertices", 300, "--detail-levels", 0,
                                       self.path("seq", "points.series"))
        state = os.path.join(out, "paraview-state.py")
        with open(state) as f:
            self.assertIn(f"paraview --state={state}", f.read())
        with x_display() as display:  # the state renders
            result = subprocess.run(
                [shutil.which("pvpython"), "--dr", os.path.join(HERE, "pv_state.py"), state],
                capture_output=True, text=True, timeout=300,
                env=dict(os.environ, DP_PLUGIN=PLUGIN, DISPLAY=display))
        lines = [l for l in result.stdout.splitlines() if l.startswith("DP-STATE ")]
        self.assertTrue(lines, result.stdout + result.stderr)
        seen = json.loads(lines[0][len("DP-STATE "):])
        self.assertEqual(seen["sources"], {"tracked": "PVDReader",
                                           "points": "DynamicPointsSequenceReader"})
        self.assertEqual(seen["tracked"]["colour"], ["POINTS", "Residual"])
        self.assertEqual(seen["tracked"]["representation"], "Surface")
        self.assertEqual(seen["points"]["representation"], "Points")
        self.assertEqual(len(seen["times"]), report["framesTracked"])
        self.assertEqual(seen["viewTime"], seen["times"][0])
        self.assertEqual(seen["playMode"], "Snap To TimeSteps")
        self.assertEqual(seen["trackedPoints"], report["template"]["vertices"])


if __name__ == "__main__":
    unittest.main()
