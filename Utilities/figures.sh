#!/usr/bin/env bash
# DynamicPoints: prints today's headline figures (the README's "Today's figures"), each figure
# followed by the command that printed it, the machine (lscpu's model name, its thread count) and
# the date. Builds what it needs first (bash Utilities/dp.sh build: idempotent), and installs what
# the page's figures need when missing (Debian's chromium; playwright-core from npm, the version
# Utilities/dp.sh names, into the build's tools/node). Every command's whole output is kept in the
# scratch folder; a run on a loaded machine gives slower times, never other accuracies.
#
#   bash Utilities/figures.sh [--quick]
#
#   --quick   a few minutes: one tracking row (jumping, decimated template, clean), the main job
#             on the built-in sample (as it is and with --detail-levels 0), decoding time a frame
#             (the codec on horse-gallop, the built-in take's .dpz), the page's load time and
#             frames a second (both built-in takes)
#   (none)    the full set (its parts' times add up to about half an hour on 2 cores): the
#             tracking table without and with colour (24 rows), the main job on the built-in
#             sample and on the jumping capture (--detail-levels 0 and as it is), the chicken's
#             compression where DP_DATA holds it (chickenCrossing/), decoding, each take's page
#
# Environment: DP_BUILD_DIR (default: build), DP_DATA (the sequences; default: shared/data beside
# the repository), DP_FIGURES_DIR (scratch; default: BUILD/figures).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${DP_BUILD_DIR:-$root/build}"
data="${DP_DATA:-$(dirname "$root")/shared/data}"
scratch="${DP_FIGURES_DIR:-$build/figures}"

quick=0
case "${1:-}" in
  --quick) quick=1 ;;
  "") ;;
  *)
    sed -n '2,21p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
    [[ "$1" == "-h" || "$1" == "--help" ]] && exit 0
    exit 2
    ;;
esac

bash "$root/Utilities/dp.sh" build >&2
cd "$root"
bin="${build#"$root"/}/bin"
mkdir -p "$scratch"
machine="$(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc --all) threads"
today="$(date -u +%Y-%m-%d)"
commit="$(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
git diff --quiet HEAD 2>/dev/null || commit="$commit + uncommitted changes"

