"""Wall time of the main job on a batch of takes: one process against `mpirun -np N`, runs
interleaved, medians printed with the speed-up.

    /usr/bin/python3 Testing/Benchmarks/BenchmarkBatch.py --bin build/bin [--processes 2]
        [--takes 4] [--frames 30] [--points 20000] [--vertices 1000] [--repeats 3]

The takes are the built-in sample sequences (the bending tube and the waving sheet, one seed
each), written once into a temporary folder.
"""
import argparse
import os
import platform
import shutil
import statistics
import subprocess
import tempfile
import time


def machine():
    model = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            model = next(line.split(":", 1)[1].strip() for line in f
                         if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return f"{model}, {os.cpu_count()} hardware threads"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bin", required=True, help="the build's bin folder")
    parser.add_argument("--processes", type=int, default=2)
    parser.add_argument("--takes", type=int, default=4)
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--points", type=int, default=20000)
    parser.add_argument("--vertices", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    mpirun = shutil.which("mpirun")
    if not mpirun:
        raise SystemExit("mpirun not found (apt install openmpi-bin)")

    with tempfile.TemporaryDirectory(prefix="dp-batch-bench-") as tmp:
        takes = []
        for k in range(args.takes):
            take = os.path.join(tmp, f"take{k + 1}")
            subprocess.run([os.path.join(args.bin, "dynamicpoints-sample"), "--mesh",
                            ("tube", "sheet")[k % 2], "--seed", str(k + 1), "--frames",
                            str(args.frames), "--points", str(args.points), take],
                           check=True, capture_output=True)
            takes.append(take)
        job = [os.path.join(args.bin, "dynamicpoints"), "--quiet", "--vertices",
               str(args.vertices)]
        runs = {"1 process": [], f"{args.processes} processes (mpirun)": []}
        for repeat in range(args.repeats):
            for label in runs:
                output = os.path.join(tmp, f"out-{repeat}-{len(runs[label])}-{label[0]}")
                command = job + ["--output", output] + takes
                if label != "1 process":
                    command = [mpirun, "-np", str(args.processes), "--oversubscribe",
                               "--allow-run-as-root"] + command
                start = time.perf_counter()
                result = subprocess.run(command, capture_output=True, text=True)
                seconds = time.perf_counter() - start
                if result.returncode != 0:
                    raise SystemExit(f"{label} failed:\n{result.stderr[-2000:]}")
                runs[label].append(seconds)
                print(f"run {repeat + 1}, {label}: {seconds:.2f} s", flush=True)
                shutil.rmtree(output)

    print(f"\nMachine: {machine()}")
    print(f"Batch: {args.takes} takes x {args.frames} frames x {args.points} points, "
          f"{args.vertices}-vertex reconstructed template; medians of {args.repeats} "
          "interleaved runs (wall time, everything the main job writes included)")
    medians = {label: statistics.median(seconds) for label, seconds in runs.items()}
    for label, median in medians.items():
        print(f"  {label:<24} {median:8.2f} s")
    one, many = medians.values()
    print(f"  speed-up                 {one / many:8.2f}x")


if __name__ == "__main__":
    main()
