#!/usr/bin/env python3
"""Reads the joint estimator's OCV tables of the simulated suite's configs the way a user
would: a C/5 discharge of the config's healthy pack, simulated with the reference sensors
(`battsim simulate`, the voltage sensor's gain error set to zero), read by `battsim discharge --ocv-points 21` (normalised to the charge
delivered, I·R added back with the config's resistance). Writes the table into the configs.
Applied since the eleventh session (seed 5005); the defaults were retuned on these tables.

    python3 scripts/suite-ocv-tables.py [--battsim build/battsim] [--seed 5005] [--dry-run]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The pack each table is read off, and the configs that share its per-cell curve.
GROUPS = [("sim-4s.json", ["sim-4s.json", "sim-4s-1300.json", "sim-4s-1800.json"]),
          ("generic-3s.json", ["generic-3s.json"]),
          ("generic-6s.json", ["generic-6s.json"])]


def read_table(battsim, config_name, seed, tmp):
    cfg_path = os.path.join(ROOT, "configs", config_name)
    with open(cfg_path) as f:
        cfg = json.load(f)
    cells = cfg["battery"]["cells_in_series"]
    capacity_ah = cfg["battery"]["capacity_ah"]
    # C/5 at a mean cell voltage of about 3.75 V, as constant power (the simulator's loads are).
    power_w = 0.2 * capacity_ah * 3.75 * cells
    scenario = {"schema": "battsim.scenario", "version": 1, "name": "c5-" + config_name[:-5],
                "description": "C/5 discharge of the healthy pack, to read the OCV table", "seed": seed,
                "monitor_config": cfg_path, "pack": {"cells": cells, "capacity_ah": capacity_ah},
                "profile": {"kind": "hover", "idle_before_s": 30, "armed_s": 0, "flight_s": 36000, "idle_after_s": 10,
                            "mean_power_w": power_w, "gust_sd": 0, "takeoff_boost_s": 0},
                # The voltage gain error zero: a user reads the table with the monitor that then
                # flies, so its own gain error cancels; the suite's flights keep theirs.
                "sensor": {"unit": {"bus_gain_error": 0}},
                "log": {"format": "csv"}}
    sc_path = os.path.join(tmp, scenario["name"] + ".json")
    with open(sc_path, "w") as f:
        json.dump(scenario, f)
    log = os.path.join(tmp, scenario["name"] + ".csv")
    subprocess.run([battsim, "simulate", sc_path, "-o", log], check=True, capture_output=True)
    out = subprocess.run([battsim, "discharge", log, "-c", cfg_path, "--json"], check=True, capture_output=True, text=True)
    table = json.loads(out.stdout)["ocv_table"]
    if table["notes"]:
        sys.exit(f"suite-ocv-tables: {config_name}: {table['notes']}")
    return table


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--battsim", default=os.path.join(ROOT, "build", "battsim"))
    ap.add_argument("--seed", type=int, default=5005)
    ap.add_argument("--dry-run", action="store_true", help="print the tables, write nothing")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for source, targets in GROUPS:
            t = read_table(args.battsim, source, args.seed, tmp)
            print(f"{source}: {t['capacity_ah']} Ah at {t['mean_c_rate_per_h']}C, {t['cell_voltage_v'][0]} … {t['cell_voltage_v'][-1]} V")
            if args.dry_run:
                continue
            for name in targets:
                path = os.path.join(ROOT, "configs", name)
                with open(path) as f:
                    cfg = json.load(f)
                cfg["joint"]["ocv_cell_voltage_v"] = t["cell_voltage_v"]
                with open(path, "w") as f:
                    json.dump(cfg, f, indent=2, ensure_ascii=False)
                    f.write("\n")


if __name__ == "__main__":
    main()
