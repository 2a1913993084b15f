#!/usr/bin/env python3
"""Rate against distortion for per-frame mesh input, as volumetric-video codecs are measured.

Writes a take as per-frame meshes (dynamicpoints-sample --per-frame-mesh: each frame its own
connectivity, reconstructed from noisy samples, with a capture's defects in frame 0), runs the
main job on it at several template sizes, and prints for each what report.json says: the
decompressed mesh against each frame's own mesh (D1 and D2 PSNR, peak = the frame's diagonal,
both directions, the worse kept; means over the frames and the worst frame), bits per input
vertex per frame, components, and time.

    BenchmarkRateDistortion.py --bin BUILD/bin [--data DIR --sequence NAME | --sequence tube]
        [--sizes 1000,5000,20000] [--mesh-vertices 20000] [--points 80000] [--noise 0.001]
        [--frames N] [--work DIR]
"""
import argparse
import json
import os
import platform
import subprocess
import sys
import time


def parse():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--bin", required=True, help="folder of dynamicpoints and dynamicpoints-sample")
    p.add_argument("--data", default="", help="folder of the sequences (not needed for tube)")
    p.add_argument("--sequence", default="tube")
    p.add_argument("--sizes", default="1000,5000,20000", help="template vertex counts")
    p.add_argument("--mesh-vertices", type=int, default=20000, help="vertices of each input mesh")
    p.add_argument("--points", type=int, default=80000, help="samples a mesh is made from")
    p.add_argument("--noise", type=float, default=0.001, help="share of the diagonal")
    p.add_argument("--frames", type=int, default=0, help="first N frames only (0: all)")
    p.add_argument("--work", default="rate-distortion")
    return p.parse_args()


def machine():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.machine()


def run(command):
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"failed ({done.returncode}): {' '.join(command)}\n{done.stdout}{done.stderr}")
    return done.stdout


def write_input(a, folder):
    mesh = ["--mesh", "tube"] if a.sequence == "tube" else ["--mesh", os.path.join(a.data, a.sequence)]
    if a.sequence == "tube" and a.frames:
        mesh += ["--frames", str(a.frames)]
    run([os.path.join(a.bin, "dynamicpoints-sample"), *mesh, "--points", str(a.points),
         "--noise", str(a.noise), "--no-normals", "--per-frame-mesh", str(a.mesh_vertices),
         "--mesh-defects", folder])
    if a.frames and a.sequence != "tube":
        names = sorted(f for f in os.listdir(folder) if f.endswith(".ply"))
        for name in names[a.frames:]:
            os.remove(os.path.join(folder, name))
        os.remove(os.path.join(folder, "points.series"))


def main():
    a = parse()
    os.makedirs(a.work, exist_ok=True)
    folder = os.path.join(a.work, a.sequence + "-meshes")
    started = time.time()
    write_input(a, folder)
    print(f"== {a.sequence} as per-frame meshes of about {a.mesh_vertices} vertices "
          f"({a.points} samples, noise {a.noise} of the diagonal, defects in frame 0), written "
          f"in {time.time() - started:.0f} s; {machine()}, "
          f"{os.cpu_count()} threads")
    print(f"{'template':>9} {'comp':>5} {'bits/in-vertex/frame':>21} {'(geometry)':>10} "
          f"{'D1 PSNR dB':>10} {'D2 PSNR dB':>10} {'worst D1':>8} {'worst D2':>8} "
          f"{'ms/frame':>8} {'job s':>6}")
    for size in [int(s) for s in a.sizes.split(",")]:
        out = os.path.join(a.work, f"{a.sequence}-{size}")
        run([os.path.join(a.bin, "dynamicpoints"), folder, "--output", out, "--vertices",
             str(size), "--quiet"])
        with open(os.path.join(out, "report.json")) as f:
            report = json.load(f)
        c = report["compression"]
        m = c["againstInputMeshes"]
        print(f"{report['template']['vertices']:>9} {c['Components']:>5.0f} "
              f"{m['bitsPerInputVertexFrame']:>21.3f} {m['geometryBitsPerInputVertexFrame']:>10.3f} "
              f"{m['d1PsnrDb']:>10.2f} {m['d2PsnrDb']:>10.2f} {m['worstD1PsnrDb']:>8.2f} "
              f"{m['worstD2PsnrDb']:>8.2f} {report['medianMillisecondsPerFrame']:>8.1f} "
              f"{report['wallSeconds']:>6.1f}")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
