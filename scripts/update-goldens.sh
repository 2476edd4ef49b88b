#!/bin/sh
# Regenerates the committed golden summaries (tests/golden/) from the shared flights.
# Run after an intended change of the monitor's numbers, and say why in the commit.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${BATTSIM:-$root/build/battsim}
data=${BATTSIM_DATA_DIR:-$root/../shared/data}
[ -d "$data" ] || { echo "update-goldens: shared data not found at $data; set BATTSIM_DATA_DIR" >&2; exit 2; }
for set in modified original; do
  out=$root/tests/golden/predictive-bms-$set
  mkdir -p "$out"
  for f in 29 30 32 34; do
    # Run from the data dir so the recorded input path is the same on every machine.
    (cd "$data" && "$bin" replay "predictive-bms/flights/$f.csv" -c "$root/configs/reference-$set.json" \
        --summary "$out/$f.json")
  done
done
out=$root/tests/golden/predictive-bms-joint
mkdir -p "$out"
for f in 29 30 32 34; do
  (cd "$data" && "$bin" replay "predictive-bms/flights/$f.csv" -c "$root/configs/sim-4s.json" --estimator joint \
      --summary "$out/$f.json")
done
# The scoreboards: every column on both simulated suites, the last-cell set, the
# rest-polarisation stress suite, the small and the large craft, the lead-cell set and the tuning suite through a radio log, an ArduPilot and a
# PX4 log (scenario paths
# are relative to the repo).
mkdir -p "$root/tests/golden/score"
for suite in scenarios scenarios-holdout scenarios-last-cell scenarios-rest-polarisation scenarios-small scenarios-large scenarios-lead-cells; do
  (cd "$root" && "$bin" score --json -j2 "configs/$suite" -o "tests/golden/score/$suite.json")
done
for format in edgetx dataflash ulog; do
  (cd "$root" && "$bin" score --json -j2 --log-format $format configs/scenarios -o tests/golden/score/scenarios-$format.json)
done
echo "goldens written under $root/tests/golden/"
