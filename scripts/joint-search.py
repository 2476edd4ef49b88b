#!/usr/bin/env python3
"""Random search over the joint estimator's filter settings, scored on a simulated suite.

Each sample copies configs/ to a temporary directory, sets the sampled keys in the
`joint` section (or, with --health, in `joint.health_filter`) of every monitor config the
suites use, runs `battsim score --json` on the suite and appends one JSON line: the
settings and the joint column's figures. At the end it prints the settings that no other
sample beats on every figure at once (the trade-off frontier), best first by the issue's
targets. Standard library only.

    python3 scripts/joint-search.py --samples 250 --seed 1 --out /tmp/search.jsonl
    python3 scripts/joint-search.py --samples 180 --around best.json --out /tmp/near.jsonl

--around FILE samples log-normally (sigma 0.4) around the settings in FILE (a JSON object
of keys), crossing them with a grid of polarisation shapes; without it the keys are drawn
log-uniformly from the ranges below. --settings FILE scores those settings once (e.g. a line
of an earlier search, on the held-out suite with --suite scenarios-holdout); keys holding an
object (`{"verdict_filter": {"enabled": false}}`) replace that section. --copies N pools N
copies of the suite, as `battsim score --copies` does; a key holding `_per_rated_ohm` is given
to each monitor config as `_ohm` times its rated R0 (`polarisation_process_per_rated_ohm_per_sqrt_s`
too). The first line is always the committed
settings. The eighth session's searches (docs/estimator.md):

    python3 scripts/joint-search.py --no-health-filter --samples 250 --seed 1 --out one.jsonl
    python3 scripts/joint-search.py --no-health-filter --around best.json --samples 240 --seed 2 --out near.jsonl
    python3 scripts/joint-search.py --samples 70 --seed 7 --out tracking.jsonl
"""
import argparse
import itertools
import json
import math
import os
import random
import shutil
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The configs the suites' scenarios name as their monitor configs.
MONITOR_CONFIGS = ["sim-4s.json", "sim-4s-1300.json", "sim-4s-1800.json",
                   "generic-3s.json", "generic-6s.json", "reference-modified.json"]
RANGES = {  # log-uniform ranges for the noise keys
    "voltage_sigma_v": (0.01, 0.05),
    "soc_sigma0": (0.01, 0.06),
    "capacity_sigma0_fraction": (0.08, 0.3),
    "polarisation_initial_ohm": (0.002, 0.012),
    "polarisation_sigma0_ohm": (0.003, 0.03),
    "soc_process_per_sqrt_s": (5e-5, 8e-4),
    "capacity_process_fraction_per_sqrt_s": (5e-6, 8e-5),
    "polarisation_process_ohm_per_sqrt_s": (2e-5, 5e-4),
    "ocv_soc_sigma": (0.005, 0.05),
}
SHAPES = list(itertools.product([2, 3, 4], [20, 30, 40, 60], [0.1, 0.2, 0.3, 0.4, 0.5]))


def log_uniform(rng, lo, hi):
    return math.exp(rng.uniform(math.log(lo), math.log(hi)))


def sample_random(rng):
    p = {"polarisation_time_s": rng.choice([2, 3, 4, 5, 5, 7])}
    share = rng.choice([0, 0, 0.2, 0.3, 0.45, 0.6])
    if share > 0:
        p["polarisation_slow_share"] = share
        p["polarisation_slow_time_s"] = rng.choice([20, 30, 40, 60])
    for k, (lo, hi) in RANGES.items():
        p[k] = log_uniform(rng, lo, hi)
    p["polarisation_follows_resistance"] = rng.random() < 0.3
    return p


def sample_around(rng, centre, k, shapes):
    fast, slow, share = shapes[k % len(shapes)]
    p = dict(centre)
    p.update(polarisation_time_s=fast, polarisation_slow_time_s=slow, polarisation_slow_share=share)
    if k >= len(shapes):  # after one pass over the shapes with the centre's noise keys
        for key in RANGES:
            if key in centre:
                p[key] = centre[key] * math.exp(rng.gauss(0.0, 0.4))
    return p


