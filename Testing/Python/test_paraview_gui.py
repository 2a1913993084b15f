"""The ParaView GUI as a new user meets it (Xvfb, a fresh profile, the README's command): no
Welcome dialog stops the script; Save Data shows progress over the whole take; an abort between
frames keeps the frames done; File > Open on a numbered .ply group offers the Point Sequence
Reader first and shows the points; the panel, the result and the reader dialog are photographed
for the README (into DP_SCREENSHOTS)."""
import json
import os
import shutil
import subprocess
import tempfile
import time
import unittest

import numpy as np

from dp_testing import PLUGIN, XWindows, run_tool, x_display

HERE = os.path.dirname(os.path.abspath(__file__))
FRAMES = 6


def wait_for_file(path, process, timeout=300):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if os.path.exists(path):
            return
        if process.poll() is not None:
            raise AssertionError(f"paraview exited ({process.returncode}) before {path}")
        time.sleep(0.5)
    raise AssertionError(f"{path} not written after {timeout} s")


class ParaViewGuiCase(unittest.TestCase):
    """Starts the GUI as the README says (`paraview --dr --script=...`; --dr: no Welcome dialog
    on a fresh profile) on its own X server with a fresh HOME, with SCRIPT (a file of this
    folder; none: no script) and what prepare() returns, and waits for the script's file DONE in
    cls.output and for the main window."""
    SCRIPT = DONE = None

    @classmethod
    def prepare(cls):
        """What a case makes before ParaView starts; returns its further arguments."""
        return []

    @classmethod
    def setUpClass(cls):
        cls._tmp = tempfile.TemporaryDirectory(prefix="dp-gui-")
        cls.tmp = cls._tmp.name
        cls.frames = os.path.join(cls.tmp, "frames")
        run_tool("dynamicpoints-sample", "--frames", FRAMES, "--points", 3000, cls.frames)
        cls.shots = os.environ.get("DP_SCREENSHOTS") or os.path.join(cls.tmp, "screenshots")
        os.makedirs(cls.shots, exist_ok=True)
        home = os.path.join(cls.tmp, "home")
        os.makedirs(home)
        cls.output = os.path.join(cls.tmp, "out")
        os.makedirs(cls.output)
        cls._display = x_display()
        display = cls._display.__enter__()
        cls.paraview = None
        try:
            cls.x = XWindows(display)
            arguments = cls.prepare()
            if cls.SCRIPT:
                arguments.append("--script=" + os.path.join(HERE, cls.SCRIPT))
            cls.paraview = subprocess.Popen(
                [shutil.which("paraview"), "--dr", *arguments],
                env=dict(os.environ, DISPLAY=display, HOME=home, DP_PLUGIN=PLUGIN,
                         DP_SERIES=os.path.join(cls.frames, "points.series"),
                         DP_OUTPUT=cls.output),
                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True)
            if cls.DONE:
                wait_for_file(os.path.join(cls.output, cls.DONE), cls.paraview)
            time.sleep(3)  # ParaView shows its Welcome dialog a second after start, if at all
            cls.main = cls.x.wait_for(r"^ParaView 5")
            cls.x.resize(cls.main, 1500, 950)
            time.sleep(3)
        except BaseException:
            cls.tearDownClass()
            raise

    @classmethod
    def tearDownClass(cls):
        if cls.paraview:
            cls.paraview.kill()
            log = cls.paraview.communicate(timeout=60)[0]
            if os.environ.get("DP_VERBOSE"):
                print(log.decode(errors="replace"))
        cls._display.__exit__(None, None, None)
        cls._tmp.cleanup()


