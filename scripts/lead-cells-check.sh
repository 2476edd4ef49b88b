#!/bin/sh
# The reference logger's lead cells (fifty-first session). Its last cell is read as INA226
# bus − INA3221 channel 3 and its cell 1 against the monitor's ground, so their short-lag
# resistance is not the cell's: `battsim calibrate --cell-leads` measures the share on the
# dissertation's four flights (configs/sim-4s.json, the logger's config with an OCV table),
# then on healthy flights of the lead-cell suite (configs/scenarios-lead-cells/, whose
# simulated INA3221 averages 105.6 ms as the logger's appears to; three seeds of their own,
# seed + 1,001,000 … 1,003,000, none a scored flight), and scores that suite.
# With --write, the real flights' calibration is written into sim-4s.json and its 1300/1800 mAh
# siblings (the same logger; only the three keys change). The reference-*.json configs stay the
# dissertation's own settings (reference-modified.json is the built-in config, which make-config
# scales to packs of any cell count), without it.
#
#   sh scripts/lead-cells-check.sh [--write]
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
battsim="$root/build/battsim"
data=${BATTSIM_DATA_DIR:-$root/../shared/data}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

echo "== the dissertation's flights 29, 30, 32, 34"
(cd "$data" && "$battsim" calibrate --cell-leads predictive-bms/flights/29.csv predictive-bms/flights/30.csv \
    predictive-bms/flights/32.csv predictive-bms/flights/34.csv -c "$root/configs/sim-4s.json" --json) >"$tmp/real.json"
python3 - "$tmp/real.json" "${1:-}" "$root/configs/sim-4s.json" "$root/configs/sim-4s-1300.json" "$root/configs/sim-4s-1800.json" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))
for f in c["flights"]:
    print("  %-28s %-11s cells %s mOhm: cell 1 %+.3f, last cell %+.3f" % (
        f["log"].rsplit("/", 1)[-1], f["cell_resistance_source"], [round(1000 * r, 2) for r in f["cell_resistance_ohm"]],
        f["first_cell_excess"], f["last_cell_excess"]))
keys = {k: c[k] for k in ("first_cell_lead_excess", "last_cell_lead_excess", "cell_lead_excess_sigma")}
print("  ->", json.dumps(keys))
if sys.argv[2] == "--write":
    for path in sys.argv[3:]:
        config = json.load(open(path))
        config.setdefault("joint", {}).update(keys)
        with open(path, "w") as out:
            json.dump(config, out, indent=2, ensure_ascii=False)
            out.write("\n")
PY

echo "== healthy flights of configs/scenarios-lead-cells/, seeds of their own"
logs=""
for scenario in "$root"/configs/scenarios-lead-cells/*healthy*.json; do
    name=$(basename "$scenario" .json)
    seed=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['seed'])" "$scenario")
    for k in 1 2 3; do
        "$battsim" simulate "$scenario" --seed $((seed + 1000000 + 1000 * k)) -o "$tmp/$name.$k.csv" >/dev/null
        logs="$logs $tmp/$name.$k.csv"
    done
done
# shellcheck disable=SC2086
"$battsim" calibrate --cell-leads $logs -c "$root/configs/sim-4s.json" | sed "s|$tmp/||"

echo "== battsim score configs/scenarios-lead-cells (4 copies)"
"$battsim" score -j2 --copies 4 --columns joint "$root/configs/scenarios-lead-cells" | grep -E "cell outlier|battsim score"
