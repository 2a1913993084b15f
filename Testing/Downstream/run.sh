#!/usr/bin/env bash
# Installs the DynamicPoints build into a scratch prefix, builds Testing/Downstream against it
# with find_package(DynamicPoints), and runs what it built on a generated sequence.
#   run.sh BUILD_DIR SOURCE_DIR SCRATCH_DIR
set -euo pipefail
build="$1" source="$2" scratch="$3"
rm -rf "$scratch"
mkdir -p "$scratch"
cmake --install "$build" --prefix "$scratch/prefix" >/dev/null
cmake -S "$source/Testing/Downstream" -B "$scratch/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$scratch/prefix" -DEXAMPLE_SOURCE="$source/Examples/Cxx/TrackAndCompress.cxx" \
  >/dev/null
cmake --build "$scratch/build" -- --quiet
"$scratch/build/EngineOnly"
# The installed sampler makes the input; the downstream program tracks and compresses it.
"$scratch/prefix/bin/dynamicpoints-sample" --frames 5 --points 3000 "$scratch/seq" >/dev/null
"$scratch/build/TrackAndCompress" "$scratch/seq/points.series" "$scratch/out" 300
test -s "$scratch/out/tracked.dpz"
test -s "$scratch/out/tracked.glb"
test -s "$scratch/out/frame_0004.vtp"
echo "downstream project built and ran against $scratch/prefix"
