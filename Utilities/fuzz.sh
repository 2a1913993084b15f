#!/usr/bin/env bash
# Fuzzes the engine's point-cloud readers and .dpz decoder (libFuzzer, ASan + UBSan): builds
# Testing/Fuzz with clang into build-fuzz/ (or $DP_FUZZ_BUILD) and runs each target for SECONDS
# (default 60) on a copy of its seed corpus (Testing/Fuzz/corpus/FORMAT, which also holds the
# inputs of past findings, replayed first), which grows there from run to run.
# Exits non-zero on the first finding; the input is left in the build's findings/.
#   bash Utilities/fuzz.sh [SECONDS] [FORMAT ...]      (formats: ply pcd xyz obj dpz)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
seconds="${1:-60}"
shift || true
formats=("$@")
[ ${#formats[@]} -gt 0 ] || formats=(ply pcd xyz obj dpz)
build="${DP_FUZZ_BUILD:-$root/build-fuzz}"
scratch=/dev/shm; [ -w "$scratch" ] || scratch="${TMPDIR:-/tmp}" # the input file, rewritten per run
command -v clang++ >/dev/null || apt-get install -y -qq --no-install-recommends clang >/dev/null
cmake -S "$root/Testing/Fuzz" -B "$build" -G Ninja -DCMAKE_CXX_COMPILER=clang++ >/dev/null
cmake --build "$build" | tail -1
mkdir -p "$build/findings"
for format in "${formats[@]}"; do
  corpus="$build/corpus/$format"
  mkdir -p "$corpus"
  cp -n "$root/Testing/Fuzz/corpus/$format/"* "$corpus/"
  echo "== fuzz_$format for ${seconds} s"
  status=0
  TMPDIR="$scratch" "$build/fuzz_$format" "$corpus" -max_total_time="$seconds" \
    -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$build/findings/${format}-" >"$build/$format.log" 2>&1 ||
    status=$?
  grep -E "^(stat::number_of_executed_units|stat::peak_rss|SUMMARY)|runtime error|ERROR:" \
    "$build/$format.log" || true
  if [ "$status" -ne 0 ]; then
    echo "fuzz_$format: finding (log $build/$format.log, input in $build/findings/)"
    exit 1
  fi
done
