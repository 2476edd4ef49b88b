#!/bin/sh
# Runs every test: the unit, golden and CLI suites (ctest), then the checks that need
# more than the compiler (regression against committed goldens, the firmware's size
# budget). The README's test command and .ci/run both call this.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
build="$root/build"

cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" -j"$(nproc)"
cd "$build"
ctest --output-on-failure -j"$(nproc)"
