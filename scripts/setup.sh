#!/bin/sh
# Sets a fresh Debian (12+) machine up for battsim: installs the Debian packages it
# builds with, then configures and builds into build/. Nothing is downloaded besides
# Debian packages; nothing is vendored.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)

SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi

PACKAGES="build-essential cmake pkg-config
  libcli11-dev libfccp-dev nlohmann-json3-dev libeigen3-dev catch2
  libgnuplot-iostream-dev gnuplot-nox libboost-iostreams-dev libboost-system-dev libboost-filesystem-dev"
# Extra tools the full test run uses (cross-compiler, sanitizers, fuzzers, benchmarks), and
# python3 for the measurement scripts the docs quote (standard library only), and capsh
# (libcap2-bin) for the test of a directory root may not read.
if [ "${BATTSIM_MINIMAL:-0}" != 1 ]; then
  PACKAGES="$PACKAGES clang libclang-rt-14-dev gcc-xtensa-lx106 picolibc-xtensa-lx106-elf valgrind libbenchmark-dev python3 libcap2-bin"
fi

missing=""
for p in $PACKAGES; do
  dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"
done
if [ -n "$missing" ]; then
  echo "setup: installing$missing"
  $SUDO apt-get update -qq
  # shellcheck disable=SC2086
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends $missing >/dev/null
fi

# As in scripts/test.sh: an explicit BATTSIM_DATA_DIR wins over a cached one.
set -- ${BATTSIM_DATA_DIR:+"-DBATTSIM_DATA_DIR=$BATTSIM_DATA_DIR"}
cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$root/build" -j"$(nproc)"
echo "setup: built $root/build/battsim"