class TestParaViewGuiSession(ParaViewGuiCase):
    SCRIPT, DONE = "gui_session.py", "session.json"

    @classmethod
    def setUpClass(cls):
        super().setUpClass()
        with open(os.path.join(cls.output, "session.json")) as f:
            cls.session = json.load(f)

    def test_1_no_welcome_dialog_stops_the_script(self):
        self.assertEqual(self.x.visible("Welcome"), [])

    def test_2_save_data_progress_rises_over_the_whole_take(self):
        events = [(text, value) for text, value in self.session["save_progress"] if text]
        said = list(dict.fromkeys(text for text, _ in events))
        self.assertEqual(said, [f"Deformable Track: frame {k} of {FRAMES}"
                                for k in range(1, FRAMES + 1)])
        # Each frame's events stay in its share of the bar: near 0 at the start, 1 at the end,
        # never back, not 100 % after every frame.
        for text, value in events:
            k = int(text.split()[3])
            self.assertGreaterEqual(value, (k - 1) / FRAMES - 1e-9, (text, value))
            self.assertLessEqual(value, k / FRAMES + 1e-9, (text, value))
        values = [value for _, value in events]
        self.assertLessEqual(values[0], 1 / FRAMES)
        self.assertEqual(values[-1], 1.0)
        self.assertEqual(values, sorted(values))
        self.assertTrue(os.path.getsize(os.path.join(self.output, "saved.dpz")) > 0)

    def test_3_abort_between_frames_keeps_the_frames_done(self):
        said = {text for text, _ in self.session["abort_progress"] if text}
        self.assertIn(f"Deformable Track: frame 3 of {FRAMES}", said)
        self.assertNotIn(f"Deformable Track: frame 4 of {FRAMES}", said)
        self.assertEqual(self.session["abort_output_frame"], 2)
        # Going on to another time tracks frames 4 and 5 only: frames 1-3 were kept.
        again = list(dict.fromkeys(t for t, _ in self.session["resume_progress"] if t))
        self.assertEqual([t.split(" of ")[0] for t in again][-2:],
                         ["Deformable Track: frame 4", "Deformable Track: frame 5"])
        for k in (1, 2):
            self.assertFalse([t for t in again if t.startswith(f"Deformable Track: frame {k} ")])
        self.assertEqual(self.session["resume_output_frame"], FRAMES - 2)

    def test_4_the_series_opens_with_the_point_sequence_reader(self):
        self.assertEqual(self.session["reader"], "DynamicPointsSequenceReader")

    def test_5_the_panel_and_the_result(self):
        shot = self.x.photograph(self.main, os.path.join(self.shots, "paraview-gui.png"))
        height, width = shot.shape[:2]
        self.assertGreaterEqual(height, 900)
        self.assertGreaterEqual(width, 1400)
        # The render view (right of the panels) shows the coloured mesh: many colours, not the
        # plain background.
        view = shot[200:, 400:].reshape(-1, 3)
        colours = np.unique(view // 16, axis=0)
        self.assertGreater(len(colours), 40)



class TestParaViewGuiOpen(ParaViewGuiCase):
    SCRIPT, DONE = "gui_ready.py", "ready"

    def test_file_open_on_a_ply_group_shows_the_points(self):
        before = self.x.photograph(self.main, os.path.join(self.tmp, "before.png")).astype(int)
        # File > Open, the first frame of the group, Return.
        self.x.key(self.main, "ctrl+o")
        dialog = self.x.wait_for("^Open File")
        time.sleep(1)
        self.x.type(dialog, os.path.join(self.frames, "frame_0000.ply"))
        self.x.key(dialog, "Return")
        # Two readers can read .ply: ParaView asks, with ours preselected (its first reader:
        # pv_point_sequence.py checks the order); Return takes it.
        choose = self.x.wait_for("^Open Data With")
        time.sleep(1)
        self.x.photograph(choose, os.path.join(self.shots, "open-data-with.png"))
        self.x.key(choose, "Return")
        # Auto Apply shows the file at once: its points appear in the view. (ParaView's PLY
        # reader gives points without cells, which its default Surface view does not draw.)
        end = time.monotonic() + 60
        while True:
            time.sleep(2)
            after = self.x.photograph(self.main, os.path.join(self.shots, "opened-ply.png"))
            changed = np.abs(after.astype(int) - before).sum(axis=2) > 60
            if changed[250:, 300:].sum() > 1000 or time.monotonic() > end:
                break
        self.assertGreater(changed[250:, 300:].sum(), 1000)


class TestParaViewGuiState(ParaViewGuiCase):
    """`paraview --state=OUTPUT/paraview-state.py`, as the main job's last line says (ParaView
    takes no --script beside --state): the tracked take over its points, coloured by the
    distance to them."""

    @classmethod
    def prepare(cls):
        run_tool("dynamicpoints", "--output", os.path.join(cls.tmp, "job"), "--vertices", 300,
                 os.path.join(cls.frames, "points.series"))
        return ["--state=" + os.path.join(cls.tmp, "job", "paraview-state.py")]

    def test_the_state_shows_the_coloured_take_over_its_points(self):
        # The middle of the render view (right of the panels): beside its background, the mesh in
        # the distance's colours and the dark points; photographed until the state has drawn
        # them.
        end = time.monotonic() + 120
        while True:
            shot = self.x.photograph(self.main, os.path.join(self.shots, "paraview-state.png"))
            view = shot[300:850, 500:1350].reshape(-1, 3).astype(int)
            values, counts = np.unique(view, axis=0, return_counts=True)
            background = values[counts.argmax()]
            drawn = view[np.abs(view - background).sum(axis=1) > 60]
            colours = len(np.unique(drawn // 16, axis=0))
            if (len(drawn) > 0.03 * len(view) and colours > 30) or time.monotonic() > end:
                break
            time.sleep(3)
        self.assertGreater(len(drawn), 0.03 * len(view))
        self.assertGreater(colours, 30)


if __name__ == "__main__":
    unittest.main()
