#!/usr/bin/env bash
# DynamicPoints: install what the build needs (Debian bookworm, as root), build, and run.
#
#   bash Utilities/dp.sh main [ARGS...]   the main job (no ARGS: the built-in sample sequence);
#                                         builds only what it needs (it and the ParaView plugin)
#   bash Utilities/dp.sh test             the whole test suite (ctest), with the tools it uses
#   bash Utilities/dp.sh build            install what the build needs and build everything
#   bash Utilities/dp.sh install          install every Debian package (build and tests) only
#
# Idempotent: packages already installed are not fetched again, and an existing build
# folder is only brought up to date. Environment: DP_BUILD_DIR (default: build).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${DP_BUILD_DIR:-$root/build}"

# What the build and the main job need. The SDK is ParaView 5.11's (VTK 9.2 inside); the -dev
# libraries are the ones its CMake package looks for. Debian's libvtk9-dev cannot be installed
# beside it (Documentation/Development.md). OpenBLAS, serial (TBB has the cores), is the BLAS behind CHOLMOD's
# supernodal factorisation: Debian's reference BLAS made it slower than the simplicial one.
build_packages=(
  cmake ninja-build g++ pkg-config
  paraview paraview-dev python3-paraview python3-dev python3-numpy python3-mpi4py
  qtbase5-dev qttools5-dev libqt5svg5-dev libqt5x11extras5-dev libqt5opengl5-dev
  qtxmlpatterns5-dev-tools libopenmpi-dev openmpi-bin
  libdouble-conversion-dev libhdf5-openmpi-dev libnetcdf-dev libgdal-dev libexpat1-dev
  libfreetype-dev libgl2ps-dev libglew-dev libgl-dev libjpeg-dev liblz4-dev liblzma-dev
  libxml2-dev libpng-dev libtheora-dev libtiff-dev libx11-dev zlib1g-dev libutfcpp-dev
  libboost-dev libboost-iostreams-dev libavcodec-dev libavformat-dev libavutil-dev
  libswscale-dev
  libeigen3-dev libopenvdb-dev libtbb-dev libgtest-dev nlohmann-json3-dev libnanoflann-dev
  liblbfgs-dev libzstd-dev libtinygltf-dev libmeshoptimizer-dev libdraco-dev libmetis-dev
  libsuitesparse-dev libopenblas0-serial nodejs
)
# What only the tests use: clang (fuzzing, sanitizers), Open3D and SciPy (peers' results), the
# X server for the ParaView GUI and rendering tests with xdotool and xwd to drive and photograph
# the GUI, Blender, Google Draco (the rate-distortion benchmark's per-frame peer), Chromium and
# Firefox (the main job's page in real browsers).
test_packages=(
  clang python3-open3d python3-scipy xvfb xauth libgl1-mesa-dri xdotool x11-apps blender draco
  chromium firefox-esr
)
# From the npm registry: three.js for the main job's page (built into dynamicpoints); for the
# tests, the Khronos glTF validator, meshoptimizer's reference decoder (the version of Debian's
# libmeshoptimizer) and Playwright's browser driver (it drives Debian's Chromium; it downloads
# no browser).
node_main_tools=(three@0.147.0)
node_test_tools=(gltf-validator@2.0.0-dev.3.10 meshoptimizer@0.18.1 playwright-core@1.65.1)

# install_packages PACKAGE...: installs those not installed yet (one apt run).
install_packages() {
  local missing=()
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]})); then
    echo "== installing ${#missing[@]} Debian package(s): ${missing[*]}"
    if [[ $(id -u) -ne 0 ]]; then
      echo "error: installing packages needs root (run as root, or install them first)" >&2
      exit 1
    fi
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  fi
}

install_npm() {
  # npm comes with some nodejs builds and is Debian's package npm with others.
  if ! command -v npm >/dev/null; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends npm >/dev/null
  fi
}

install_test_tools() {
  install_packages "${build_packages[@]}" "${test_packages[@]}"
  install_npm
}

# install_node_tools PACKAGE@VERSION...: those not installed yet into $build/tools/node (npm).
install_node_tools() {
  local folder="$build/tools/node" missing=()
  for tool in "$@"; do
    grep -qxF "$tool" "$folder/.installed" 2>/dev/null || missing+=("$tool")
  done
  ((${#missing[@]})) || return 0
  echo "== installing ${missing[*]} (npm) in $folder"
  mkdir -p "$folder"
  npm install --prefix "$folder" --no-audit --no-fund --silent "${missing[@]}" >/dev/null
  printf '%s\n' "${missing[@]}" >>"$folder/.installed"
}

configure_project() {
  if [[ ! -f "$build/CMakeCache.txt" ]]; then
    echo "== configuring in $build"
    cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DPython3_EXECUTABLE=/usr/bin/python3 >/dev/null
  fi
}

# build_project [TARGET...]: configures (once) and builds the targets (default: everything).
build_project() {
  configure_project
  echo "== building${1:+ $*}"
  cmake --build "$build" -j "$(nproc)" ${1:+--target "$@"} -- --quiet
}

# What the main job needs: the program, and the ParaView plugin its state file loads.
main_targets() {
  echo dynamicpoints
  grep -q '^DYNAMICPOINTS_BUILD_PLUGIN:.*=ON' "$build/CMakeCache.txt" 2>/dev/null &&
    echo DynamicPoints
  true
}

command="${1:-}"
shift || true
case "$command" in
  main)
    install_packages "${build_packages[@]}"
    install_npm
    install_node_tools "${node_main_tools[@]}"
    configure_project
    # shellcheck disable=SC2046 # one word per target
    build_project $(main_targets)
    exec "$build/bin/dynamicpoints" "$@"
    ;;
  test)
    install_test_tools
    install_node_tools "${node_main_tools[@]}" "${node_test_tools[@]}"
    build_project
    cd "$build"
    exec ctest --output-on-failure -j "$(nproc)" "$@"
    ;;
  build)
    install_packages "${build_packages[@]}"
    install_npm
    install_node_tools "${node_main_tools[@]}"
    build_project
    ;;
  install)
    install_test_tools
    ;;
  *)
    sed -n '2,10p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
    [[ "$command" == "-h" || "$command" == "--help" ]] && exit 0
    exit 2
    ;;
esac
