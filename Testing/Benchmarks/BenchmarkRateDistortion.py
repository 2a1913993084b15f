#!/usr/bin/env python3
"""Rate against distortion for per-frame mesh input, as volumetric-video codecs are measured.

Writes a take as per-frame meshes (dynamicpoints-sample --per-frame-mesh: each frame its own
connectivity, reconstructed from noisy samples, with a capture's defects in frame 0), then, in one
run and on one metric (each decoded frame against that frame's own mesh: D1 and D2 PSNR, peak =
the frame's diagonal, both directions, the worse kept; means over the frames and the worst frame):

  - the main job with no option (the detail layer at the level it chooses);
  - the main job with templates of each --sizes and no detail layer;
  - the main job with the detail layer at each --levels (over a template of
    --detail-template vertices, default 1000) and each --growths;
  - Google Draco coding each frame alone at each --draco quantisation (draco_encoder -qp N
    -cl 10, positions and faces; Debian's package draco), measured by BenchmarkMeshFidelity
    with the main job's own measure.

For each: bits per input vertex per frame (the whole file: for the main job the .dpz, for Draco
the sum of its frames), the detail layer's share, time per frame (the main job's median per
frame, tracking and detail; Draco's encoding and decoding), the main job's wall time and peak
resident memory. Then, for each Draco point, the main job's cheapest row that reaches its D1
PSNR, and the ratio of bits, or the highest D1 the main job reached.

    BenchmarkRateDistortion.py --bin BUILD/bin [--data DIR --sequence NAME | --sequence tube]
        [--sizes 1000,5000] [--levels 2,3] [--detail-template 1000] [--growths 10]
        [--draco 8,11,14] [--no-auto]
        [--mesh-vertices 20000] [--points 80000] [--noise 0.001] [--frames N] [--work DIR]
        [--reuse-input]
"""
import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import threading
import time


def parse():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--bin", required=True, help="folder of dynamicpoints and dynamicpoints-sample")
    p.add_argument("--data", default="", help="folder of the sequences (not needed for tube)")
    p.add_argument("--sequence", default="tube")
    p.add_argument("--sizes", default="1000,5000", help="template vertex counts, no detail layer")
    p.add_argument("--levels", default="2,3", help="detail levels of the detail rows")
    p.add_argument("--detail-template", type=int, default=1000,
                   help="template vertex count of the detail rows")
    p.add_argument("--growths", default="10", help="--fit-growth of the detail rows, percent")
    p.add_argument("--draco", default="8,11,14", help="draco_encoder -qp values ('' for none)")
    p.add_argument("--no-auto", action="store_true", help="no row of the main job's defaults")
    p.add_argument("--mesh-vertices", type=int, default=20000, help="vertices of each input mesh")
    p.add_argument("--points", type=int, default=80000, help="samples a mesh is made from")
    p.add_argument("--noise", type=float, default=0.001, help="share of the diagonal")
    p.add_argument("--frames", type=int, default=0, help="first N frames only (0: all)")
    p.add_argument("--work", default="rate-distortion")
    p.add_argument("--reuse-input", action="store_true",
                   help="keep the per-frame meshes an earlier run wrote in --work")
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


def run_measured(command):
    """Runs `command`, returning its stdout and peak resident memory (MiB) from wait4."""
    # communicate() would reap the child; wait4 reaps it instead, to read its own rusage.
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    stdout_chunks, stderr_chunks = [], []

    def drain(stream, chunks):
        for chunk in iter(lambda: stream.read(65536), b""):
            chunks.append(chunk)
    readers = [threading.Thread(target=drain, args=(process.stdout, stdout_chunks)),
               threading.Thread(target=drain, args=(process.stderr, stderr_chunks))]
    for r in readers:
        r.start()
    _, status, usage = os.wait4(process.pid, 0)
    for r in readers:
        r.join()
    out, err = b"".join(stdout_chunks).decode(), b"".join(stderr_chunks).decode()
    code = os.waitstatus_to_exitcode(status)
    if code != 0:
        sys.exit(f"failed ({code}): {' '.join(command)}\n{out}{err}")
    return out, usage.ru_maxrss / 1024


def write_input(a, folder):
    mesh = ["--mesh", "tube"] if a.sequence == "tube" else ["--mesh", os.path.join(a.data, a.sequence)]
    if a.sequence == "tube" and a.frames:
        mesh += ["--frames", str(a.frames)]
    run_measured([os.path.join(a.bin, "dynamicpoints-sample"), *mesh, "--points", str(a.points),
                  "--noise", str(a.noise), "--no-normals", "--per-frame-mesh",
                  str(a.mesh_vertices), "--mesh-defects", folder])
    if a.frames and a.sequence != "tube":
        names = sorted(f for f in os.listdir(folder) if f.endswith(".ply"))
        for name in names[a.frames:]:
            os.remove(os.path.join(folder, name))
        os.remove(os.path.join(folder, "points.series"))


HEADER = (f"{'row':<28} {'bits/in-vertex/frame':>20} {'(detail)':>8} {'D1 PSNR dB':>10} "
          f"{'D2 PSNR dB':>10} {'worst D1':>8} {'ms/frame':>8} {'job s':>6} {'peak MiB':>8}")


