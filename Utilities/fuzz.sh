#!/usr/bin/env bash
# Fuzzes everything users feed files to (libFuzzer, ASan + UBSan): the point-cloud readers, .series
# files, template meshes, a template tracked for a frame, the .dpz decoder. Builds Testing/Fuzz
# with clang into build-fuzz/ (or $DP_FUZZ_BUILD) and runs each target for SECONDS (default 60),
# or for DP_FUZZ_RUNS executions when that is set, on a copy of its seed corpus
# (Testing/Fuzz/corpus/NAME, which also holds the inputs of past findings, replayed first); the
# copy grows there from run to run. Exits non-zero on the first finding; the input is left in the
# build's findings/. Memory is held tight: the readers' budget (DP_MEMORY_BUDGET) is 128 MiB, and
# a process resident over 512 MiB, or a single allocation over 256 MiB, is a finding (what a
# reader allocates is bounded by its input, and the inputs are small). Each run's executions
# and coverage are added to $build/runs.tsv (target, date, runs, edges, features).
#   bash Utilities/fuzz.sh [SECONDS] [TARGET ...]
#   targets: ply pcd xyz obj drc series template_ply template_obj track dpz (default: all)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
seconds="${1:-60}"
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(ply pcd xyz obj drc series template_ply template_obj track dpz)
build="${DP_FUZZ_BUILD:-$root/build-fuzz}"
scratch=/dev/shm; [ -w "$scratch" ] || scratch="${TMPDIR:-/tmp}" # the input file, rewritten per run
limit=(-max_total_time="$seconds") span="$seconds s"
[ -z "${DP_FUZZ_RUNS:-}" ] || { limit=(-runs="$DP_FUZZ_RUNS"); span="$DP_FUZZ_RUNS executions"; }
bash "$root/Utilities/dp.sh" install # clang and the engine's libraries, when missing
cmake -S "$root/Testing/Fuzz" -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ >/dev/null
cmake --build "$build" | tail -1
mkdir -p "$build/findings"
for target in "${targets[@]}"; do
  seeds="$root/Testing/Fuzz/corpus/$target"
  [ "$target" != track ] || seeds="$root/Testing/Fuzz/corpus/template_ply"
  corpus="$build/corpus/$target"
  mkdir -p "$corpus"
  cp -n "$seeds/"* "$corpus/"
  echo "== fuzz_$target for $span"
  status=0
  start=$(date +%s)
  # ASan's quarantine of freed blocks held small, so that the resident limit measures the readers.
  TMPDIR="$scratch" DP_MEMORY_BUDGET=128M ASAN_OPTIONS="quarantine_size_mb=64" \
    "$build/fuzz_$target" "$corpus" "${limit[@]}" \
    -timeout=10 -rss_limit_mb=512 -malloc_limit_mb=256 -print_final_stats=1 \
    -artifact_prefix="$build/findings/${target}-" >"$build/$target.log" 2>&1 ||
    status=$?
  grep -E "^(stat::number_of_executed_units|stat::peak_rss|SUMMARY)|runtime error|ERROR:" \
    "$build/$target.log" || true
  runs=$(grep -oE '^stat::number_of_executed_units: [0-9]+' "$build/$target.log" | grep -oE '[0-9]+$' || echo 0)
  coverage=$(grep -oE 'cov: [0-9]+ ft: [0-9]+' "$build/$target.log" | tail -1)
  echo "   $(($(date +%s) - start)) s; $runs runs; coverage: $coverage; corpus: $(ls "$corpus" | wc -l) inputs"
  printf '%s\t%s\t%s\t%s\n' "$target" "$(date -u +%F)" "$runs" \
    "$(echo "$coverage" | awk '{print $2 "\t" $4}')" >>"$build/runs.tsv"
  if [ "$status" -ne 0 ]; then
    echo "fuzz_$target: finding (log $build/$target.log, input in $build/findings/)"
    exit 1
  fi
done
echo "no finding in ${#targets[@]} targets"
