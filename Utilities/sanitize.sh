#!/usr/bin/env bash
# The C++ test suite (engine and filters) built with AddressSanitizer and UndefinedBehaviorSanitizer
# and run: any memory error, leak or undefined behaviour fails it.
#   bash Utilities/sanitize.sh [BUILD_DIR]      (default: build-sanitize/ beside build/)
# The test suite runs it once (ctest: sanitizers.cxx_suite). The Python tests are left out: the
# interpreter and VTK are not instrumented, and the C++ tests reach the same engine code.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$root/build-sanitize}"
flags="-O1 -g -fno-omit-frame-pointer -fsanitize=address,undefined -fno-sanitize-recover=all"
bash "$root/Utilities/dp.sh" install # the libraries, when missing
if [[ ! -f "$build/CMakeCache.txt" ]]; then
  echo "== configuring the sanitizer build in $build"
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$flags" -DCMAKE_C_FLAGS_RELWITHDEBINFO="$flags" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DDYNAMICPOINTS_WRAP_PYTHON=OFF >/dev/null
fi
echo "== building the tests with ASan + UBSan"
SECONDS=0
cmake --build "$build" -j "$(nproc)" --target TestEngine TestFilters -- --quiet
echo "built in $SECONDS s"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:halt_on_error=1:strict_string_checks=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
SECONDS=0
for suite in TestEngine TestFilters; do
  echo "== $suite under ASan + UBSan"
  "$build/bin/$suite" --gtest_brief=1
done
echo "sanitizer suite passed in $SECONDS s"