def reseed(suite_dir, k):
    """The suite's scenarios with other seeds (k > 0): the same packs, loads and faults with
    other gusts, cell spreads and sensor errors. A validation set for choosing among a
    search's best settings without touching the held-out suite."""
    for name in sorted(os.listdir(suite_dir)):
        if not name.endswith(".json"):
            continue
        path = os.path.join(suite_dir, name)
        with open(path) as f:
            sc = json.load(f)
        if sc.get("schema") != "battsim.scenario":
            continue
        sc["seed"] = sc.get("seed", 1) + 7919 * k
        with open(path, "w") as f:
            json.dump(sc, f)


def per_pack(settings, rated_ohm):
    """Settings with every key holding `_per_rated_ohm` (at any depth) turned into the key
    without that suffix plus `_ohm`, valued that many times the config's rated R0: one row can
    then give each pack a resistance in proportion to its own (e.g.
    `polarisation_initial_per_rated_ohm` 0.35 → `polarisation_initial_ohm` 0.007 for the 4S
    pack at 0.02 Ω, 0.0105 for the 6S one)."""
    out = {}
    for key, value in settings.items():
        if isinstance(value, dict):
            value = per_pack(value, rated_ohm)
        if "_per_rated_ohm" in key:
            if rated_ohm is None:
                sys.exit(f"joint-search: {key} needs the config's battery.internal_resistance_ohm")
            key, value = key.replace("_per_rated_ohm", "_ohm", 1), value * rated_ohm
        out[key] = value
    return out


def score(battsim, suite, settings, health, health_off, reseed_k=0, keep=None, copies=1):
    with tempfile.TemporaryDirectory() as tmp:
        configs = os.path.join(tmp, "configs")
        shutil.copytree(os.path.join(ROOT, "configs"), configs)
        if reseed_k:
            reseed(os.path.join(configs, suite), reseed_k)
        for name in MONITOR_CONFIGS:
            path = os.path.join(configs, name)
            with open(path) as f:
                c = json.load(f)
            joint = c.setdefault("joint", {})
            if health_off:
                joint.setdefault("health_filter", {})["enabled"] = False
            rated_ohm = c.get("battery", {}).get("internal_resistance_ohm")
            (joint.setdefault("health_filter", {}) if health else joint).update(per_pack(settings, rated_ohm))
            with open(path, "w") as f:
                json.dump(c, f)
        out = os.path.join(tmp, "score.json")
        r = subprocess.run([battsim, "score", "-j2", "--columns", "oracle,joint", "--json", "-o", out,
                            "--copies", str(copies), os.path.join(configs, suite)], capture_output=True, text=True)
        if r.returncode != 0:
            print(f"joint-search: battsim score failed for {json.dumps(settings)}:\n{r.stderr}", file=sys.stderr)
            return None
        with open(out) as f:
            d = json.load(f)
        if keep:  # the per-flight report, for figures the summary below does not hold
            shutil.copy(out, keep)
    s = d["summary"]
    joint = lambda k: s[k]["joint"]
    above = [abs(f["estimators"]["joint"]["remaining_time_error_pct"][1]) -
             abs(f["estimators"]["oracle"]["remaining_time_error_pct"][1]) for f in d["flights"]]
    return {
        "above_oracle_20": statistics.median(above), "above_oracle_20_largest": max(above),
        "remaining_time_20": joint("remaining_time_20")["median_abs"],
        "remaining_time_50": joint("remaining_time_50")["median_abs"],
        "energy_20": joint("remaining_energy_20")["median_abs"],
        "capacity_20": joint("capacity_20")["median_abs"], "capacity_end": joint("capacity_end")["median_abs"],
        "early_warnings": joint("early_warnings")["count"], "false_warnings": joint("false_warnings")["count"],
        "false_warnings_undegraded": joint("false_warnings_undegraded")["count"],
    }


LOWER = ["above_oracle_20", "above_oracle_20_largest", "remaining_time_50", "energy_20", "capacity_20",
         "capacity_end", "false_warnings"]


def beats(a, b):  # a at least as good as b on every figure, better on one
    pairs = [(a[k], b[k]) for k in LOWER] + [(-a["early_warnings"], -b["early_warnings"])]
    return all(x <= y for x, y in pairs) and any(x < y for x, y in pairs)


