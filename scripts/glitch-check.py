#!/usr/bin/env python3
"""One garbled current reading in a real or bundled log, replayed with the joint estimator:
prints the first fifth's resistance, the resistance and capacity at the end and the warnings,
clean and glitched, for the two cases the thirty-sixth session's resistance gate did not
catch (docs/estimator.md): a glitch before the resistance window reaches its bar (1 s after
the take-off of logs/example-4s.csv) and one in a racing window (flight 30, 100 s in). Both
are caught since the thirty-seventh session: the glitched lines should read as the clean ones.

    python3 scripts/glitch-check.py [BATTSIM] [DATA_DIR]
"""
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build", "battsim")
DATA = sys.argv[2] if len(sys.argv) > 2 else os.path.join(ROOT, "..", "shared", "data")

# (log, config, row to garble, current in mA written there); raw logs: field 7 is current_ma.
CASES = [
    (os.path.join(ROOT, "logs", "example-4s.csv"), os.path.join(ROOT, "configs", "sim-4s.json"), 950, 100000),
    (os.path.join(DATA, "predictive-bms", "flights", "30.csv"), os.path.join(ROOT, "configs", "reference-original.json"),
     3826, 200000),
]


def replay(log, config):
    out = subprocess.run([BIN, "replay", log, "-c", config, "--estimator", "joint", "--json"],
                         capture_output=True, text=True, check=True).stdout
    j = json.loads(out)
    f = j["flight"]
    return (f["resistance_ohm"]["first20_mean"], f["resistance_ohm"]["final"], f["capacity_ah"]["final"],
            [w["name"] for w in j["warnings"]])


def main():
    with tempfile.TemporaryDirectory() as tmp:
        for log, config, row, milliamps in CASES:
            lines = open(log).read().splitlines()
            fields = lines[row].split(",")
            fields[6] = "%.2f" % milliamps
            lines[row] = ",".join(fields)
            glitched = os.path.join(tmp, "glitched.csv")
            with open(glitched, "w") as f:
                f.write("\n".join(lines) + "\n")
            for label, path in (("clean", log), ("row %d at %g A" % (row, milliamps / 1000), glitched)):
                r20, rend, cap, warnings = replay(path, config)
                print("%s, %s: R first 20 %% %.2f mOhm, R final %.2f mOhm, capacity final %.3f Ah, warnings %s"
                      % (os.path.basename(log), label, r20 * 1e3, rend * 1e3, cap, ", ".join(warnings) or "none"))


if __name__ == "__main__":
    main()
