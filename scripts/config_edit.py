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
