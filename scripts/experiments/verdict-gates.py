#!/usr/bin/env python3
"""Two gates on the short-flight verdict's capacity, measured (neither adopted).

Needs the experiment's keys, which are not in the code: first

    git apply scripts/experiments/verdict-gates.patch && cmake --build build

and `git apply -R` the same patch afterwards. The keys, in `joint`:
  verdict_capacity_sigmas K       the verdict's total and capacity-only solves take the
                                  verdict filter's capacity K of its standard errors higher:
                                  a flight is short only if it is short at that end;
  verdict_min_charge_fraction F   they take the rated capacity until F × rated is drawn
                                  since take-off: no capacity verdict on too little evidence.
For each value of --key this copies configs/ to a temporary directory, sets the key in every
config with a `joint` section, and prints the short flights warned in time and the false
warnings over both suites (`battsim score --copies N`), and the warnings over the CMU
Matrice 100 flights (`battsim batch`), which have no ground truth: all 140 with the
committed config, and, with --stitched, the 70 even ones with an OCV table that
`battsim fit-ocv` stitches from the 70 odd ones (twenty-fifth session, docs/estimator.md).

    python3 scripts/experiments/verdict-gates.py --key verdict_capacity_sigmas --values 0,0.5,1,2,3
    python3 scripts/experiments/verdict-gates.py --key verdict_min_charge_fraction --values 0,0.03,0.05,0.08,0.1 --stitched
"""
import argparse, collections, json, os, shutil, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from config_edit import edit_joint_sections, m100_summaries, shared_data_dir  # noqa: E402


def set_key(path, key, value):
    with open(path) as f:
        cfg = json.load(f)
    cfg.setdefault("joint", {})[key] = value
    with open(path, "w") as f:
        json.dump(cfg, f, indent=2)


def m100_warnings(battsim, config, data, tmp, which):
    """Counts of warnings raised over the Matrice 100 flights numbered in `which`."""
    try:
        summaries = m100_summaries(battsim, ROOT, config, data, tmp)
    except RuntimeError as e:
        sys.exit(str(e))
    counts = collections.Counter()
    for n in which:
        counts.update({w["name"] for w in summaries[n]["warnings"]})
    return (f"short flight {counts['short_flight']}/{len(which)} (low capacity {counts['low_capacity']}, "
            f"high resistance {counts['high_resistance']})")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--key", choices=["verdict_capacity_sigmas", "verdict_min_charge_fraction"], required=True)
    ap.add_argument("--values", required=True)
    ap.add_argument("--copies", type=int, default=4)
    ap.add_argument("--stitched", action="store_true", help="also the even M100 flights on a table from the odd ones")
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    a = ap.parse_args()
    battsim = os.path.join(a.build, "battsim")
    data = shared_data_dir(ROOT)
    env = dict(os.environ, BATTSIM_DATA_DIR=data)
    manifest = os.path.join(ROOT, "configs", "manifests", "cmu-m100.json")
    with tempfile.TemporaryDirectory() as work:
        stitched = os.path.join(work, "stitched.json")
        if a.stitched:
            r = subprocess.run([battsim, "fit-ocv", "-m", manifest, "--test-every", "2", "-c",
                                os.path.join(ROOT, "configs", "dji-tb47d-6s.json"), "-o", stitched],
                               capture_output=True, text=True, env=env)
            if r.returncode != 0:
                sys.exit(f"battsim fit-ocv failed:\n{r.stderr}")
        for value in (float(x) for x in a.values.split(",")):
            with tempfile.TemporaryDirectory() as tmp:
                configs = os.path.join(tmp, "configs")
                shutil.copytree(os.path.join(ROOT, "configs"), configs)
                edit_joint_sections(configs, lambda j: j.__setitem__(a.key, value) or True)
                row = [f"{a.key} {value:g}:"]
                for suite in ("scenarios", "scenarios-holdout"):
                    r = subprocess.run([battsim, "score", "-j2", "--copies", str(a.copies), "--json",
                                        os.path.join(configs, suite)], capture_output=True, text=True)
                    if r.returncode != 0:
                        sys.exit(f"battsim score failed (is the patch applied?):\n{r.stderr}")
                    s = json.loads(r.stdout)["summary"]
                    row.append(f"{suite} warned in time {s['early_warnings']['joint']['count']}/"
                               f"{s['early_warnings']['joint']['of']}, false {s['false_warnings']['joint']['count']}"
                               f" (undegraded {s['false_warnings_undegraded']['joint']['count']});")
                m100 = os.path.join(configs, "dji-tb47d-6s.json")  # no `joint` section of its own
                set_key(m100, a.key, value)
                row.append("M100 committed config: " + m100_warnings(battsim, m100, data, tmp, range(1, 141)))
                if a.stitched:
                    table = os.path.join(tmp, "stitched.json")
                    shutil.copy(stitched, table)
                    set_key(table, a.key, value)
                    row.append("; stitched table, even flights: " +
                               m100_warnings(battsim, table, data, tmp, range(2, 141, 2)))
                print(" ".join(row), flush=True)


if __name__ == "__main__":
    main()
