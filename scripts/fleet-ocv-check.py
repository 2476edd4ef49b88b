#!/usr/bin/env python3
"""How good is an OCV table stitched from a fleet's ordinary flights (`battsim fit-ocv`)?

1. Simulates the fleet of configs/scenarios-fleet-ocv (14 flights of the simulator's 4S pack
   model, each its own seed, taking off at 100 % down to 35 %), stitches a table from them
   starting from the config's model curve (`--ignore-table`), and prints it against the
   plant's own rest curve and the bench table of configs/sim-4s.json (read off a simulated
   C/5 discharge, scripts/suite-ocv-tables.py).
2. Scores the tuning and held-out suites (`battsim score --copies N`) three ways: sim-4s.json
   with its bench table (as committed), with the stitched table, and with no table (the model
   curve); only sim-4s.json changes, so the figures are also given for its flights alone.
3. With the shared data present: fits the dissertation's flights 30 and 32 (which all take
   off full: nothing to stitch, and the report says so), then stitches the CMU Matrice 100
   fleet's odd flights and reports the voltage error on the even ones, before (the config's
   estimated curve) and after, and what the joint monitor then reads on the even flights.

    python3 scripts/fleet-ocv-check.py [--copies 4] [--build build] [--data ../shared/data]

Standard library only; about two minutes on two cores.
"""
import argparse
import csv
import glob
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The simulator's cell rest curve (src/host/sim/ocv.cpp, generic_lipo), every 5 % of SOC.
PLANT_OCV = [3.300, 3.550, 3.650, 3.690, 3.715, 3.735, 3.750, 3.765, 3.780, 3.795, 3.810,
             3.830, 3.850, 3.875, 3.900, 3.930, 3.960, 3.995, 4.035, 4.090, 4.200]
CMU = ["--time-col", "time", "--time-unit", "s", "--voltage-col", "battery_voltage",
       "--current-col", "battery_current", "--current-unit", "A"]


