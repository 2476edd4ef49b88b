#!/usr/bin/env python3
"""Is the joint estimator's capacity standard error honest?

The monitor reports the capacity with its standard error (`capacity_sigma_ah` in the
series, `flight.capacity_ah.final_sigma` in the summary). An honest one has about 68 % of
the errors within one of it and 95 % within two. Three rulers:

  simulated suites   every scenario (N copies, seed + 7919·k as `battsim score --copies`
                     does) replayed with its own config: (estimate − truth) / sigma at 20 %
                     of the flight and at the landing; the tuning and held-out suites, then
                     the two stress suites (a polarisation shape from real rests, weak last
                     cells);
  dissertation       the final capacity against the capacity its rests read before and after
                     the flight (flights 29, 30, 32; 34 has no landing rest), in sigmas;
  Matrice 100        no truth: the spread of the final capacity over the fleet's flights (one
                     pack model; IQR / 1.349, a robust standard deviation) against the median
                     reported sigma, with the committed config and, with --stitched, on the
                     even flights with an OCV table `battsim fit-ocv` stitches from the odd.

    python3 scripts/capacity-calibration.py [--copies 4] [--stitched] [--fraction-of-charge F]

--fraction-of-charge F scores a copy of configs/ with `joint.capacity_sigma_fraction_of_charge`
set to F (0: the health filter's error alone, as before the twenty-sixth session). Standard
library only (twenty-fifth session, docs/estimator.md).
"""
import argparse, csv, json, os, shutil, statistics, sys, tempfile
from concurrent.futures import ThreadPoolExecutor

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from config_edit import (battsim_in, edit_joint_sections, m100_summaries, run_or_exit as run,  # noqa: E402
                         shared_data_dir, simulate_copy, suite_scenarios)


def sim_flight(job):
    battsim, tmp, scen, k = job
    s, cfg, tag, truth = simulate_copy(battsim, tmp, scen, k)
    run([battsim, "replay", tag + ".csv", "-c", cfg, "--estimator", "joint", "--series", tag + ".series.csv"])
    with open(tag + ".series.csv") as f:
        rows = [r for r in csv.DictReader(f) if float(r["capacity_sigma_ah"]) > 0.0]
    fl = truth["flight"]
    t20 = fl["takeoff_s"] + 0.2 * fl["total_flight_time_s"]
    at20 = next((r for r in rows if float(r["time_s"]) >= t20), None)
    end = [r for r in rows if float(r["time_s"]) <= fl["landing_s"]]
    true_ah = truth["pack"]["capacity_ah"]
    # (error in sigmas, error in % of the truth)
    z = lambda r: ((float(r["capacity_ah"]) - true_ah) / float(r["capacity_sigma_ah"]),
                   100.0 * (float(r["capacity_ah"]) / true_ah - 1.0))
    return (z(at20) if at20 else None), (z(end[-1]) if end else None), s["profile"]["kind"]


def share(zs, bound):
    return sum(abs(z) <= bound for z in zs) / len(zs)


def m100(battsim, config, data, which, tmp):
    summaries = m100_summaries(battsim, ROOT, config, data, tmp)
    caps, sigmas = [], []
    for n in which:
        c = summaries[n]["flight"]["capacity_ah"]
        caps.append(c["final"])
        sigmas.append(c["final_sigma"])
    q = statistics.quantiles(caps, n=4)
    with open(config) as f:
        rated = json.load(f)["battery"]["capacity_ah"]
    high = sum(c > 1.5 * rated for c in caps)
    return statistics.median(caps), (q[2] - q[0]) / 1.349, statistics.median(sigmas), len(caps), high


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--copies", type=int, default=4)
    ap.add_argument("--stitched", action="store_true")
    ap.add_argument("--fraction-of-charge", type=float)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    a = ap.parse_args()
    battsim = battsim_in(a.build)
    data = shared_data_dir(ROOT)
    with tempfile.TemporaryDirectory() as tmp:
        configs = os.path.join(ROOT, "configs")
        if a.fraction_of_charge is not None:
            configs = os.path.join(tmp, "configs")
            shutil.copytree(os.path.join(ROOT, "configs"), configs)
            edit_joint_sections(configs, lambda j: j.update(capacity_sigma_fraction_of_charge=a.fraction_of_charge) or True)
            m100_config = os.path.join(configs, "dji-tb47d-6s.json")  # no joint section of its own
            with open(m100_config) as f:
                cfg = json.load(f)
            cfg.setdefault("joint", {})["capacity_sigma_fraction_of_charge"] = a.fraction_of_charge
            with open(m100_config, "w") as f:
                json.dump(cfg, f, indent=2)
        for suite in ("scenarios", "scenarios-holdout", "scenarios-rest-polarisation", "scenarios-last-cell"):
            scens = suite_scenarios(configs, suite)
            jobs = [(battsim, tmp, p, k) for p in scens for k in range(a.copies)]
            with ThreadPoolExecutor(2) as pool:
                res = list(pool.map(sim_flight, jobs))
            for label, i in (("at 20 %", 0), ("at the landing", 1)):
                zs = [r[i][0] for r in res if r[i] is not None]
                by_kind = []
                for kind in sorted({r[2] for r in res}):
                    es = [r[i][1] for r in res if r[i] is not None and r[2] == kind]
                    by_kind.append(f"{kind} {statistics.median(es):+.1f} % (worst {max(es, key=abs):+.1f})")
                print(f"{suite} {label}: capacity error, signed median: " + ", ".join(by_kind))
                print(f"{suite} {label}: {len(zs)} flights, |error| within 1 sigma {100 * share(zs, 1):.0f} %, "
                      f"2 sigma {100 * share(zs, 2):.0f} %, median |error| / sigma "
                      f"{statistics.median(abs(z) for z in zs):.2f}")
        for n in (29, 30, 32):
            path = os.path.join(data, "predictive-bms", "flights", f"{n}.csv")
            c = json.loads(run([battsim, "replay", path, "-c", os.path.join(configs, "sim-4s.json"),
                                "--estimator", "joint", "--json"]))["flight"]["capacity_ah"]
            print(f"dissertation flight {n}: final {c['final']:.3f} ± {c['final_sigma']:.3f} Ah, rests "
                  f"{c['after_rest']:.3f} Ah: {(c['final'] - c['after_rest']) / c['final_sigma']:+.1f} sigma")
        med, spread, sig, n, high = m100(battsim, os.path.join(configs, "dji-tb47d-6s.json"), data,
                                         range(1, 141), tmp)
        print(f"Matrice 100, committed config, {n} flights: final capacity median {med:.2f} Ah, spread "
              f"(IQR / 1.349) {spread:.2f} Ah, median reported sigma {sig:.3f} Ah: ratio {spread / sig:.1f}; "
              f"{high} above 1.5 x the config's capacity")
        if a.stitched:
            table = os.path.join(tmp, "stitched.json")
            run([battsim, "fit-ocv", "-m", os.path.join(ROOT, "configs", "manifests", "cmu-m100.json"),
                 "--test-every", "2", "-c", os.path.join(configs, "dji-tb47d-6s.json"), "-o", table],
                env=dict(os.environ, BATTSIM_DATA_DIR=data))
            med, spread, sig, n, high = m100(battsim, table, data, range(2, 141, 2), tmp)
            print(f"Matrice 100, table stitched from the odd flights, {n} even flights: final capacity median "
                  f"{med:.2f} Ah, spread {spread:.2f} Ah, median reported sigma {sig:.3f} Ah: ratio {spread / sig:.1f}; "
                  f"{high} above 1.5 x the config's capacity")


if __name__ == "__main__":
    main()
