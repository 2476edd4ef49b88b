#!/usr/bin/env python3
"""How much the joint estimator's scoreboard rests on the OCV table's absolute level.

Copies configs/ to a temporary directory, moves every config's joint OCV table
(`joint.ocv_cell_voltage_v`) by each shift in millivolts per cell, scores both simulated
suites against it and prints one row per shift and suite. The simulated logs do not move
(the plant is the same); only what the monitor believes the rest voltage to be.

  python3 scripts/ocv-sensitivity.py [--battsim build/battsim] [--shifts-mv -5 -2 0 2 5]
"""
import argparse
import os
import statistics
import sys

from config_edit import score_edited

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def summarise(report):
    s = report["summary"]

    def col(key, field="median_abs"):
        v = s[key]["joint"]
        return v.get(field, v.get("count"))

    gaps = []
    for flight in report["flights"]:
        e = flight["estimators"]
        if "oracle" in e:
            gaps.append(abs(e["joint"]["remaining_time_error_pct"][1]) - abs(e["oracle"]["remaining_time_error_pct"][1]))
    return {
        "gap": (statistics.median(gaps), max(gaps)),
        "time20": col("remaining_time_20"),
        "time50": col("remaining_time_50"),
        "energy20": (col("remaining_energy_20"), col("remaining_energy_20", "worst")),
        "capacity20": col("capacity_20"),
        "warnings": (col("early_warnings"), s["early_warnings"]["joint"]["of"]),
        "false": col("false_warnings"),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--battsim", default=os.path.join(ROOT, "build", "battsim"))
    ap.add_argument("--shifts-mv", type=float, nargs="+", default=[-5, -2, 0, 2, 5])
    ap.add_argument("--suites", nargs="+", default=["scenarios", "scenarios-holdout"])
    args = ap.parse_args()
    if not os.access(args.battsim, os.X_OK):
        sys.exit(f"ocv-sensitivity: {args.battsim} is not an executable; build first or pass --battsim")

    print("| table shift (mV/cell) | suite | gap to the oracle at 20 %, median / largest (points) | remaining time at 20 %, 50 % | "
          "energy at 20 %, median / worst | capacity at 20 % | warnings in time | false warnings |")
    print("|---|---|---|---|---|---|---|---|")
    for shift_mv in args.shifts_mv:
        def shift(joint, shift_v=shift_mv / 1000.0):
            table = joint.get("ocv_cell_voltage_v")
            if table:
                joint["ocv_cell_voltage_v"] = [round(v + shift_v, 6) for v in table]
            return bool(table)
        try:
            for suite, report in score_edited(args.battsim, ROOT, shift, args.suites, "joint,oracle"):
                r = summarise(report)
                print(f"| {shift_mv:+g} | {suite} | {r['gap'][0]:.2f} / {r['gap'][1]:.1f} | {r['time20']:.2f}, {r['time50']:.2f} | "
                      f"{r['energy20'][0]:.2f} / {r['energy20'][1]:.1f} | {r['capacity20']:.2f} | "
                      f"{r['warnings'][0]}/{r['warnings'][1]} | {r['false']} |", flush=True)
        except RuntimeError as e:
            sys.exit(f"ocv-sensitivity: at {shift_mv:+g} mV: {e}")

if __name__ == "__main__":
    main()
