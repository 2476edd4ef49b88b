#!/usr/bin/env python3
"""The cell capacity verdict's bar (`joint.cell_capacity_significance_sigmas`), re-measured.

For each bar: every suite scored over N copies with the bar set in a copy of configs/
(cells named / outlier cells, false cell alarms, which), then the dissertation's four flights
replayed with configs/sim-4s.json at that bar, with and without the balance-tap artefact rule
(`cell_tap_artifact_ratio` 0), listing any cell named and when.

    python3 scripts/experiments/cell-capacity-bar.py [--bars 5,4,3.5,3,2.5] [--copies 4]

Standard library only (twenty-sixth session, docs/estimator.md; not adopted).
"""
import argparse, json, os, shutil, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from config_edit import battsim_in, edit_joint_sections, run_or_exit as run, shared_data_dir  # noqa: E402

SUITES = ["scenarios", "scenarios-holdout", "scenarios-last-cell", "scenarios-rest-polarisation"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bars", default="5,4,3.5,3,2.5")
    ap.add_argument("--copies", type=int, default=4)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    a = ap.parse_args()
    battsim = battsim_in(a.build)
    data = shared_data_dir(ROOT)
    for bar in [float(b) for b in a.bars.split(",")]:
        with tempfile.TemporaryDirectory() as tmp:
            configs = os.path.join(tmp, "configs")
            shutil.copytree(os.path.join(ROOT, "configs"), configs)
            edit_joint_sections(configs, lambda j: j.update(cell_capacity_significance_sigmas=bar) or True)
            for suite in SUITES:
                out = os.path.join(tmp, suite + ".json")
                run([battsim, "score", "-j2", "--copies", str(a.copies), "--columns", "joint", "--json", "-o", out,
                     os.path.join(configs, suite)])
                with open(out) as f:
                    d = json.load(f)
                tp = d["summary"]["cell_outlier_true_positives"]["joint"]
                fp = d["summary"]["cell_outlier_false_positives"]["joint"]
                false = [f"{f['name']} cell {f['estimators']['joint']['named_cell']}" for f in d["flights"]
                         if f["estimators"]["joint"]["named_cell"]
                         and f["estimators"]["joint"]["named_cell"] not in f["outlier_cells"]]
                print(f"bar {bar} σ, {suite}: named {tp['count']}/{tp['of']}, false {fp['count']}"
                      + (f" ({', '.join(false)})" if false else ""))
            for tap in (None, 0.0):
                cfg_path = os.path.join(tmp, "flights.json")
                with open(os.path.join(configs, "sim-4s.json")) as f:
                    cfg = json.load(f)
                if tap is not None:
                    cfg["joint"]["cell_tap_artifact_ratio"] = tap
                with open(cfg_path, "w") as f:
                    json.dump(cfg, f)
                named = []
                for n in (29, 30, 32, 34):
                    s = json.loads(run([battsim, "replay", os.path.join(data, "predictive-bms", "flights", f"{n}.csv"),
                                        "-c", cfg_path, "--estimator", "joint", "--json"]))
                    named += [f"{n}: cell {w.get('cell')} at {w['first_time_s']:.0f} s" for w in s.get("warnings", [])
                              if w["name"] == "cell_outlier"]
                rule = "without the tap rule" if tap is not None else "with the tap rule"
                print(f"bar {bar} σ, dissertation flights {rule}: " + ("; ".join(named) if named else "no cell named"))


if __name__ == "__main__":
    main()
