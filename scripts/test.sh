#!/bin/sh
# Runs every test: the unit, golden, firmware and CLI suites (ctest), then the checks that
# need more than one build: the core cross-compiled for the ESP8266 within its size
# budget, the test suite again under ASan+UBSan (clang), and bounded libFuzzer runs from
# that same build.
# The README's test command and .ci/run both call this. BATTSIM_QUICK=1 skips the
# sanitizer build and the fuzzers (for a fast local loop).
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
build="$root/build"
jobs=$(nproc)
# An explicit BATTSIM_DATA_DIR wins over the data dir cached by an earlier configure.
# Without the shared data the [data] tests are left out with a warning (an error if CI=true).
set -- ${BATTSIM_DATA_DIR:+"-DBATTSIM_DATA_DIR=$BATTSIM_DATA_DIR"}

echo "== build and ctest"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$build" -j"$jobs"
(cd "$build" && ctest --output-on-failure -j"$jobs")

echo "== ESP8266 cross-compile and size budget"
sh "$root/scripts/cross-compile.sh" --header "$build/firmware/generated/battsim_config.h"
# The fitted config's header too: model extensions compiled for the target as constants.
sh "$root/scripts/cross-compile.sh" --header "$build/firmware/generated-fitted/battsim_config.h" >/dev/null
# ... and the joint estimator's (configs/sim-4s.json with its OCV table).
sh "$root/scripts/cross-compile.sh" --header "$build/firmware/generated-joint/battsim_config.h" >/dev/null

if [ "${BATTSIM_QUICK:-0}" = 1 ]; then exit 0; fi

# One clang build with ASan+UBSan (optimised, with debug info) serves the test suite and the
# fuzz harnesses. Until the thirty-fourth session a gcc -O0 sanitizer build ran the suite and
# fuzz.sh made a third build of its own: the two took most of CI's time (the sanitized suite
# alone 630 s at -O0, 152 s at -O2).
san="$root/build-san"
echo "== ASan+UBSan build (clang) of the test suite and the fuzz harnesses"
# Line tables only (clang's -gline-tables-only) instead of full debug info: a sanitizer's
# report still names file and line; the heaviest file compiled in 43 s instead of 60.
# The test programs' own files at -O0 (the code they test stays at -O2): in the forty-third
# session `cmake --build build-san --target unit_tests cli_tests`, configured with and without
# this flag, took 208 s instead of 422 s on two cores. Their run
# time is less clear: 268 and 244 s summed per test case against 277 and 268 s at -O2 in one
# comparison, but the fresh-clone CI's sanitized ctest took 403 s against 281 s the session
# before; the whole CI went from 1,904 to 1,743 s.
CC=clang CXX=clang++ cmake -S "$root" -B "$san" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -gline-tables-only -DNDEBUG" -DBATTSIM_TEST_CODE_FLAGS=-O0 \
  -DBATTSIM_SANITIZE=ON -DBATTSIM_FUZZ=ON "$@" >/dev/null
cmake --build "$san" -j"$jobs"
(cd "$san" && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 ctest --output-on-failure -j"$jobs")

echo "== fuzzing (bounded)"
# The three harnesses run side by side: 70 s on two cores is the 45 core-seconds each had
# when they ran one after another.
BATTSIM_FUZZ_BUILD="$san" FUZZ_SECONDS=${FUZZ_SECONDS:-70} sh "$root/scripts/fuzz.sh"
