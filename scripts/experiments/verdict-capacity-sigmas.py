#!/usr/bin/env python3
"""Should the short-flight verdict weigh its own uncertainty?

Needs the experiment's key, which is not in the code: first

    git apply scripts/experiments/verdict-capacity-sigmas.patch && cmake --build build

and `git apply -R` the same patch afterwards. The key, `joint.verdict_capacity_sigmas` K:
the verdict's total and capacity-only solves take the verdict filter's capacity K of its
standard errors higher, so a flight is short only if it is short at that end. For each K
this copies configs/ to a temporary directory, sets the key in every config with a `joint`
section and in the Matrice 100's, and prints the short flights warned in time and the
false warnings over both suites (`battsim score --copies N`), and the warnings over the 140
CMU Matrice 100 flights (`battsim batch -m configs/manifests/cmu-m100.json --estimator
joint`), which have no ground truth (twenty-fifth session, docs/estimator.md).

    python3 scripts/experiments/verdict-capacity-sigmas.py [--sigmas 0,0.5,1,2,3] [--copies 4]
"""
import argparse, csv, io, json, os, shutil, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from config_edit import edit_joint_sections  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sigmas", default="0,0.5,1,2,3")
    ap.add_argument("--copies", type=int, default=4)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    a = ap.parse_args()
    battsim = os.path.join(a.build, "battsim")
    data = os.path.abspath(os.environ.get("BATTSIM_DATA_DIR", os.path.join(ROOT, "..", "shared", "data")))
    for k in (float(x) for x in a.sigmas.split(",")):
        with tempfile.TemporaryDirectory() as tmp:
            configs = os.path.join(tmp, "configs")
            shutil.copytree(os.path.join(ROOT, "configs"), configs)
            edit_joint_sections(configs, lambda j: j.__setitem__("verdict_capacity_sigmas", k) or True)
            m100 = os.path.join(configs, "dji-tb47d-6s.json")  # no `joint` section of its own
            with open(m100) as f:
                cfg = json.load(f)
            cfg.setdefault("joint", {})["verdict_capacity_sigmas"] = k
            with open(m100, "w") as f:
                json.dump(cfg, f, indent=2)
            row = [f"K {k:g}:"]
            for suite in ("scenarios", "scenarios-holdout"):
                r = subprocess.run([battsim, "score", "-j2", "--copies", str(a.copies), "--json",
                                    os.path.join(configs, suite)], capture_output=True, text=True)
                if r.returncode != 0:
                    sys.exit(f"battsim score failed (is the patch applied?):\n{r.stderr}")
                s = json.loads(r.stdout)["summary"]
                row.append(f"{suite} warned in time {s['early_warnings']['joint']['count']}/"
                           f"{s['early_warnings']['joint']['of']}, false {s['false_warnings']['joint']['count']}"
                           f" (undegraded {s['false_warnings_undegraded']['joint']['count']});")
            r = subprocess.run([battsim, "batch", "-m", os.path.join(configs, "manifests", "cmu-m100.json"),
                                "--estimator", "joint", "--format", "csv", "--no-progress"],
                               capture_output=True, text=True, env=dict(os.environ, BATTSIM_DATA_DIR=data))
            if r.returncode != 0:
                sys.exit(f"battsim batch failed:\n{r.stderr}")
            rows = list(csv.DictReader(io.StringIO(r.stdout)))
            count = lambda w: sum(w in x["warnings"].split(";") for x in rows)
            row.append(f"M100 short flight {count('short_flight')}/{len(rows)} (low capacity {count('low_capacity')},"
                       f" high resistance {count('high_resistance')})")
            print(" ".join(row), flush=True)


if __name__ == "__main__":
    main()
