#!/usr/bin/env python3
"""What `make-config --chemistry li-ion` changes on real Li-ion data (fiftieth session).

The Samsung INR18650-30Q constant-current discharges of the shared lab data (1C to 4C; the
C/10 one is where the Li-ion table was read, so it is left out), each replayed as the single
cell it is (1S 3000 mAh) and as a 6S2P pack (the cell's voltage x 6 and current x 2: a
long-range pack's 12-24 A), through the config `make-config` writes with the LiPo curve and
with --chemistry li-ion, joint estimator. Prints the capacity at the end against the charge
the discharge drew to 2.5 V (the data README's), and the warnings raised.

    python3 scripts/li-ion-check.py [--battsim build/battsim]
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.path.join(os.path.dirname(ROOT), "shared", "data", "samsung-30q")
RATES = ["1C", "2C", "3C", "4C"]


def drawn_ah(path):
    """Charge drawn (trapezoid over the discharging samples), as the data README counts it."""
    total, last = 0.0, None
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            t, i = float(row["time_s"]), -float(row["current_a"])
            if last is not None:
                total += 0.5 * (max(i, 0.0) + max(last[1], 0.0)) * (t - last[0]) / 3600.0
            last = (t, i)
    return total


def as_pack(src, dst, series, parallel):
    with open(src, newline="") as f, open(dst, "w", newline="") as g:
        w = csv.writer(g)
        w.writerow(["time_s", "voltage_v", "current_a", "temperature_c"])
        for row in csv.DictReader(f):
            w.writerow([row["time_s"], "%.4f" % (float(row["voltage_v"]) * series),
                        "%.4f" % (-float(row["current_a"]) * parallel), row["cell_temperature_c"]])


def run(battsim, args):
    p = subprocess.run([battsim] + args, capture_output=True, text=True)
    if p.returncode not in (0, 1):
        sys.exit("li-ion-check: battsim %s: exit %d: %s" % (" ".join(args), p.returncode, p.stderr.strip()))
    return p.stdout


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--battsim", default=os.path.join(ROOT, "build", "battsim"))
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        print("| log | pack | true Ah | LiPo curve: Ah at the end, warnings | --chemistry li-ion: Ah, warnings |")
        print("|---|---|---|---|---|")
        for rate in RATES:
            src = os.path.join(DATA, "Q30_S001_%s.csv" % rate)
            truth = drawn_ah(src)
            for series, parallel in ((1, 1), (6, 2)):
                log = os.path.join(tmp, "%s-%ds%dp.csv" % (rate, series, parallel))
                as_pack(src, log, series, parallel)
                cells = []
                for chem in ("lipo", "li-ion"):
                    cfg = os.path.join(tmp, "%s-%ds.json" % (chem, series))
                    # The cutoff at the discharges' own 2.5 V per cell, so both run to the same end.
                    run(a.battsim, ["make-config", "--cells", str(series), "--capacity-mah", str(3000 * parallel),
                                    "--cutoff-v", str(2.5 * series), "--chemistry", chem, "-o", cfg])
                    s = json.loads(run(a.battsim, ["replay", log, "-c", cfg, "--estimator", "joint", "--json"]))
                    cap = s["flight"]["capacity_ah"]
                    warned = ",".join(sorted({w["name"] for w in s.get("warnings", []) if w["name"] != "sensor_fault"})) or "none"
                    cells.append("%.3f (%+.1f %%), %s" % (cap["final"], 100.0 * (cap["final"] / (truth * parallel) - 1.0), warned))
                print("| Q30_S001_%s | %dS%dP | %.3f | %s | %s |" % (rate, series, parallel, truth * parallel, cells[0], cells[1]))


if __name__ == "__main__":
    main()