def validate(a):
    """Chooses among a search's best settings on reseeded copies of the suite: a setting whose
    figures hold on other seeds is one that did not merely fit the tuning suite's noise."""
    rows = [json.loads(line) for line in open(a.validate) if line.strip()]
    rows = [r for r in rows if r["figures"] and r["settings"]]
    rows.sort(key=lambda r: (-r["figures"]["early_warnings"], r["figures"]["false_warnings"],
                             r["figures"]["above_oracle_20"]))
    candidates = [{}] + [r["settings"] for r in rows[:a.top]]
    ks = [int(k) for k in a.reseeds.split(",")]
    results = []
    for n, p in enumerate(candidates):
        per = [score(a.battsim, a.suite, p, a.health, a.no_health_filter, k) for k in ks]
        per = [m for m in per if m]
        if not per:
            continue
        mean = {k: statistics.mean(m[k] for m in per) for k in per[0]}
        results.append((p, mean))
        with open(a.out, "a") as out:
            out.write(json.dumps({"settings": p, "reseeds": ks, "mean": mean, "per_seed": per}) + "\n")
        print(f"{n + 1}/{len(candidates)}", file=sys.stderr)
    results.sort(key=lambda r: (-r[1]["early_warnings"], r[1]["false_warnings"], r[1]["above_oracle_20"]))
    for p, m in results:
        print(json.dumps({"mean": {k: round(v, 2) for k, v in m.items()}, "settings": p}))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--battsim", default=os.path.join(ROOT, "build", "battsim"))
    ap.add_argument("--suite", default="scenarios", help="suite directory under configs/")
    ap.add_argument("--samples", type=int, default=100)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--around", help="JSON file of settings to sample around")
    ap.add_argument("--health", action="store_true", help="set the keys in joint.health_filter")
    ap.add_argument("--no-health-filter", action="store_true", help="switch the health filter off (one filter, as before it)")
    ap.add_argument("--settings", help="JSON file of settings: score these once (after the committed ones) and stop")
    ap.add_argument("--out", required=True, help="JSON lines, appended")
    ap.add_argument("--reseed", type=int, default=0,
                    help="score the suite's scenarios with their seeds moved (K = 1, 2, ...): a validation set")
    ap.add_argument("--validate", help="a search's JSON lines: score its --top best (most warnings, fewest false, "
                    "smallest gap) and the committed settings on --reseeds, print the means, and stop")
    ap.add_argument("--keep-json", help="with --settings: also write those settings' full `battsim score --json` report here")
    ap.add_argument("--copies", type=int, default=1,
                    help="fly the suite this many times (battsim score --copies; figures pool every copy)")
    ap.add_argument("--top", type=int, default=12)
    ap.add_argument("--reseeds", default="1,2,3", help="the seed moves --validate scores on")
    a = ap.parse_args()
    if a.validate:
        validate(a)
        return
    rng = random.Random(a.seed)
    centre = json.load(open(a.around)) if a.around else None
    shapes = list(SHAPES)
    if centre:
        rng.shuffle(shapes)
    if a.settings:
        fixed = json.load(open(a.settings))
        a.samples = 1
    with open(a.out, "a") as out:
        rows = []
        for k in range(-1, a.samples):
            if k < 0:
                p = {}
            elif a.settings:
                p = fixed
            else:
                p = sample_around(rng, centre, k, shapes) if centre else sample_random(rng)
            keep = a.keep_json if a.settings and k >= 0 else None
            m = score(a.battsim, a.suite, p, a.health, a.no_health_filter, a.reseed, keep, a.copies)
            out.write(json.dumps({"settings": p, "figures": m}) + "\n")
            out.flush()
            if m:
                rows.append((p, m))
            print(f"{k + 1}/{a.samples}", file=sys.stderr)
    front = [(p, m) for p, m in rows if not any(beats(m2, m) for _, m2 in rows)]
    front.sort(key=lambda r: (-r[1]["early_warnings"], r[1]["false_warnings"], r[1]["above_oracle_20"]))
    for p, m in front:
        print(json.dumps({"figures": {k: round(v, 2) for k, v in m.items()}, "settings": p}))


if __name__ == "__main__":
    main()
