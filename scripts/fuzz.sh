#!/bin/sh
# Builds the libFuzzer harnesses with clang (ASan+UBSan) and runs each for a bounded time,
# seeded with the shared real logs and the committed regression inputs. A crash fails the
# run and leaves the input in <build>/crashes/: add it to tests/fuzz/regressions/.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
# BATTSIM_FUZZ_BUILD: a clang build configured with BATTSIM_FUZZ=ON to reuse (test.sh's
# sanitizer build); by default a build of its own.
build="${BATTSIM_FUZZ_BUILD:-$root/build-fuzz}"
seconds=${FUZZ_SECONDS:-60}
data=${BATTSIM_DATA_DIR:-$root/../shared/data}

# As in scripts/test.sh: an explicit BATTSIM_DATA_DIR wins over a cached one.
set -- ${BATTSIM_DATA_DIR:+"-DBATTSIM_DATA_DIR=$BATTSIM_DATA_DIR"}
if [ -z "${BATTSIM_FUZZ_BUILD:-}" ]; then
  CC=clang CXX=clang++ cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBATTSIM_FUZZ=ON "$@" >/dev/null
fi
cmake --build "$build" -j"$(nproc)" --target fuzz_reader fuzz_monitor fuzz_documents

corpus="$build/corpus"
mkdir -p "$corpus/reader" "$corpus/monitor" "$corpus/documents" "$build/crashes"
# Seeds: small real logs of every format (not copied into the repository), when the shared
# data is there; the committed seeds and regressions always.
if [ ! -d "$data" ]; then
  echo "fuzz: shared data not found at $data (set BATTSIM_DATA_DIR); its real-log seeds skipped"
fi
for f in "$data/px4/test.ulg" "$data/ardupilot/robert_lefebvre_octo_PM.log" "$root/tests/fuzz/seeds/"*; do
  [ -f "$f" ] && cp "$f" "$corpus/reader/" || true
done
if [ -f "$data/predictive-bms/flights/30.csv" ]; then head -c 4000 "$data/predictive-bms/flights/30.csv" > "$corpus/reader/raw.csv"; fi
if [ -f "$data/ardupilot/log171.bin" ]; then head -c 20000 "$data/ardupilot/log171.bin" > "$corpus/reader/df.bin"; fi
if [ -d "$root/tests/fuzz/regressions" ]; then cp "$root"/tests/fuzz/regressions/* "$corpus/reader/" 2>/dev/null || true; fi

# Documents: the first byte picks the reader (0 config, 1 scenario, 2 manifest, 3 table).
seed_doc() { { printf "$1"; cat "$2"; } > "$corpus/documents/$3"; }
seed_doc '\000' "$root/configs/sim-4s.json" config.json
seed_doc '\000' "$root/configs/reference-modified.json" config-ref.json
seed_doc '\001' "$root/configs/scenarios/3s-hover-healthy.json" scenario.json
seed_doc '\002' "$root/configs/manifests/predictive-bms.json" manifest.json
printf '\003{"schema": "battsim.batch", "version": 1, "inputs": {"count": 1, "digest": "d"}, "shard": null, "rows": []}' \
  > "$corpus/documents/table.json"

rm -f "$build"/fuzz_*.rc
# The three run side by side, so on two cores each gets about two thirds of a core for the
# whole time (one after another they had taken three times as long).
for h in reader monitor documents; do
  echo "fuzz: $h for ${seconds}s"
  ( rc=0
    "$build/tests/fuzz_$h" "$corpus/$h" -max_total_time="$seconds" -max_len=65536 -timeout=10 \
      -artifact_prefix="$build/crashes/$h-" -print_final_stats=1 2>"$build/fuzz_$h.log" || rc=$?
    echo $rc > "$build/fuzz_$h.rc" ) &
done
wait
status=0
for h in reader monitor documents; do
  if [ "$(cat "$build/fuzz_$h.rc")" != 0 ]; then
    echo "fuzz: $h FAILED; see $build/fuzz_$h.log and $build/crashes/"
    tail -40 "$build/fuzz_$h.log"
    status=1
  else
    echo "fuzz: $h: $(grep -E "stat::number_of_executed_units" "$build/fuzz_$h.log" | tail -1)"
    grep -E "cov:" "$build/fuzz_$h.log" | tail -1
  fi
done
exit $status