def run(cmd, **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        sys.exit(f"fleet-ocv-check: {' '.join(cmd[:3])} ... failed ({r.returncode}): {r.stderr.strip()}")
    return r.stdout


def monitor_configs(suite_dir):
    m = {}
    for f in glob.glob(os.path.join(suite_dir, "*.json")):
        d = json.load(open(f))
        if d.get("schema") == "battsim.scenario":
            m[d["name"]] = os.path.basename(d["monitor_config"])
    return m


def figures(score, configs, only=None):
    flights = [f for f in score["flights"] if only is None or configs[f["name"].split("@")[0]] == only]

    def med(key, idx=None):
        v = []
        for f in flights:
            x = f["estimators"]["joint"][key]
            x = x if idx is None else x[idx]
            if x is not None:
                v.append(abs(x))
        return f"{statistics.median(v):.2f} / {max(v):.1f}"

    short = [f for f in flights if f["short_flight"]]
    undegraded = [f for f in flights if not f["degraded"]]
    return [str(len(flights)), med("remaining_time_error_pct", 1), med("remaining_time_error_pct", 2),
            med("remaining_energy_error_20_pct"), med("capacity_error_20_pct"), med("capacity_error_end_pct"),
            f"{sum(f['estimators']['joint']['warned_in_time'] for f in short)}/{len(short)}",
            f"{sum(1 for f in undegraded if f['estimators']['joint']['false_warnings'])}/{len(undegraded)}"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--copies", type=int, default=4)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--data", default=os.environ.get("BATTSIM_DATA_DIR", os.path.join(ROOT, "..", "shared", "data")))
    a = ap.parse_args()
    battsim = os.path.join(a.build, "battsim")
    if not os.access(battsim, os.X_OK):
        sys.exit(f"fleet-ocv-check: {battsim} not found; build first (sh scripts/setup.sh)")
    tmp = tempfile.mkdtemp(prefix="fleet-ocv-")
    try:
        logs = os.path.join(tmp, "logs")
        os.makedirs(logs)
        run([battsim, "simulate", os.path.join(ROOT, "configs", "scenarios-fleet-ocv"), "--out-dir", logs])
        fleet = sorted(glob.glob(os.path.join(logs, "*.csv")))
        report = json.loads(run([battsim, "fit-ocv", *fleet, "-c", os.path.join(ROOT, "configs", "sim-4s.json"),
                                 "--ignore-table", "--json"]))
        table = report["ocv_cell_voltage_v"]["fitted"]
        bench = json.load(open(os.path.join(ROOT, "configs", "sim-4s.json")))["joint"]["ocv_cell_voltage_v"]
        print(f"Stitched from {len(fleet)} simulated flights (SOC span {report['soc_span'][0]:.2f}..1.00, slow "
              f"polarisation {report['polarisation_time_s']['slow']:.0f} s); per cell, mV against the plant's rest curve:\n")
        print("| SOC | " + " | ".join(f"{j * 5}" for j in range(21)) + " |")
        print("|---|" + "---|" * 21)
        print("| stitched | " + " | ".join(f"{1000 * (table[j] - PLANT_OCV[j]):+.0f}" for j in range(21)) + " |")
        print("| bench C/5 | " + " | ".join(f"{1000 * (bench[j] - PLANT_OCV[j]):+.0f}" for j in range(21)) + " |")
        rms = report["rms_v_per_cell"]
        print(f"\nfit error per cell: model curve {1000 * rms['config_curve']:.1f} mV, stitched {1000 * rms['fitted']:.1f} mV\n")

        header = ["table", "suite", "flights", "remaining time at 20 %", "at 50 %", "energy at 20 %",
                  "capacity at 20 %", "at the end", "short flights warned in time", "false warnings, undegraded"]
        rows = []
        for variant in ("bench (committed)", "stitched", "none (model curve)"):
            cfg_dir = os.path.join(tmp, "configs-" + variant.split()[0])
            shutil.copytree(os.path.join(ROOT, "configs"), cfg_dir)
            path = os.path.join(cfg_dir, "sim-4s.json")
            cfg = json.load(open(path))
            if variant.startswith("stitched"):
                cfg["joint"]["ocv_cell_voltage_v"] = [round(v, 4) for v in table]
            elif variant.startswith("none"):
                cfg["joint"].pop("ocv_cell_voltage_v", None)
            json.dump(cfg, open(path, "w"), indent=2)
            for suite in ("scenarios", "scenarios-holdout"):
                score = json.loads(run([battsim, "score", "-j2", "--copies", str(a.copies), "--json",
                                        os.path.join(cfg_dir, suite)]))
                configs = monitor_configs(os.path.join(cfg_dir, suite))
                rows.append([variant, suite] + figures(score, configs))
                rows.append([variant, suite + " (sim-4s flights)"] + figures(score, configs, "sim-4s.json"))
        print(f"Scoreboard, {a.copies} copies, joint estimator (median / worst |error| %):\n")
        print("| " + " | ".join(header) + " |")
        print("|" + "---|" * len(header))
        for r in rows:
            print("| " + " | ".join(r) + " |")

        pbms = os.path.join(a.data, "predictive-bms", "flights")
        if os.path.isdir(pbms):
            p = json.loads(run([battsim, "fit-ocv", os.path.join(pbms, "30.csv"), os.path.join(pbms, "32.csv"), "--test",
                                os.path.join(pbms, "29.csv"), os.path.join(pbms, "34.csv"), "-c",
                                os.path.join(ROOT, "configs", "sim-4s.json"), "--json"]))
            r = p["rms_v_per_cell"]
            print(f"\nDissertation flights (all take off full), table fitted on 30 and 32 from sim-4s.json's: error per cell "
                  f"{1000 * r['config_curve']:.1f} -> {1000 * r['fitted']:.1f} mV, on 29 and 34 "
                  f"{1000 * r['test_config_curve']:.1f} -> {1000 * r['test_fitted']:.1f} mV; notes:")
            for n in p["notes"]:
                print("  " + n)

        flights = os.path.join(a.data, "cmu-m100", "flights")
        if not os.path.isdir(flights):
            print(f"\n(no {flights}: the Matrice 100 check is skipped)")
            return
        odd = [os.path.join(flights, f"{i}.csv") for i in range(1, 141, 2)]
        even = [os.path.join(flights, f"{i}.csv") for i in range(2, 141, 2)]
        out = os.path.join(tmp, "m100-stitched.json")
        m = json.loads(run([battsim, "fit-ocv", *odd, "--test", *even, "-c",
                            os.path.join(ROOT, "configs", "dji-tb47d-6s.json"), *CMU, "-o", out, "--json"]))
        r = m["rms_v_per_cell"]
        print(f"\nCMU Matrice 100: table fitted on the 70 odd flights; error per cell on the 70 even ones "
              f"{1000 * r['test_config_curve']:.1f} mV (config's estimated curve) -> {1000 * r['test_fitted']:.1f} mV "
              f"(fitted flights {1000 * r['config_curve']:.1f} -> {1000 * r['fitted']:.1f} mV); full (SOC 1) "
              f"{m['ocv_cell_voltage_v']['fitted'][-1]:.3f} V per cell, the config's curve "
              f"{m['ocv_cell_voltage_v']['config_curve'][-1]:.3f} V")
        for name, cfg in (("config's curve", os.path.join(ROOT, "configs", "dji-tb47d-6s.json")), ("stitched", out)):
            caps, warned = [], 0
            for log in even:
                s = json.loads(run([battsim, "replay", log, "-c", cfg, *CMU, "--estimator", "joint", "--json"]))
                caps.append(s["flight"]["capacity_ah"]["mean"])
                names = {w["name"] for w in s["warnings"]}
                warned += bool(names & {"short_flight", "low_capacity", "high_resistance"})
            q = statistics.quantiles(caps, n=4)
            print(f"  even flights, {name}: capacity over the flight median {statistics.median(caps):.2f} Ah "
                  f"(quartiles {q[0]:.2f}..{q[2]:.2f}), health warnings on {warned}/{len(even)}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