# The figures' parser: MODE FILE... prints one figure a line (Testing/Benchmarks' outputs and the
# main job's report.json).
parse_py=$(cat <<'PY'
import json, re, sys
mode, args = sys.argv[1], sys.argv[2:]
if mode == "tracker":
    log, suffix = args
    row = re.compile(r"^(\S+)\s+(\d+)\s+(\S+)\s+([\d.]+)\s+\(\s*[\d.]+%\)\s+([\d.]+)\s+[\d.]+\s+"
                     r"[\d.]+\s+([\d.]+)\s+\(\s*\d+\)\s+([\d.]+)x\s+([\d.]+)$")
    sequence, current = None, None
    for line in open(log):
        m = re.match(r"== (\S+): (\d+) of", line)
        if m:
            sequence, frames = m.group(1), m.group(2)
        m = row.match(line.strip())
        if m:
            kind, verts, cond, rms, largest, worst, jitter, ms = m.groups()
            current = dict(name=f"{sequence} ({frames} frames), {kind} {verts} v, {cond}{suffix}",
                           rms=rms, largest=largest, worst=worst, jitter=jitter, ms=ms)
        m = re.search(r"([\d.]+) mm along the surface", line)
        if m and current:
            current['surface'] = m.group(1)
        m = re.search(r"retries on (\d+) frames\), (\d+) frames flagged", line)
        if m and current:
            c = current
            print(f"tracking {c['name']}: vertex RMS {c['rms']} mm ({c['surface']} along the "
                  f"surface), worst frame uncovered {c['worst']} %, jitter {c['jitter']}x, "
                  f"{m.group(2)} frames flagged, {float(c['ms']):.0f} ms a frame")
            current = None
elif mode == "main":
    folder, seconds, label = args
    r = json.load(open(folder + "/report.json"))
    c, d = r['compression'], r.get("detail", {})
    stages = r.get("medianStageSecondsPerFrame", {})
    detail = (f"{d['levels']} detail levels ({d['fineVertices']} vertices)"
              if d.get("levels") else "no detail layer")
    detail_ms = (f" ({1000 * stages['detailSeconds']:.0f} ms the detail)"
                 if d.get("levels") and "detailSeconds" in stages else "")
    print(f"main job, {label}: {float(seconds):.1f} s for {r['framesTracked']} frames, "
          f"median {r['medianMillisecondsPerFrame']:.0f} ms a frame{detail_ms}, "
          f"{len(r['framesFailed'])} flagged; template {r['template']['vertices']} v, {detail}")
    share = (f", the detail layer {c['detail']['bytes']} of them" if "detail" in c else "")
    print(f"main job, {label}, compressed: {c['Bytes']} bytes{share}, "
          f"{c['InputPointsOverFile']:.0f}x smaller than the input points; the tracked mesh "
          f"{c['Components']} components, {c['BitsPerVertexFrame']:.2f} bits per vertex per frame")
elif mode == "codec":
    log, = args
    name = None
    for line in open(log):
        m = re.match(r"== (\S+): (\d+) vertices, (\d+) frames", line)
        if m:
            name = f"{m.group(1)} ({m.group(2)} v, {m.group(3)} frames)"
        m = re.match(r"\s*([\d.]+) (\S+)\s+full codec\s+(\d+)\s+([\d.]+)", line)
        if m:
            kg, layout, comp, bits = m.groups()
        m = re.search(r"decoding: ([\d.]+) ms a frame", line)
        if m:
            print(f"codec, {name}, KG {kg} %, {layout}: {bits} bits per vertex per frame "
                  f"({comp} components); decoding {m.group(1)} ms a frame (one thread)")
elif mode == "decoding":
    log, = args
    for line in open(log):
        if line.startswith("== "):
            name = "/".join(line.split()[1].rstrip(":").split("/")[-2:])
        m = re.match(r"(the detail layer's fine mesh|the tracked mesh)[^:]*: (\d+) frames of (\d+) "
                     r"vertices; the file decoded in ([\d.]+) ms, a frame given in ([\d.]+) ms; "
                     r"decoding: ([\d.]+) ms a frame", line)
        if m:
            what, frames, vertices, whole, frame, total = m.groups()
            print(f"decoding {name}, {what.split(' ', 1)[1]} ({vertices} v, {frames} frames): "
                  f"{total} ms a frame (the file {whole} ms, then {frame} ms a frame)")
elif mode == "page":
    log, = args
    for line in open(log):
        if line.startswith("== "):
            page, rest = line[3:].strip().split(": ", 1)
            page = "/".join(page.split("/")[-2:])
        m = re.match(r"load: ([\d.]+) s \(median of (\d+)", line)
        if m:
            print(f"page {page} ({rest}): loads in {m.group(1)} s (median of {m.group(2)})")
        m = re.match(r"drawing: ([\d.]+) frames a second, ([\d.]+) ms a frame", line)
        if m:
            print(f"page {page}: draws {m.group(1)} frames a second ({m.group(2)} ms a frame)")
PY
)

# run LOG COMMAND...: runs COMMAND, its output into LOG; stops the script with its end on failure.
run() {
  local log="$1"
  shift
  echo "== $*" >&2
  if ! "$@" >"$log" 2>&1; then
    tail -20 "$log" >&2
    echo "figures.sh: failed: $* (the whole output: $log)" >&2
    exit 1
  fi
}

# report COMMAND_TEXT < FIGURES: each figure line, then the command, the machine and the date.
report() {
  local line
  while IFS= read -r line; do
    # shellcheck disable=SC2016 # the backquotes are the output's (Markdown)
    printf '%s\n    by `%s`; %s; %s\n' "$line" "$1" "$machine" "$today"
  done
}

# The tracking table's rows (BenchmarkTracker), without colour and, with --colour, with it.
tracking() {
  local options=("$@") suffix
  for colour in "" --colour; do
    [[ $quick == 1 && -n $colour ]] && continue
    local command=("$bin/BenchmarkTracker" --data "$data" "${options[@]}" --seed 1
      ${colour:+"$colour"})
    local log="$scratch/tracker${colour}.log"
    run "$log" "${command[@]}"
    suffix="${colour:+, colour}"
    python3 -c "$parse_py" tracker "$log" "$suffix" | report "${command[*]}"
  done
}

# main_job NAME LABEL [OPTIONS] [INPUT]: the main job into SCRATCH/NAME, timed as a whole.
main_job() {
  local name="$1" label="$2"
  shift 2
  local out="$scratch/$name" command
  rm -rf "$out"
  command=("$bin/dynamicpoints" --output "$out" --quiet "$@")
  local start
  start=$(date +%s%N)
  run "$scratch/$name.log" "${command[@]}"
  python3 -c "$parse_py" main "$out" "$((($(date +%s%N) - start) / 1000000))e-3" "$label" |
    report "${command[*]}"
}

