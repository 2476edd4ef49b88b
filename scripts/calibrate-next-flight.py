#!/usr/bin/env python3
"""Scores `battsim calibrate` on a simulated suite: each pack's previous flight sets its shape.

For every scenario of SUITE the flight is simulated once as written (the pack's previous
flight), `battsim calibrate` picks the health filter's slow polarisation share from it, and the
pack's next flight (the same scenario with seed + 7919, i.e. copy 1 of `battsim score --copies`)
is scored twice: with the monitor config as it is, and with the calibrated one. Prints the joint
column of both and the shares chosen. Standard library only.

    python3 scripts/calibrate-next-flight.py configs/scenarios-rest-polarisation
    python3 scripts/calibrate-next-flight.py configs/scenarios configs/scenarios-holdout
    python3 scripts/calibrate-next-flight.py --shift-other-filters tracking,verdict configs/scenarios-rest-polarisation
"""
import argparse
import collections
import glob
import json
import os
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COPY_SEED_STEP = 7919  # battsim score --copies: copy k adds 7919 k to the seed


def run(args):
    try:
        r = subprocess.run(args, capture_output=True, text=True)
    except OSError as e:
        sys.exit("calibrate-next-flight: cannot run %s (%s); build first or pass --battsim" % (args[0], e.strerror))
    if r.returncode != 0:
        sys.exit("calibrate-next-flight: %s failed (%d): %s" % (" ".join(args), r.returncode, r.stderr.strip()))
    return r.stdout


def figures(summary):
    g = lambda k: summary[k]["joint"]
    return ("remaining time at 20 %% %.2f, gap to oracle %.2f / %.1f, energy at 20 %% %.2f, "
            "capacity at 20 %% %.2f / %.1f, warned %d/%d, false %d (%d undegraded)" % (
                g("remaining_time_20")["median_abs"], g("remaining_time_20_above_oracle")["median"],
                g("remaining_time_20_above_oracle")["max"], g("remaining_energy_20")["median_abs"],
                g("capacity_20")["median_abs"], g("capacity_20")["worst"], g("early_warnings")["count"],
                g("early_warnings")["of"], g("false_warnings")["count"], g("false_warnings_undegraded")["count"]))


def shift_other_filters(config_path, shift, others):
    """Moves the tracking and/or verdict filter's slow share by the health filter's change
    (an experiment: `battsim calibrate` itself moves the health filter's alone)."""
    if not others or shift == 0:
        return
    config = json.load(open(config_path))
    joint = config["joint"]
    for name in others:
        section = joint if name == "tracking" else joint["verdict_filter"]
        section["polarisation_slow_share"] = min(1.0, max(0.0, section["polarisation_slow_share"] + shift))
    json.dump(config, open(config_path, "w"), indent=1)


def score_suite(battsim, suite, others):
    tmp = tempfile.mkdtemp(prefix="calnext-")
    try:
        plain, calibrated, configs = (os.path.join(tmp, d) for d in ("plain", "calibrated", "configs"))
        for d in (plain, calibrated, configs):
            os.makedirs(d)
        shares = collections.Counter()
        for path in sorted(glob.glob(os.path.join(suite, "*.json"))):
            scenario = json.load(open(path))
            name = scenario["name"]
            monitor = os.path.normpath(os.path.join(os.path.dirname(path), scenario["monitor_config"]))
            log = os.path.join(tmp, name + ".csv")
            run([battsim, "simulate", path, "-o", log, "--truth", os.path.join(tmp, name + ".truth.json")])
            cal_cfg = os.path.join(configs, name + ".json")
            r = subprocess.run([battsim, "calibrate", log, "-c", monitor, "-o", cal_cfg, "--json"],
                               capture_output=True, text=True)  # battsim ran already: simulate above
            if r.returncode == 1:  # no rest to read (a current-offset sensor never rests): as configured
                cal_cfg = monitor
                shares["no rest"] += 1
            elif r.returncode != 0:
                sys.exit("calibrate-next-flight: battsim calibrate %s: %s" % (log, r.stderr.strip()))
            else:
                report = json.loads(r.stdout)
                shares[report["chosen_slow_share"]] += 1
                shift_other_filters(cal_cfg, report["chosen_slow_share"] - report["configured_slow_share"], others)
            nxt = dict(scenario, seed=scenario["seed"] + COPY_SEED_STEP)
            json.dump(dict(nxt, monitor_config=monitor), open(os.path.join(plain, name + ".json"), "w"))
            json.dump(dict(nxt, monitor_config=cal_cfg), open(os.path.join(calibrated, name + ".json"), "w"))
        out = {}
        for label, d in (("as configured", plain), ("calibrated", calibrated)):
            o = os.path.join(tmp, label.replace(" ", "-") + ".json")
            run([battsim, "score", "-j2", "--json", "--columns", "oracle,joint", d, "-o", o])
            out[label] = json.load(open(o))["summary"]
        print("%s (next flights, %d):" % (os.path.relpath(suite, ROOT), sum(shares.values())))
        for label, s in out.items():
            print("  %-13s %s" % (label, figures(s)))
        print("  shares chosen: %s" % ", ".join("%s x%d" % (k, v) for k, v in sorted(shares.items(), key=str)))
    finally:
        shutil.rmtree(tmp)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("suites", nargs="+", help="scenario directories")
    ap.add_argument("--battsim", default=os.path.join(ROOT, "build", "battsim"))
    ap.add_argument("--shift-other-filters", default="",
                    help="comma-separated: tracking, verdict; move their slow shares by the health filter's change too")
    a = ap.parse_args()
    others = [x for x in a.shift_other_filters.split(",") if x]
    for x in others:
        if x not in ("tracking", "verdict"):
            ap.error("--shift-other-filters: expected tracking or verdict, found %r" % x)
    for suite in a.suites:
        if not os.path.isdir(suite):
            ap.error("%s: not a directory of scenarios" % suite)
        score_suite(a.battsim, os.path.abspath(suite), others)


if __name__ == "__main__":
    main()
