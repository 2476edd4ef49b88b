#!/bin/sh
# What `battsim replay --config-out` does for a current-sensor offset: on each simulated
# offset flight (the tuning and held-out suites', four seeds each, copy k adding 7919 k to the
# seed as `battsim score --copies` does) the offset injected, the offset the joint estimator
# learnt on the ground, and the charge counted over the log against the truth's, before and
# through the written config. Needs build/battsim.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/build/battsim"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

echo "| scenario | copy | injected A | learnt A | charge counted vs truth, before → after | fault after | capacity Ah before → after (truth) |"
echo "|---|--:|--:|--:|---|---|---|"
for sc in "$root/configs/scenarios/3s-racing-fault-current-offset.json" \
          "$root/configs/scenarios/4s-racing-fault-current-offset.json" \
          "$root/configs/scenarios-holdout/ho-4s-racing-fault-current-offset.json"; do
  config=$(python3 -c "import json,os,sys; s=json.load(open(sys.argv[1])); print(os.path.normpath(os.path.join(os.path.dirname(sys.argv[1]), s['monitor_config'])))" "$sc")
  seed0=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['seed'])" "$sc")
  for k in 0 1 2 3; do
    "$bin" simulate "$sc" --seed $((seed0 + 7919 * k)) -o "$tmp/f.csv" > /dev/null
    "$bin" replay "$tmp/f.csv" -c "$config" --estimator joint --json > "$tmp/before.json"
    "$bin" replay "$tmp/f.csv" -c "$config" --estimator joint --config-out "$tmp/fixed.json" > /dev/null 2>&1
    "$bin" replay "$tmp/f.csv" -c "$tmp/fixed.json" --estimator joint --json > "$tmp/after.json"
    python3 - "$sc" "$k" "$tmp" <<'EOF'
import json, os, sys
sc, k, tmp = sys.argv[1:4]
before, after = (json.load(open(os.path.join(tmp, n))) for n in ("before.json", "after.json"))
truth = json.load(open(os.path.join(tmp, "f.truth.json")))
charge_ah = truth["flight"]["log_charge_ah"]

def counted_pct(s):  # the count over the log (less the charge read as missing at the start) against the truth's
    return 100.0 * ((s["consumed"]["ah"] - 1e-3 * s["initial_state"]["consumed_mah"]) / charge_ah - 1.0)

def fault(s):
    return next((w for w in s["warnings"] if w["name"] == "sensor_fault"), None)

f = fault(before)
learnt = f.get("current_offset_a") if f else None
print("| %s | %s | %.2f | %s | %+.1f %% → %+.1f %% | %s | %.3f → %.3f (%.3f) |" % (
    os.path.basename(sc)[:-5], k, truth["scenario"]["sensor"]["faults"]["current_offset_a"],
    "%.3f" % learnt if learnt is not None else "none", counted_pct(before), counted_pct(after),
    ", ".join(fault(after)["cause"]) if fault(after) else "none",
    before["flight"]["capacity_ah"]["final"], after["flight"]["capacity_ah"]["final"], truth["pack"]["capacity_ah"]))
EOF
  done
done

# How much of the offset a rest learns: the 4S flight (1.5 A) with longer and shorter rests
# before its take-off (the suite's is 60 s).
echo
echo "| rest before take-off s | learnt A (of 1.50) |"
echo "|--:|--:|"
for idle in 30 60 120 240; do
  python3 - "$root/configs/scenarios/4s-racing-fault-current-offset.json" "$idle" "$tmp/rest.json" <<'EOF'
import json, os, sys
path, idle, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
s = json.load(open(path))
s["profile"]["idle_before_s"] = idle
s["monitor_config"] = os.path.normpath(os.path.join(os.path.dirname(path), s["monitor_config"]))
json.dump(s, open(out, "w"))
EOF
  "$bin" simulate "$tmp/rest.json" -o "$tmp/rest.csv" > /dev/null
  "$bin" replay "$tmp/rest.csv" -c "$root/configs/sim-4s.json" --estimator joint --json > "$tmp/rest-summary.json"
  python3 - "$idle" "$tmp/rest-summary.json" <<'EOF'
import json, sys
s = json.load(open(sys.argv[2]))
w = next((w for w in s["warnings"] if w["name"] == "sensor_fault"), None)
print("| %s | %s |" % (sys.argv[1], "%.3f" % w["current_offset_a"] if w and "current_offset_a" in w else "not a fault"))
EOF
done
