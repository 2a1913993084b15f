"""The main job on a batch of takes: each input into OUTPUT/<name>/ as a run on it alone, a report
for all (batch.json), a bad input failing alone and named; under `mpirun -np 2` the inputs are
handed out largest first to whichever process is free, with byte-identical files."""
import filecmp
import json
import os
import shutil
import subprocess
import tempfile
import unittest

from dp_testing import run_tool, tool

EXAMPLE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "Examples",
                       "ParaView", "track_takes.py")

OPTIONS = ["--vertices", "300", "--quiet"]


def dynamicpoints(*args, mpi=0):
    command = [tool("dynamicpoints"), *OPTIONS, *map(str, args)]
    if mpi:
        mpirun = shutil.which("mpirun")
        if not mpirun:
            raise AssertionError("mpirun (openmpi-bin) is missing")
        command = [mpirun, "-np", str(mpi), "--oversubscribe", "--allow-run-as-root", *command]
    return subprocess.run(command, capture_output=True, text=True, timeout=600)


class TestBatch(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls._tmp = tempfile.TemporaryDirectory(prefix="dp-batch-")
        cls.tmp = cls._tmp.name
        # Three takes of different sizes (the largest, "long", goes first) and a broken one.
        for name, frames, points in (("short", 4, 3000), ("long", 8, 3000), ("mid", 6, 3000)):
            run_tool("dynamicpoints-sample", "--frames", frames, "--points", points,
                     "--seed", frames, cls.take(name))
        os.makedirs(cls.take("broken"))
        with open(os.path.join(cls.take("broken"), "frame_0000.ply"), "w") as f:
            f.write("not a ply file\n")
        cls.inputs = [cls.take("short"), os.path.join(cls.take("long"), "points.series"),
                      cls.take("mid") + "/", cls.take("broken")]
        cls.one = dynamicpoints("--output", cls.out("one"), *cls.inputs)
        cls.two = dynamicpoints("--output", cls.out("two"), *cls.inputs, mpi=2)

    @classmethod
    def tearDownClass(cls):
        cls._tmp.cleanup()

    @classmethod
    def take(cls, name):
        return os.path.join(cls.tmp, "takes", name)

    @classmethod
    def out(cls, *parts):
        return os.path.join(cls.tmp, *parts)

    def batch(self, run):
        with open(self.out(run, "batch.json")) as f:
            return json.load(f)

    def test_each_input_has_its_own_folder_and_the_report_says_how_it_ended(self):
        self.assertEqual(self.one.returncode, 1, self.one.stderr)
        report = self.batch("one")
        self.assertEqual([os.path.basename(e["output"]) for e in report["inputs"]],
                         ["short", "long", "mid", "broken"])
        for entry, frames in zip(report["inputs"][:3], (4, 8, 6)):
            self.assertEqual((entry["result"], entry["exitStatus"]), ("done", 0), entry)
            self.assertEqual(entry["frames"], frames)
            for name in ("tracked.dpz", "tracked.glb", "tracked.pvd", "report.json"):
                self.assertTrue(os.path.exists(os.path.join(entry["output"], name)), name)
        broken = report["inputs"][3]
        self.assertEqual((broken["result"], broken["exitStatus"]), ("failed", 1))
        # The failure is named; the others' outputs are written.
        self.assertIn("1 of 4 inputs did not finish", self.one.stderr)
        self.assertIn(self.take("broken") + " (failed)", self.one.stderr)

    def test_two_processes_share_the_batch_and_write_the_same_files(self):
        self.assertEqual(self.two.returncode, 1, self.two.stdout + self.two.stderr)
        self.assertIn(self.take("broken") + " (failed)", self.two.stderr)
        report = self.batch("two")
        self.assertEqual(report["processes"], 2)
        by_name = {os.path.basename(e["output"]): e for e in report["inputs"]}
        # Handed out largest first (by bytes on disk) to whichever process is free; both worked.
        self.assertEqual({name: e["turn"] for name, e in by_name.items()},
                         {"long": 0, "mid": 1, "short": 2, "broken": 3})
        self.assertEqual({e["process"] for e in report["inputs"]}, {0, 1})
        for name in ("short", "long", "mid"):
            for output in ("tracked.dpz", "tracked.glb"):
                self.assertTrue(filecmp.cmp(self.out("one", name, output),
                                            self.out("two", name, output), shallow=False),
                                (name, output))

    def test_pvbatch_spreads_the_takes_over_its_ranks_with_the_main_jobs_bytes(self):
        # The documented pvbatch script: every rank runs it and takes whole takes.
        takes = [self.take("long"), self.take("mid"), self.take("broken")]
        result = subprocess.run(
            [shutil.which("mpirun"), "-np", "2", "--oversubscribe", "--allow-run-as-root",
             shutil.which("pvbatch"), "--symmetric", EXAMPLE, "--vertices", "300",
             self.out("pvbatch"), *takes],
            capture_output=True, text=True, timeout=600,
            env=dict(os.environ, PYTHONPATH=os.environ.get("PYTHONPATH", "")))
        self.assertEqual(result.returncode, 1, result.stdout + result.stderr)
        self.assertIn("1 of 3 takes failed", result.stderr)
        self.assertIn(self.take("broken"), result.stderr)
        ranks = {line.split("]")[0] for line in result.stdout.splitlines()
                 if line.startswith("[rank ")}
        self.assertEqual(ranks, {"[rank 0", "[rank 1"}, result.stdout)
        for name in ("long", "mid"):
            for output in ("tracked.dpz", "tracked.glb"):
                self.assertTrue(filecmp.cmp(self.out("one", name, output),
                                            self.out("pvbatch", name, output), shallow=False),
                                (name, output))

    def test_inputs_of_the_same_name_get_their_own_folders(self):
        first = os.path.join(self.tmp, "a", "take")
        second = os.path.join(self.tmp, "b", "take")
        for seed, folder in enumerate((first, second), start=1):
            run_tool("dynamicpoints-sample", "--frames", 3, "--points", 2000, "--seed", seed,
                     folder)
        result = dynamicpoints("--output", self.out("same"), first, second)
        self.assertEqual(result.returncode, 0, result.stderr)
        outputs = [e["output"] for e in self.batch("same")["inputs"]]
        self.assertEqual([os.path.basename(o) for o in outputs], ["take", "take-2"])
        self.assertFalse(filecmp.cmp(os.path.join(outputs[0], "tracked.dpz"),
                                     os.path.join(outputs[1], "tracked.dpz"), shallow=False))


if __name__ == "__main__":
    unittest.main()
