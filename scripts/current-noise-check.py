#!/usr/bin/env python3
"""Current-sensor noise the simulated logs do not carry: replays two simulated 4S flights
(a hover and a racing flight, as `battsim simulate` writes them) with uniform noise of
±N mA added to each current reading (the voltage untouched), joint estimator, and prints the
resistance over the first fifth and at the end, the capacity over the first fifth and at the
end, and the warnings. The reference hardware's INA226 (16 averages) reads within about
±10 mA; flight-controller current sensors are often noisier (docs/estimator.md, thirty-seventh
session).

    python3 scripts/current-noise-check.py [--settings '{"hover_resistance_min_step_a": 1.0}'] [BATTSIM]

--settings merges keys into the config's `joint` section (a copy of configs/sim-4s.json).
"""
import json
import os
import random
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ARGS = sys.argv[1:]
SETTINGS = {}
if len(ARGS) >= 2 and ARGS[0] == "--settings":
    SETTINGS = json.loads(ARGS[1])
    ARGS = ARGS[2:]
BIN = ARGS[0] if ARGS else os.path.join(ROOT, "build", "battsim")
CONFIG = os.path.join(ROOT, "configs", "sim-4s.json")
SCENARIOS = ["4s-hover-healthy", "4s-racing-healthy-a"]
NOISE_MA = [0, 50, 100, 200, 400]
SEEDS = [1, 2]


def replay(path, config):
    out = subprocess.run([BIN, "replay", path, "-c", config, "--estimator", "joint", "--json"],
                         capture_output=True, text=True, check=True).stdout
    j = json.loads(out)
    f = j["flight"]
    return "R first 20 %% %.1f, end %.1f mOhm; capacity first 20 %% %.3f, end %.3f Ah; %s" % (
        f["resistance_ohm"]["first20_mean"] * 1e3, f["resistance_ohm"]["final"] * 1e3,
        f["capacity_ah"]["first20_mean"], f["capacity_ah"]["final"],
        ",".join(w["name"] for w in j["warnings"]) or "no warnings")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        config = CONFIG
        if SETTINGS:
            with open(CONFIG) as f:
                c = json.load(f)
            c["joint"].update(SETTINGS)
            config = os.path.join(tmp, "config.json")
            with open(config, "w") as f:
                json.dump(c, f)
        for name in SCENARIOS:
            log = os.path.join(tmp, name + ".csv")
            subprocess.run([BIN, "simulate", os.path.join(ROOT, "configs", "scenarios", name + ".json"), "-o", log],
                           capture_output=True, check=True)
            rows = open(log).read().splitlines()
            for noise in NOISE_MA:
                for seed in SEEDS if noise else SEEDS[:1]:
                    rng = random.Random(seed)
                    out = []
                    for row in rows:  # raw format: field 7 is current_ma
                        fields = row.split(",")
                        fields[6] = "%.2f" % (float(fields[6]) + rng.uniform(-noise, noise))
                        out.append(",".join(fields))
                    noisy = os.path.join(tmp, "noisy.csv")
                    with open(noisy, "w") as f:
                        f.write("\n".join(out) + "\n")
                    print("%s, ±%d mA (seed %d): %s" % (name, noise, seed, replay(noisy, config)))


if __name__ == "__main__":
    main()
