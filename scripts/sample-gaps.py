#!/usr/bin/env python3
"""Logging gaps: how long they are in a log, and what charge a simulated one hides.

    python3 scripts/sample-gaps.py logs LOG... [-c CONFIG]
        Per log (through `battsim replay --series`): the median sample interval, the
        longest interval in flight (current above 3 A) and every interval over 0.75 s
        (the joint estimator's joint.max_sample_gap_s).

    python3 scripts/sample-gaps.py charge [--scenario S] [--seeds K]
        Simulates copy 0 … K−1 of the scenario (seed + 7919·k, as `battsim score --copies`)
        and, for every flying gap over 0.75 s, compares the true charge (the truth series,
        integrated at its 1 s resolution) with the charge counted at the sample after the
        gap and at the mean of the currents either side; prints the RMS of both and the
        RMS of the latter's error over (the larger current × the gap), the scatter
        joint.gap_charge_sigma_fraction stands for (docs/estimator.md, fifteenth session).

Standard library only; BATTSIM names the binary (default build/battsim).
"""
import argparse
import csv
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BATTSIM = os.environ.get("BATTSIM", os.path.join(ROOT, "build", "battsim"))
GAP_S = 0.75


def run(args):
    r = subprocess.run([BATTSIM] + args, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("sample-gaps: battsim %s failed: %s" % (" ".join(args), r.stderr.strip()))


def logs(paths, config):
    with tempfile.TemporaryDirectory() as tmp:
        for path in paths:
            series = os.path.join(tmp, "series.csv")
            args = ["replay", path, "--series", series] + (["-c", config] if config else [])
            run(args)
            with open(series) as f:
                rows = list(csv.DictReader(f))
            t = [float(r["time_s"]) for r in rows]
            i = [float(r["current_a"]) for r in rows]
            dt = [b - a for a, b in zip(t, t[1:])]
            if not dt:
                print("%s: fewer than two samples" % path)
                continue
            flying = [d for d, cur in zip(dt, i[1:]) if cur > 3.0]
            over = [(round(t[k], 1), round(d, 2)) for k, d in enumerate(dt) if d > GAP_S]
            print("%s: %d samples, median interval %.3f s, longest in flight %s, over %.2f s: %d %s" % (
                path, len(t), statistics.median(dt), "%.3f s" % max(flying) if flying else "-", GAP_S,
                len(over), over[:8]))


def charge(scenario, seeds):
    with open(scenario) as f:
        base_seed = json.load(f).get("seed", 1)
    rect, trap, ratio = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(seeds):
            log = os.path.join(tmp, "copy%d.csv" % k)
            run(["simulate", scenario, "--seed", str(base_seed + 7919 * k), "--format", "raw", "-o", log])
            with open(os.path.join(tmp, "copy%d.truth.json" % k)) as f:
                series = json.load(f)["series"]
            ts, cur = series["time_s"], series["current_a"]

            def true_as(a, b):  # the truth's current held over each of its intervals
                s = 0.0
                for j in range(len(ts) - 1):
                    lo, hi = max(a, ts[j]), min(b, ts[j + 1])
                    if hi > lo:
                        s += cur[j] * (hi - lo)
                return s

            t, i = [], []
            with open(log) as f:
                for line in f:
                    p = line.strip().split(",")
                    if len(p) >= 7 and p[0].isdigit():  # raw: ms, pack V, 4 cells, mA, shunt mV
                        t.append(float(p[0]) / 1000.0)
                        i.append(float(p[6]) / 1000.0)
            for j in range(1, len(t)):
                dt = t[j] - t[j - 1]
                if dt > GAP_S and max(i[j], i[j - 1]) > 3.0:
                    q = true_as(t[j - 1], t[j])
                    rect.append(q - i[j] * dt)
                    e = q - 0.5 * (i[j] + i[j - 1]) * dt
                    trap.append(e)
                    ratio.append(e / (max(abs(i[j]), abs(i[j - 1])) * dt))
    if not trap:
        sys.exit("sample-gaps: no flying gap over %.2f s in %d copies" % (GAP_S, seeds))
    rms = lambda v: math.sqrt(sum(x * x for x in v) / len(v))
    print("%d gaps over %.2f s in %d copies of %s" % (len(trap), GAP_S, seeds, scenario))
    print("charge at the sample after the gap: error RMS %.1f As, largest %.1f As" % (rms(rect), max(rect, key=abs)))
    print("charge at the mean of the currents either side: error RMS %.1f As, largest %.1f As" % (rms(trap), max(trap, key=abs)))
    print("  its error over (larger current x gap): RMS %.3f" % rms(ratio))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="mode", required=True)
    lg = sub.add_parser("logs")
    lg.add_argument("paths", nargs="+")
    lg.add_argument("-c", "--config")
    ch = sub.add_parser("charge")
    ch.add_argument("--scenario", default=os.path.join(ROOT, "configs/scenarios/4s-racing-fault-missed-samples.json"))
    ch.add_argument("--seeds", type=int, default=6)
    a = ap.parse_args()
    if a.mode == "logs":
        logs(a.paths, a.config)
    else:
        charge(a.scenario, a.seeds)


if __name__ == "__main__":
    main()