# The page's figures need Chromium and playwright-core; installed here when missing.
page_tools() {
  local playwright
  playwright="$(grep -o 'playwright-core@[0-9.]*' "$root/Utilities/dp.sh" | head -1)"
  if ! dpkg-query -W -f='${Status}' chromium 2>/dev/null | grep -q "install ok installed"; then
    if [[ $(id -u) -ne 0 ]]; then
      echo "the page's figures need Debian's chromium (as root: apt-get install chromium)" >&2
      return 1
    fi
    echo "== installing chromium (apt)" >&2
    export DEBIAN_FRONTEND=noninteractive
    local install=(apt-get install -y -qq --no-install-recommends chromium)
    "${install[@]}" >/dev/null 2>&1 || { apt-get update -qq && "${install[@]}" >/dev/null; } ||
      return 1
  fi
  if ! grep -qxF "$playwright" "$build/tools/node/.installed" 2>/dev/null; then
    echo "== installing $playwright (npm) in $build/tools/node" >&2
    npm install --prefix "$build/tools/node" --no-audit --no-fund --silent "$playwright" \
      >/dev/null || return 1
    echo "$playwright" >>"$build/tools/node/.installed"
  fi
}

set_name="full set"
[[ $quick == 0 ]] || set_name=quick
echo "DynamicPoints figures ($set_name): $machine; $today; commit $commit;" \
  "Release build in ${build#"$root"/}"

# Tracking.
if [[ -d "$data/jumping" ]]; then
  if [[ $quick == 1 ]]; then
    tracking --sequence jumping --template decimated --condition clean
  else
    tracking --sequence jumping,horse-gallop,horse-collapse --template decimated,reconstructed \
      --condition clean,noisy
  fi
else
  echo "tracking: skipped, no sequences in $data (DP_DATA)"
fi

# The main job on the built-in sample (the tube, generated first: its time included).
main_job tube "built-in tube"
main_job tube-levels0 "built-in tube, --detail-levels 0" --detail-levels 0
dpz=("$scratch/tube/tracked.dpz" "$scratch/tube-levels0/tracked.dpz")
pages=("$scratch/tube/view.html" "$scratch/tube-levels0/view.html")

# The main job on the jumping capture (the issue's: 0.1 % noise, two holes moving every frame, no
# normals, 150 frames).
if [[ $quick == 0 && -d "$data/jumping" ]]; then
  capture="$scratch/jumping-capture"
  command=("$bin/dynamicpoints-sample" --mesh "$data/jumping" --noise 0.001 --holes 2
    --moving-holes --no-normals "$capture")
  rm -rf "$capture"
  run "$scratch/jumping-capture.log" "${command[@]}"
  main_job jumping-levels0 "jumping capture, --detail-levels 0" --detail-levels 0 "$capture"
  main_job jumping "jumping capture" "$capture"
  dpz+=("$scratch/jumping-levels0/tracked.dpz" "$scratch/jumping/tracked.dpz")
  pages+=("$scratch/jumping-levels0/view.html" "$scratch/jumping/view.html")
fi

# The codec alone (BenchmarkCompression): horse-gallop, and the chicken crossing where it is.
codec() {
  local command=("$bin/BenchmarkCompression" --data "$data" --sequence "$1" --target "$2"
    --layout trajectories --repeats 1)
  run "$scratch/codec-$1.log" "${command[@]}"
  python3 -c "$parse_py" codec "$scratch/codec-$1.log" | report "${command[*]}"
}
if [[ -d "$data/horse-gallop" ]]; then
  codec horse-gallop 0.2
fi
if [[ $quick == 0 ]]; then
  if [[ -d "$data/chickenCrossing" ]]; then
    codec chickenCrossing 0.1
  else
    echo "codec, chicken crossing: skipped, no $data/chickenCrossing (not shipped:" \
      "github.com/CraGL/Hyperspectral-Inverse-Skinning, models/chickenCrossing)"
  fi
fi

# Decoding a frame of the main job's .dpz files, as vtkCompressedSequenceReader gives them.
command=(env PYTHONPATH="${build#"$root"/}/lib/python3/dist-packages" /usr/bin/python3
  Testing/Benchmarks/BenchmarkDecoding.py "${dpz[@]}")
run "$scratch/decoding.log" "${command[@]}"
python3 -c "$parse_py" decoding "$scratch/decoding.log" | report "${command[*]}"

# The page: load time and frames a second in headless Chromium.
if page_tools; then
  command=(/usr/bin/python3 Testing/Benchmarks/BenchmarkPage.py --node-tools "$build/tools/node"
    "${pages[@]}")
  run "$scratch/page.log" "${command[@]}"
  python3 -c "$parse_py" page "$scratch/page.log" | report "${command[*]}"
else
  echo "page: skipped (no Chromium)"
fi
echo "(whole outputs: $scratch)"
