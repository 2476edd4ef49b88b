#!/usr/bin/env python3
"""What the joint estimator reads through a radio's telemetry log (README, "Radio telemetry logs").

Scores a simulated suite (`battsim score --copies N --json`) as the monitor's own logger writes
it and through an EdgeTX radio log (0.1 V and 0.1 A steps, one row per --interval seconds),
then, with --settings, through the radio log again with joint-estimator settings merged into
every monitor config (a scratch copy of configs/; the committed files are not touched), and
prints the joint column's figures for each run:

    python3 scripts/radio-log-check.py [--suite scenarios] [--copies 4]
    python3 scripts/radio-log-check.py --interval 0.05           # the steps alone, at the logger's rate
    python3 scripts/radio-log-check.py --settings '{"solver_steps_per_update": 33}' \\
                                       --settings '{"health_filter": {"ocv_soc_sigma": 0.03}}'

Standard library only; about 20 s a run on two cores with four copies.
"""
import argparse
import glob
import json
import os
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def merge(into, extra):
    for k, v in extra.items():
        if isinstance(v, dict):
            merge(into.setdefault(k, {}), v)
        else:
            into[k] = v


def scratch_suite(tmp, suite, interval, settings):
    """configs/*.json (settings merged into `joint`) and the suite's scenarios, logged as edgetx."""
    os.makedirs(os.path.join(tmp, "s"))
    for f in glob.glob(os.path.join(ROOT, "configs", "*.json")):
        with open(f) as fh:
            d = json.load(fh)
        if d.get("schema") == "battsim.config":
            merge(d.setdefault("joint", {}), settings)
        with open(os.path.join(tmp, os.path.basename(f)), "w") as fh:
            json.dump(d, fh, indent=1)
    for f in glob.glob(os.path.join(ROOT, "configs", suite, "*.json")):
        with open(f) as fh:
            d = json.load(fh)
        d["log"] = {"format": "edgetx", "interval_s": interval}  # monitor_config "../X.json" finds the copies
        with open(os.path.join(tmp, "s", os.path.basename(f)), "w") as fh:
            json.dump(d, fh, indent=1)
    return os.path.join(tmp, "s")


def score(battsim, suite_dir, copies, extra=()):
    out = subprocess.run([battsim, "score", "-j2", "--copies", str(copies), "--json", suite_dir, *extra],
                         cwd=ROOT, check=True, capture_output=True, text=True).stdout
    return json.loads(out)["summary"]


def row(s):
    j = lambda k: s[k]["joint"]
    gap = j("remaining_time_20_above_oracle")
    return (f"{j('remaining_time_20')['median_abs']:.2f} | {gap['median']:.2f} / {gap['max']:.1f} | "
            f"{j('remaining_energy_20')['median_abs']:.2f} | "
            f"{j('capacity_20')['median_abs']:.2f} / {j('capacity_20')['worst']:.1f} | "
            f"{j('capacity_end')['median_abs']:.2f} | "
            f"{j('resistance_20')['median_abs']:.2f} / {j('resistance_20')['worst']:.1f} | "
            f"{j('early_warnings')['count']}/{j('early_warnings')['of']} | "
            f"{j('false_warnings')['count']} ({j('false_warnings_undegraded')['count']})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--battsim", default=os.path.join(ROOT, "build", "battsim"))
    ap.add_argument("--suite", default="scenarios", help="suite directory under configs/")
    ap.add_argument("--copies", type=int, default=4)
    ap.add_argument("--interval", type=float, default=0.2, help="the radio's log interval, s")
    ap.add_argument("--settings", action="append", default=[],
                    help="JSON object merged into every config's joint section; one more run each")
    a = ap.parse_args()
    if not os.path.exists(a.battsim):
        sys.exit(f"radio-log-check: {a.battsim} not found; build first (sh scripts/setup.sh)")
    print("| run | remaining time at 20 % | gap to the oracle, median / largest | energy at 20 % | "
          "capacity at 20 %, median / worst | capacity at the end | resistance at 20 %, median / worst | "
          "warned in time | false warnings (undegraded) |")
    print("|---|---|---|---|---|---|---|---|---|")
    suite_dir = os.path.join(ROOT, "configs", a.suite)
    print(f"| own logger | {row(score(a.battsim, suite_dir, a.copies))} |")
    for label, settings in [("radio log", {})] + [(s, json.loads(s)) for s in a.settings]:
        tmp = tempfile.mkdtemp(prefix="battsim-radio-")
        try:
            radio = scratch_suite(tmp, a.suite, a.interval, settings)
            name = f"radio log every {a.interval:g} s" + ("" if not settings else f", {label}")
            print(f"| {name} | {row(score(a.battsim, radio, a.copies))} |")
        finally:
            shutil.rmtree(tmp)


if __name__ == "__main__":
    main()
