#!/usr/bin/env python3
"""The joint filters' voltage sigma per cell (fortieth session): reruns the figures behind the choice.

`battsim make-config` writes the three filters' `voltage_sigma_v` (tracking, health, verdict) as
the core's defaults x cells / 4 below 4S. This scores variants of that rule on scratch copies
of the suites (nothing in the repo is changed) and prints the joint column's summary lines:

    python3 scripts/sigma-per-cell.py small 0      # the small suite before: the defaults' sigma
    python3 scripts/sigma-per-cell.py small 1      # as committed: x cells / 4
    python3 scripts/sigma-per-cell.py small 0.5    # x (cells / 4) ** 0.5
    python3 scripts/sigma-per-cell.py main 3,6     # tuning and held-out suites, generic-3s and -6s scaled
    python3 scripts/sigma-per-cell.py main 3       # only generic-3s scaled

Four copies, `battsim score -j2 --copies 4 --columns joint,oracle`. Standard library only.
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
BATTSIM = os.environ.get("BATTSIM", os.path.join(ROOT, "build", "battsim"))
LINES = ("minus the oracle", "largest, points", "energy at 20 %, median", "capacity at 20 %, median",
         "early warnings", "false health", "undegraded")


def default_sigmas():
    """The core's defaults, read off make-config's 1S config (a quarter of each)."""
    out = subprocess.run([BATTSIM, "make-config", "--cells", "1", "--capacity-mah", "1550", "-o", "-"],
                         capture_output=True, text=True, check=True).stdout
    j = json.loads(out)["joint"]
    return (4 * j["voltage_sigma_v"], 4 * j["health_filter"]["voltage_sigma_v"],
            4 * j["verdict_filter"]["voltage_sigma_v"])


def set_sigmas(config_path, factor, defaults):
    with open(config_path) as f:
        c = json.load(f)
    j = c.setdefault("joint", {})
    j["voltage_sigma_v"] = defaults[0] * factor
    j.setdefault("health_filter", {})["voltage_sigma_v"] = defaults[1] * factor
    j.setdefault("verdict_filter", {})["voltage_sigma_v"] = defaults[2] * factor
    with open(config_path, "w") as f:
        json.dump(c, f, indent=2)


def score(suite_dir):
    r = subprocess.run([BATTSIM, "score", "-j2", "--copies", "4", "--columns", "joint,oracle", suite_dir],
                       capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit("sigma-per-cell: battsim score failed on %s:\n%s" % (suite_dir, r.stderr))
    print("==", os.path.basename(suite_dir))
    for line in r.stdout.splitlines():
        if any(key in line for key in LINES):
            print(line)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("suite", choices=["small", "main"])
    p.add_argument("value", help="small: the power of cells / 4; main: the cell counts whose generic config is scaled (3,6)")
    a = p.parse_args()
    defaults = default_sigmas()
    with tempfile.TemporaryDirectory(prefix="battsim-sigma-") as tmp:
        if a.suite == "small":
            power = float(a.value)
            suite = os.path.join(tmp, "scenarios-small")
            shutil.copytree(os.path.join(ROOT, "configs", "scenarios-small"), suite)
            for pack in sorted(glob.glob(os.path.join(suite, "packs", "*.json"))):
                with open(pack) as f:
                    cells = json.load(f)["battery"]["cells_in_series"]
                set_sigmas(pack, (cells / 4.0) ** power if cells < 4 else 1.0, defaults)
            score(suite)
        else:
            # The suites name their configs as ../NAME.json: copy both suites and the configs beside them.
            for name in ("scenarios", "scenarios-holdout"):
                shutil.copytree(os.path.join(ROOT, "configs", name), os.path.join(tmp, name))
            for config in glob.glob(os.path.join(ROOT, "configs", "*.json")):
                shutil.copy(config, tmp)
            for cells in (int(c) for c in a.value.split(",")):
                set_sigmas(os.path.join(tmp, "generic-%ds.json" % cells), cells / 4.0, defaults)
            for name in ("scenarios", "scenarios-holdout"):
                score(os.path.join(tmp, name))


if __name__ == "__main__":
    main()
