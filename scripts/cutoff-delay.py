#!/usr/bin/env python3
"""How far past the loaded-voltage crossing a flight really ends, as the solver sees it.

The simulator's truth judges its cutoff on a low-passed pack voltage (scenario
`truth.cutoff_filter_s`, 5 s), as a pilot's voltage alarm does, so a flight runs on past
the moment the loaded voltage first crosses the minimum. The joint estimator's solver adds
`joint.cutoff_delay_s` after the crossing. This script copies configs/, sets that delay in
every config with a `joint` section, scores both simulated suites with the oracle, the
diagnostic `solve-truth` column (the solver fed the true pack: the model's own error) and the
joint estimator, and prints one row per delay and suite. Standard library only.

  python3 scripts/cutoff-delay.py [--battsim build/battsim] [--delays 0 2.5 5 7.5] [-j 2]
"""
import argparse
import os
import statistics
import sys

from config_edit import score_edited

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SUITES = ["scenarios", "scenarios-holdout"]


def summarise(report):
    rows = {}
    for col in ("solve-truth", "joint"):
        energy, gaps = [], []
        for flight in report["flights"]:
            e = flight["estimators"]
            energy.append(e[col]["remaining_energy_error_20_pct"])
            gaps.append(abs(e[col]["remaining_time_error_pct"][1]) - abs(e["oracle"]["remaining_time_error_pct"][1]))
        energy = [x for x in energy if x is not None]
        rows[col] = {
            "energy_abs": statistics.median(abs(x) for x in energy),
            "energy_signed": statistics.median(energy),
            "gap": statistics.median(gaps),
            "gap_largest": max(gaps),
        }
    s = report["summary"]
    rows["joint"]["warnings"] = (s["early_warnings"]["joint"]["count"], s["early_warnings"]["joint"]["of"])
    rows["joint"]["false"] = s["false_warnings"]["joint"]["count"]
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--battsim", default=os.path.join(ROOT, "build", "battsim"))
    ap.add_argument("--delays", type=float, nargs="+", default=[0.0, 2.5, 5.0, 7.5])
    ap.add_argument("-j", "--jobs", type=int, default=2)
    a = ap.parse_args()
    print("| delay (s) | suite | solve-truth energy at 20 %, median \\|err\\| / signed | solve-truth gap to the oracle | "
          "joint energy at 20 %, median \\|err\\| / signed | joint gap, median / largest | warnings, false |")
    print("|---|---|---|---|---|---|---|")
    for delay in a.delays:
        def put(joint):
            joint["cutoff_delay_s"] = delay
            return True
        try:
            for suite, report in score_edited(a.battsim, ROOT, put, SUITES, "oracle,solve-truth,joint", a.jobs):
                m = summarise(report)
                t, j = m["solve-truth"], m["joint"]
                print(f"| {delay:g} | {suite} | {t['energy_abs']:.2f} / {t['energy_signed']:+.2f} | {t['gap']:+.2f} | "
                      f"{j['energy_abs']:.2f} / {j['energy_signed']:+.2f} | {j['gap']:.2f} / {j['gap_largest']:.1f} | "
                      f"{j['warnings'][0]}/{j['warnings'][1]}, {j['false']} |", flush=True)
        except RuntimeError as e:
            print(f"cutoff-delay: at {delay:g} s: {e}", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
