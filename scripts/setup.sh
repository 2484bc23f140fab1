#!/usr/bin/env bash
# Installs what Free-Init needs on Debian bookworm (idempotent: quick when all is there) and builds
# it into ./build. Used by run_demo.sh and run_tests.sh; safe to run on its own.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(build-essential cmake ccache libeigen3-dev libceres-dev libgtest-dev libgmock-dev
          libbenchmark-dev libopencv-dev libmrpt-dev mrpt-apps
          libegl1 libegl-mesa0 libgl1-mesa-dri
          librosbag-dev libsensor-msgs-dev zlib1g-dev
          libzstd-dev liblz4-dev libsqlite3-dev)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] installing: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi

BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-2}
export CCACHE_DIR=${CCACHE_DIR:-$HOME/.ccache}
# Hash paths relative to the checkout, so a fresh clone elsewhere (CI) reuses the cache.
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$PWD}
export CCACHE_NOHASHDIR=1
# Warnings are errors here: this is the compiler (Debian bookworm's GCC 12) the code is checked
# with, and the demo, the tests and CI then share one configuration (and one compiler cache).
# FREEINIT_CMAKE_ARGS: more configure options.
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DFREEINIT_WERROR=ON ${FREEINIT_CMAKE_ARGS:-} \
  >/dev/null
cmake --build "$BUILD_DIR" -j"$JOBS"
