#!/usr/bin/env python3
"""A monitor's current-sensor gain from a fleet that shares its packs, with no charger.

Simulated fleets of --monitors monitors flying the same --packs packs (each pack once on each
monitor; the packs are the tuning suite's 4S scenarios of several kinds, seeded per flight).
In each fleet one monitor's current sensor has a gain error g (every one of its flights), the
others are clean; with --ambient-sd each flight's ambient temperature is drawn about 20 °C.
One `battsim batch` per fleet (manifest `pack` and `monitor`, no `charged_mah`) gives the
per-monitor table's fleet comparison. Prints, for each g, how often the faulty monitor and a
clean one are flagged (`fleet_gain_fault`), and the gain error read against the true one.

    python3 scripts/fleet-gain.py [--fleets 5] [--monitors 4] [--packs 6] [--ambient-sd 0]

Standard library only (twenty-seventh session).
"""
import argparse, json, os, random, statistics, subprocess, sys, tempfile
from concurrent.futures import ThreadPoolExecutor

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from config_edit import battsim_in, run_or_exit as run  # noqa: E402

KINDS = ["4s-racing-healthy-a", "4s-racing-healthy-b", "4s-racing-capacity-75", "4s-racing-resistance-180",
         "4s-hover-healthy", "4s-racing-healthy-c", "4s-racing-aged", "4s-hover-capacity-75"]
GAINS = [0.0, -0.05, 0.04, 0.08]


def simulate(job):
    battsim, tmp, kind, seed, gain, ambient_c, tag = job
    with open(os.path.join(ROOT, "configs", "scenarios", kind + ".json")) as f:
        s = json.load(f)
    s["monitor_config"] = os.path.join(ROOT, "configs", "sim-4s.json")
    if gain:
        s.setdefault("sensor", {}).setdefault("faults", {})["current_gain_error"] = gain
    if ambient_c is not None:
        s["environment"] = {"ambient_c": ambient_c, "initial_temperature_c": ambient_c}
    path = os.path.join(tmp, tag + ".json")
    with open(path, "w") as f:
        json.dump(s, f)
    run([battsim, "simulate", path, "-o", os.path.join(tmp, tag + ".csv"), "--seed", str(seed)])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--fleets", type=int, default=5, help="fleets per gain error")
    ap.add_argument("--monitors", type=int, default=4)
    ap.add_argument("--packs", type=int, default=6)
    ap.add_argument("--ambient-sd", type=float, default=0.0, help="°C; 0: every flight at its scenario's ambient")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    a = ap.parse_args()
    battsim = battsim_in(a.build)
    rng = random.Random(a.seed)
    cfg = os.path.join(ROOT, "configs", "sim-4s.json")
    results = {g: {"hit": 0, "clean_flagged": 0, "clean": 0, "errors": []} for g in GAINS}
    with tempfile.TemporaryDirectory() as tmp:
        jobs, manifests, k = [], [], 0
        for gain in GAINS:
            for fleet in range(a.fleets):
                name = f"g{gain:g}-f{fleet}"
                rows = ["path,pack,monitor,config"]
                for p in range(a.packs):
                    kind = KINDS[(fleet + p) % len(KINDS)]
                    for m in range(a.monitors):
                        k += 1
                        ambient = 20.0 + rng.gauss(0.0, a.ambient_sd) if a.ambient_sd > 0 else None
                        tag = f"{name}-p{p}-m{m}"
                        jobs.append((battsim, tmp, kind, 3000 + 7919 * k, gain if m == 0 else 0.0, ambient, tag))
                        rows.append(f"{tag}.csv,p{p},m{m},{cfg}")
                path = os.path.join(tmp, name + ".csv")
                with open(path, "w") as f:
                    f.write("\n".join(rows) + "\n")
                manifests.append((gain, path))
        with ThreadPoolExecutor(2) as pool:
            list(pool.map(simulate, jobs))
        for gain, path in manifests:
            r = subprocess.run([battsim, "batch", "-m", path, "--estimator", "joint", "--format", "json",
                                "--no-progress"], capture_output=True, text=True)
            if r.returncode != 0:
                sys.exit(f"battsim batch failed on {path}:\n{r.stderr}")
            res = results[gain]
            for mon in json.loads(r.stdout)["monitors"]:
                if mon["monitor"] == "m0" and gain:
                    res["hit"] += mon["fleet_gain_fault"] is True
                    res["errors"].append(mon["fleet_gain_error"] - gain)
                else:
                    res["clean"] += 1
                    res["clean_flagged"] += mon["fleet_gain_fault"] is True
                    if not gain:
                        res["errors"].append(mon["fleet_gain_error"])
    print(f"{a.fleets} fleets per gain error, {a.monitors} monitors × {a.packs} shared packs each; "
          f"ambient {'per scenario' if a.ambient_sd <= 0 else f'20 ± {a.ambient_sd:g} °C per flight'}")
    for gain in GAINS:
        res = results[gain]
        errs = sorted(abs(e) for e in res["errors"])
        hit = f"faulty monitor flagged {res['hit']}/{a.fleets}; " if gain else ""
        print(f"gain error {100 * gain:+g} %: {hit}clean monitors flagged {res['clean_flagged']}/{res['clean']}; "
              f"gain read off by {100 * statistics.median(errs):.2f} % median, {100 * errs[-1]:.2f} % worst")


if __name__ == "__main__":
    main()