def row(name, bits, detail, d1, d2, worst, ms, job, peak):
    def f(v, w, p):
        return f"{v:>{w}.{p}f}" if v is not None else f"{'-':>{w}}"
    print(f"{name:<28} {f(bits, 20, 3)} {f(detail, 8, 3)} {f(d1, 10, 2)} {f(d2, 10, 2)} "
          f"{f(worst, 8, 2)} {f(ms, 8, 1)} {f(job, 6, 1)} {f(peak, 8, 0)}")
    sys.stdout.flush()


def main_job(a, folder, name, options):
    """One main-job row; returns (name, bits, d1)."""
    out = os.path.join(a.work, f"{a.sequence}-{name.replace(' ', '-').replace(',', '')}")
    _, peak = run_measured([os.path.join(a.bin, "dynamicpoints"), folder, "--output", out,
                            "--quiet", *options])
    with open(os.path.join(out, "report.json")) as f:
        report = json.load(f)
    m = report["compression"]["againstInputMeshes"]
    levels = report["detail"]["levels"]
    label = f"{name} ({report['template']['vertices']} v, {levels} lv)"
    row(label, m["bitsPerInputVertexFrame"], m.get("detailBitsPerInputVertexFrame", 0.0),
        m["d1PsnrDb"], m["d2PsnrDb"], m["worstD1PsnrDb"], report["medianMillisecondsPerFrame"],
        report["wallSeconds"], peak)
    return label, m["bitsPerInputVertexFrame"], m["d1PsnrDb"]


def draco(a, folder, qp):
    """Each frame coded alone by Draco at -qp `qp`; returns (name, bits, d1)."""
    encoder, decoder = shutil.which("draco_encoder"), shutil.which("draco_decoder")
    if not encoder or not decoder:
        sys.exit("draco_encoder / draco_decoder not found (Debian's package draco)")
    decoded = os.path.join(a.work, f"{a.sequence}-draco-{qp}")
    os.makedirs(decoded, exist_ok=True)
    frames = sorted(f for f in os.listdir(folder) if f.endswith(".ply"))
    total_bytes, vertices, ms = 0, 0, []
    for name in frames:
        coded = os.path.join(decoded, name + ".drc")
        started = time.perf_counter()
        run_measured([encoder, "-i", os.path.join(folder, name), "-o", coded, "-qp", str(qp),
                      "-cl", "10"])
        run_measured([decoder, "-i", coded, "-o", os.path.join(decoded, name)])
        ms.append(1000 * (time.perf_counter() - started))
        total_bytes += os.path.getsize(coded)
        with open(os.path.join(folder, name), "rb") as f:
            header = f.read(400).decode("latin-1")
        vertices += int(header.split("element vertex ")[1].split()[0])
    out, _ = run_measured([os.path.join(a.bin, "BenchmarkMeshFidelity"), decoded, folder])
    words = out.split()
    d1, worst, d2 = float(words[4]), float(words[7].rstrip(")")), float(words[10])
    bits = 8 * total_bytes / vertices
    row(f"Draco -qp {qp}", bits, None, d1, d2, worst, statistics.median(ms), None, None)
    return f"Draco -qp {qp}", bits, d1


def compare(main_rows, draco_rows):
    print("\nAt each Draco point, the main job's cheapest row that reaches its D1 PSNR:")
    best = max(main_rows, key=lambda r: r[2]) if main_rows else None
    for name, bits, d1 in draco_rows:
        reaching = [r for r in main_rows if r[2] >= d1]
        if reaching:
            r = min(reaching, key=lambda r: r[1])
            print(f"  {name} ({d1:.2f} dB, {bits:.3f} bits): {r[0]}, {r[2]:.2f} dB at "
                  f"{r[1]:.3f} bits: {bits / r[1]:.1f}x fewer bits")
        elif best:
            print(f"  {name} ({d1:.2f} dB, {bits:.3f} bits): not reached; the main job's highest "
                  f"D1 is {best[2]:.2f} dB ({best[0]})")


def main():
    a = parse()
    os.makedirs(a.work, exist_ok=True)
    folder = os.path.join(a.work, a.sequence + "-meshes")
    started = time.time()
    if not (a.reuse_input and os.path.isdir(folder) and os.listdir(folder)):
        write_input(a, folder)
    print(f"== {a.sequence} as per-frame meshes of about {a.mesh_vertices} vertices "
          f"({a.points} samples, noise {a.noise} of the diagonal, defects in frame 0), written "
          f"in {time.time() - started:.0f} s; {machine()}, {os.cpu_count()} threads")
    print(HEADER)
    main_rows, draco_rows = [], []
    if not a.no_auto:
        main_rows.append(main_job(a, folder, "main job, no option", []))
    for size in [int(s) for s in a.sizes.split(",") if s]:
        main_rows.append(main_job(a, folder, f"template {size}",
                                  ["--vertices", str(size), "--detail-levels", "0"]))
    for levels in [int(s) for s in a.levels.split(",") if s]:
        for growth in [s for s in a.growths.split(",") if s]:
            main_rows.append(main_job(a, folder, f"detail {levels}, growth {growth} %",
                                      ["--vertices", str(a.detail_template), "--detail-levels",
                                       str(levels), "--fit-growth", growth]))
    for qp in [int(s) for s in a.draco.split(",") if s]:
        draco_rows.append(draco(a, folder, qp))
    compare(main_rows, draco_rows)


if __name__ == "__main__":
    main()
