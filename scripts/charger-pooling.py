#!/usr/bin/env python3
"""The current sensor against the charger, one flight at a time and pooled per monitor.

Simulated monitors, each flying F packs of the tuning suite's full-start 4S scenarios (a
drone flies whatever pack is charged), with a current-sensor gain error g injected in every
one of its flights. The charger's count is the truth's `flight.log_charge_ah` with a charger
error: Gaussian, --charger-sigma of it, and with probability --bad-fraction a bad entry
(the charge stopped early, or a count typed wrong) 5–15 % short. One `battsim batch` run
over all the flights (manifest `monitor` and `charged_mah`) gives each flight's check and
each monitor's pooled one (`--monitors`). Prints, for each g, how often a flight and a
monitor are flagged, and how far the gain each suggests is from the one that corrects the
sensor (1 / (1 + g)): median and worst |suggested × (1 + g) − 1|.

    python3 scripts/charger-pooling.py [--trials 10] [--flights 5] [--charger-sigma 0.015]

The charger error model is an assumption (a hobby charger's count is good to about 1–2 %),
not a measurement. Standard library only (twenty-seventh session).
"""
import argparse, json, os, random, statistics, subprocess, sys, tempfile
from concurrent.futures import ThreadPoolExecutor

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from config_edit import battsim_in, run_or_exit as run  # noqa: E402

SCENARIOS = ["4s-racing-healthy-a", "4s-racing-healthy-b", "4s-racing-healthy-c", "4s-hover-healthy",
             "4s-racing-aged", "4s-racing-capacity-75", "4s-racing-resistance-180", "4s-hover-capacity-75"]
GAINS = [0.0, 0.02, 0.04, 0.08]


def simulate(job):
    battsim, tmp, name, seed, gain, tag = job
    with open(os.path.join(ROOT, "configs", "scenarios", name + ".json")) as f:
        s = json.load(f)
    s["monitor_config"] = os.path.join(ROOT, "configs", "sim-4s.json")
    if gain:
        s.setdefault("sensor", {}).setdefault("faults", {})["current_gain_error"] = gain
    scen = os.path.join(tmp, tag + ".scenario.json")
    with open(scen, "w") as f:
        json.dump(s, f)
    log = os.path.join(tmp, tag + ".csv")
    run([battsim, "simulate", scen, "-o", log, "--seed", str(seed)])
    with open(os.path.join(tmp, tag + ".truth.json")) as f:
        return log, json.load(f)["flight"]["log_charge_ah"]


def line(label, errors, flagged, n):
    signed = statistics.median(errors)
    errors = sorted(abs(e) for e in errors)
    return (f"{label}: flagged {flagged}/{n}; suggested gain off by {100 * statistics.median(errors):.2f} % "
            f"median (signed {100 * signed:+.2f} %), {100 * errors[-1]:.2f} % worst ({len(errors)} suggestions)")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--trials", type=int, default=10, help="monitors per gain error")
    ap.add_argument("--flights", type=int, default=5, help="flights per monitor")
    ap.add_argument("--charger-sigma", type=float, default=0.015)
    ap.add_argument("--bad-fraction", type=float, default=0.1)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    a = ap.parse_args()
    battsim = battsim_in(a.build)
    rng = random.Random(a.seed)
    with tempfile.TemporaryDirectory() as tmp:
        jobs, monitors = [], []
        for gain in GAINS:
            for t in range(a.trials):
                monitor = f"g{gain:g}-t{t}"
                monitors.append((monitor, gain))
                for f in range(a.flights):
                    k = t * a.flights + f
                    name = SCENARIOS[k % len(SCENARIOS)]
                    jobs.append((battsim, tmp, name, 5000 + 7919 * k, gain, f"{monitor}-f{f}"))
        with ThreadPoolExecutor(2) as pool:
            sims = list(pool.map(simulate, jobs))
        rows = ["path,monitor,config,charged_mah"]
        cfg = os.path.join(ROOT, "configs", "sim-4s.json")
        for (_, _, _, _, gain, tag), (log, charge_ah) in zip(jobs, sims):
            err = rng.gauss(0.0, a.charger_sigma)
            if rng.random() < a.bad_fraction:
                err -= rng.uniform(0.05, 0.15)
            rows.append(f"{log},{tag.rsplit('-f', 1)[0]},{cfg},{1000 * charge_ah * (1 + err):.1f}")
        manifest = os.path.join(tmp, "fleet.csv")
        with open(manifest, "w") as f:
            f.write("\n".join(rows) + "\n")
        mon_path = os.path.join(tmp, "monitors.json")
        r = subprocess.run([battsim, "batch", "-m", manifest, "--estimator", "joint", "--format", "json",
                            "--monitors", mon_path, "--no-progress"], capture_output=True, text=True)
        if r.returncode not in (0, 1):
            sys.exit(f"battsim batch failed:\n{r.stderr}")
        table = json.loads(r.stdout)
    print(f"{len(monitors)} monitors × {a.flights} flights; charger error {100 * a.charger_sigma:g} % "
          f"(σ), {100 * a.bad_fraction:g} % of entries 5–15 % short")
    by_monitor = {m["monitor"]: m for m in table["monitors"]}
    for gain in GAINS:
        names = [m for m, g in monitors if g == gain]
        rows = [r for r in table["rows"] if r["monitor"] in names]
        flight_err = [r["charger_suggested_gain"] * (1 + gain) - 1 for r in rows
                      if r["charger_suggested_gain"] is not None]
        pooled = [by_monitor[m] for m in names]
        pooled_err = [m["suggested_current_gain"] * (1 + gain) - 1 for m in pooled
                      if m["suggested_current_gain"] is not None]
        print(f"gain error {100 * gain:+g} %")
        print("  " + line("one flight", flight_err, sum(r["charger_fault"] is True for r in rows), len(rows)))
        print("  " + line(f"pooled over {a.flights}", pooled_err, sum(m["charger_fault"] is True for m in pooled),
                          len(pooled)))


if __name__ == "__main__":
    main()
