#!/usr/bin/env python3
"""`battsim replay --charged-mah` on the simulated suites: the current sensor against a charger.

Every scenario of the tuning and held-out suites (N copies, seed + 7919·k as `battsim score
--copies` does) is simulated, and its truth's `flight.log_charge_ah` (what the pack gave over
the log, which a charger puts back when the pack began full) is given as the charger's count.
Prints the ratio of the monitor's count to it for the clean sensors (range; partly charged packs
get no verdict), every flight with a sensor fault (ratio, flagged or not), any clean flight
flagged, and for each flagged flight with a suggested gain the ratio again with the config
`--config-out` wrote. The simulation has no charger error.

    python3 scripts/charger-check.py [--copies 2]

Standard library only (twenty-sixth session; README, `battsim replay`).
"""
import argparse, json, os, sys, tempfile
from concurrent.futures import ThreadPoolExecutor

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from config_edit import battsim_in, run_or_exit as run, simulate_copy, suite_scenarios  # noqa: E402


def flight(job):
    battsim, tmp, scen, k = job
    s, cfg, tag, truth = simulate_copy(battsim, tmp, scen, k)
    # A partly charged pack: the charger also puts back what was missing at power-on.
    charged = 1000.0 * (truth["flight"]["log_charge_ah"] + truth["pack"]["initial_charge_drawn_ah"])
    args = [battsim, "replay", tag + ".csv", "-c", cfg, "--estimator", "joint", "--charged-mah", f"{charged:.3f}"]
    c = json.loads(run(args + ["--json"]))["charger_check"]
    fixed = None
    if c["suggested_current_gain"] is not None and c["fault"]:
        run(args + ["--config-out", tag + ".fixed.json"])
        fixed = json.loads(run([battsim, "replay", tag + ".csv", "-c", tag + ".fixed.json", "--estimator", "joint",
                                "--charged-mah", f"{charged:.3f}", "--json"]))["charger_check"]["ratio"]
    return f"{s['name']}@{k}", truth["sensor"]["faulty"], c["ratio"], c["fault"], len(c["notes"]), fixed


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--copies", type=int, default=2)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    a = ap.parse_args()
    battsim = battsim_in(a.build)
    with tempfile.TemporaryDirectory() as tmp:
        scens = [p for suite in ("scenarios", "scenarios-holdout")
                 for p in suite_scenarios(os.path.join(ROOT, "configs"), suite)]
        with ThreadPoolExecutor(2) as pool:
            res = list(pool.map(flight, [(battsim, tmp, p, k) for p in scens for k in range(a.copies)]))
    clean = [r for r in res if not r[1]]
    ratios = [r[2] for r in clean]
    judged = [r for r in clean if r[3] is not None]
    ratios = [r[2] for r in judged]
    print(f"clean sensors: {len(clean)} flights, {len(clean) - len(judged)} without a verdict (not full at the "
          f"start); the rest ratio {min(ratios):.4f} .. {max(ratios):.4f}, {sum(bool(r[3]) for r in judged)} flagged")
    for name, faulty, ratio, fault, notes, fixed in res:
        if faulty or fault:
            verdict = "no verdict" if fault is None else "flagged" if fault else "not flagged"
            print(f"{name}: {'sensor fault' if faulty else 'clean'}, ratio {ratio:.4f}, {verdict}, {notes} note(s)"
                  + (f"; with the written config {fixed:.4f}" if fixed is not None else ""))


if __name__ == "__main__":
    main()
