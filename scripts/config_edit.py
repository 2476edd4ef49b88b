"""Shared by the scripts that score the suites against edited copies of configs/."""
import json
import os


def edit_joint_sections(config_dir, edit):
    """Calls edit(joint_section) on every config in config_dir that has a `joint` section and
    writes those for which it returns True back."""
    for name in sorted(os.listdir(config_dir)):
        path = os.path.join(config_dir, name)
        if not name.endswith(".json") or not os.path.isfile(path):
            continue
        with open(path) as f:
            cfg = json.load(f)
        if not isinstance(cfg.get("joint"), dict) or not edit(cfg["joint"]):
            continue
        with open(path, "w") as f:
            json.dump(cfg, f, indent=2)


def score_edited(battsim, root, edit, suites, columns, jobs=2):
    """Copies root/configs to a temporary directory, applies edit as edit_joint_sections does,
    and yields (suite, report) for `battsim score --json` on each suite of the copy. Raises
    RuntimeError with battsim's message when a score fails."""
    import shutil
    import subprocess
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        configs = os.path.join(tmp, "configs")
        shutil.copytree(os.path.join(root, "configs"), configs)
        edit_joint_sections(configs, edit)
        for suite in suites:
            out = os.path.join(tmp, suite + ".json")
            try:
                r = subprocess.run([battsim, "score", "-j", str(jobs), "--columns", columns, "--json", "-o", out,
                                    os.path.join(configs, suite)], capture_output=True, text=True)
            except OSError as e:
                raise RuntimeError(f"cannot run {battsim} ({e.strerror}); build first or pass --battsim") from e
            if r.returncode != 0:
                raise RuntimeError(f"battsim score failed on {suite}:\n{r.stderr}")
            with open(out) as f:
                yield suite, json.load(f)


def m100_summaries(battsim, root, config, data, tmp):
    """Replays the CMU Matrice 100 manifest's flights with `config` (the joint estimator) and
    returns {flight number: summary JSON}. data: the shared data folder; tmp: a scratch dir."""
    import subprocess
    with open(os.path.join(root, "configs", "manifests", "cmu-m100.json")) as f:
        m = json.load(f)
    m["defaults"]["config"] = config
    m["base_dir"] = os.path.join(data, "cmu-m100", "flights")
    path = os.path.join(tmp, "m100.json")
    with open(path, "w") as f:
        json.dump(m, f)
    out = os.path.join(tmp, "m100-summaries")
    r = subprocess.run([battsim, "batch", "-m", path, "--estimator", "joint", "--out", out, "--no-progress",
                        "-o", os.path.join(tmp, "m100-table.md")], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"battsim batch failed on the Matrice 100 flights:\n{r.stderr}")
    summaries = {}
    for name in os.listdir(out):
        with open(os.path.join(out, name)) as f:
            summaries[int(name[:-len(".json")])] = json.load(f)
        os.remove(os.path.join(out, name))
    os.rmdir(out)
    return summaries


def run_or_exit(args, **kw):
    """Runs a command and returns its stdout; exits with its stderr when it fails."""
    import subprocess
    import sys
    r = subprocess.run(args, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        sys.exit(f"{' '.join(args[:2])} failed:\n{r.stderr}")
    return r.stdout


def suite_scenarios(configs, suite):
    """The scenario files of configs/<suite>, sorted (its README and other JSON left out)."""
    import glob
    out = []
    for p in sorted(glob.glob(os.path.join(configs, suite, "*.json"))):
        with open(p) as f:
            if json.load(f).get("schema") == "battsim.scenario":
                out.append(p)
    return out


def simulate_copy(battsim, tmp, scen, k):
    """Simulates copy k of a scenario (seed + 7919·k, as `battsim score --copies` does) into
    tmp; returns (scenario, its monitor config path, the log's path without .csv, truth)."""
    with open(scen) as f:
        s = json.load(f)
    cfg = os.path.normpath(os.path.join(os.path.dirname(scen), s["monitor_config"]))
    tag = os.path.join(tmp, f"{s['name']}@{k}")
    run_or_exit([battsim, "simulate", scen, "-o", tag + ".csv", "--seed", str(s["seed"] + 7919 * k)])
    with open(tag + ".truth.json") as f:
        truth = json.load(f)
    return s, cfg, tag, truth


def battsim_in(build):
    """The battsim binary in a build directory; exits with a message when it is not built."""
    import sys
    battsim = os.path.join(build, "battsim")
    if not os.access(battsim, os.X_OK):
        sys.exit(f"{battsim} not found: build first")
    return battsim


def shared_data_dir(root):
    """The shared measured data: $BATTSIM_DATA_DIR, else ../shared/data beside the repository."""
    return os.path.abspath(os.environ.get("BATTSIM_DATA_DIR", os.path.join(root, "..", "shared", "data")))
