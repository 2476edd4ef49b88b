#!/usr/bin/env python3
"""Can a current-sensor gain error be flagged by the capacity reading above the rated one?

Simulates every scenario of the given suites (N copies, seed + 7919·k as `battsim score
--copies` does), replays each with the joint estimator and prints, per flight, the capacity
it reports against the config's rated capacity: the largest after 10 % of the flight, at
20 % and at the landing. The gain-fault flights read (gain × true capacity); a flag needs a
bar that no clean flight crosses (twenty-fourth session, docs/estimator.md).

    python3 scripts/experiments/gain-plausibility.py [--suites scenarios,scenarios-holdout] [--copies 4]
"""
import argparse, csv, glob, json, os, subprocess, sys, tempfile
from concurrent.futures import ThreadPoolExecutor

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from config_edit import battsim_in  # noqa: E402


def one(args):
    battsim, tmp, scen, k = args
    s = json.load(open(scen))
    cfg = os.path.normpath(os.path.join(os.path.dirname(scen), s["monitor_config"]))
    rated = json.load(open(cfg))["battery"]["capacity_ah"]
    tag = os.path.join(tmp, f"{s['name']}-{k}")
    subprocess.run([battsim, "simulate", scen, "-o", tag + ".csv", "--seed", str(s["seed"] + 7919 * k)], check=True, capture_output=True)
    truth = json.load(open(tag + ".truth.json"))
    subprocess.run([battsim, "replay", tag + ".csv", "-c", cfg, "--estimator", "joint", "--series", tag + ".series.csv"],
                   check=True, capture_output=True)
    rows = [r for r in csv.DictReader(open(tag + ".series.csv")) if r["flying"] == "1" and r["capacity_ah"]]
    t0, t1 = float(rows[0]["time_s"]), float(rows[-1]["time_s"])
    cap = [(float(r["time_s"]) - t0, float(r["capacity_ah"]) / rated) for r in rows]
    return {"flight": f"{s['name']}@{k}", "faulty": truth["sensor"]["faulty"], "gain": "current_gain_error" in json.dumps(s),
            "true": truth["pack"]["capacity_ah"] / rated, "max": max(c for t, c in cap if t > 0.1 * (t1 - t0)),
            "at20": next(c for t, c in cap if t >= 0.2 * (t1 - t0)), "end": cap[-1][1]}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--suites", default="scenarios,scenarios-holdout,scenarios-rest-polarisation,scenarios-last-cell")
    ap.add_argument("--copies", type=int, default=4)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    a = ap.parse_args()
    battsim = battsim_in(a.build)
    jobs = []
    with tempfile.TemporaryDirectory() as tmp:
        for suite in a.suites.split(","):
            for scen in sorted(glob.glob(os.path.join(ROOT, "configs", suite, "*.json"))):
                if json.load(open(scen)).get("schema") == "battsim.scenario":
                    jobs += [(battsim, tmp, scen, k) for k in range(a.copies)]
        with ThreadPoolExecutor(2) as ex:
            res = list(ex.map(one, jobs))
    clean = [r for r in res if not r["faulty"]]
    gain = [r for r in res if r["gain"]]
    for name, key in (("largest after 10 % of the flight", "max"), ("at 20 %", "at20"), ("at the landing", "end")):
        worst = max(clean, key=lambda r: r[key])
        print(f"capacity / rated {name}: clean flights up to {worst[key]:.3f} ({worst['flight']}); "
              f"gain-fault flights {min(r[key] for r in gain):.3f}..{max(r[key] for r in gain):.3f}")


if __name__ == "__main__":
    main()
