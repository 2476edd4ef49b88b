#!/usr/bin/env python3
"""What a ground station hears from the monitor's MAVLink telemetry (docs/telemetry.md).

Replays logs with `battsim replay --estimator joint --json --tlog`, reads the .tlog back with
its own decoder (checksums checked) and prints, per log: frames and bytes per second of log
time, each STATUSTEXT with its flight time against the summary's warning, and the last
BATTERY_STATUS. Without LOGs: the dissertation's four flights (configs/sim-4s.json) and every
scenario of --suite (simulated into a scratch directory, each with its own monitor config).

    python3 scripts/telemetry-check.py [--suite configs/scenarios] [LOG ...] [-c CONFIG] [--args "REPLAY OPTIONS"]

The last line counts the verdicts withdrawn in flight (telemetry.clear_hold_s) and how many of
them were warned again later, e.g. on the Matrice 100 fleet:

    python3 scripts/telemetry-check.py ../shared/data/cmu-m100/flights/*.csv -c configs/dji-tb47d-6s.json \
        --args "--time-col time --time-unit s --voltage-col battery_voltage --current-col battery_current --current-unit A"

Standard library only; about a minute for the suite on two cores.
"""
import argparse
import glob
import json
import os
import struct
import subprocess
import sys
import tempfile

from mavlink_stream import frames, text as status_text

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BATTSIM = os.path.join(ROOT, "build", "battsim")
DATA = os.environ.get("BATTSIM_DATA_DIR", os.path.join(ROOT, "..", "shared", "data"))
REPEAT_S = 30  # telemetry.text_repeat_s's default
CHARGE = {0: "undefined", 1: "ok", 2: "low", 3: "critical", 6: "unhealthy"}
# A withdrawal's opening (telemetry.clear_hold_s) → the first 16 characters of what it withdraws.
WITHDRAWS = {"battsim: short flight": "battsim: flight ", "battsim: low capacity": "battsim: low cap",
             "battsim: high resistance": "battsim: high re"}


TOTALS = {"logs": 0, "warned": 0, "withdrawn": 0, "warned again": 0}


def check(log, config, tmp, extra=()):
    tlog = os.path.join(tmp, "out.tlog")
    r = subprocess.run([BATTSIM, "replay", log, "-c", config, "--estimator", "joint", "--json", "--tlog", tlog] + list(extra),
                       capture_output=True, text=True)
    if r.returncode != 0:
        return "%s: replay failed: %s" % (os.path.basename(log), r.stderr.strip())
    summary = json.loads(r.stdout)
    data = open(tlog, "rb").read()
    fr = frames(data, tlog=True)
    span = fr[-1][0] - fr[0][0] if len(fr) > 1 else 1.0
    start = (summary.get("flight") or {}).get("start_s")
    lines = ["%s: %d frames, %.0f B/s on the wire" % (os.path.basename(log), len(fr), (len(data) - 8 * len(fr)) / span)]
    warned = {w["name"]: w for w in summary.get("warnings", [])}
    said = {}  # a sentence's first 16 characters → [its first line's index, times said again]
    repeats = []
    for t, msgid, p in fr:
        if msgid == 253:
            text = status_text(p)
            if text[:16] in said:
                said[text[:16]][1] += 1
                continue
            at = "flight %.1f s" % (t - start) if start is not None and t >= start else "log %.1f s (on the ground)" % t
            lines.append("  %s  \"%s\"" % (at, text))
            withdrawn = WITHDRAWS.get(text.split(" cleared,")[0]) if " cleared," in text else None
            if withdrawn in said:  # a withdrawn verdict said again later is news, not a repeat
                repeats.append(said.pop(withdrawn))
            if withdrawn is None:
                said[text[:16]] = [len(lines) - 1, 0]
    texts = [status_text(p) for t, m, p in fr if m == 253]
    cleared = [i for i, x in enumerate(texts) if x.startswith("battsim: short flight cleared")]
    TOTALS["logs"] += 1
    TOTALS["warned"] += any(x.startswith("battsim: flight ") for x in texts)
    TOTALS["withdrawn"] += len(cleared)
    TOTALS["warned again"] += sum(any(x.startswith("battsim: flight ") for x in texts[i + 1:]) for i in cleared)
    for index, again in repeats + list(said.values()):
        if again:
            lines[index] += " (said again %d time%s in flight, at least %g s apart)" % (again, "s"[:again > 1], REPEAT_S)
    batt = [p for t, m, p in fr if m == 147][-1]
    remaining, time_s, state = struct.unpack_from("<b", batt, 35)[0], struct.unpack_from("<i", batt, 36)[0], batt[40]
    lines.append("  summary warnings: %s; last battery status: %d %%, %d s left, %s" % (
        ", ".join("%s at %s" % (n, "flight %.1f s" % w["flight_time_s"] if w["flight_time_s"] is not None
                                 else "log %.1f s (on the ground)" % w["first_time_s"])
                  for n, w in warned.items()) or "none",
        remaining, time_s, CHARGE.get(state, state)))
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("logs", nargs="*")
    ap.add_argument("-c", "--config", default=os.path.join(ROOT, "configs", "sim-4s.json"))
    ap.add_argument("--suite", default=os.path.join(ROOT, "configs", "scenarios"))
    ap.add_argument("--args", default="", help="more replay options for every log (column mapping)")
    a = ap.parse_args()
    if not os.path.exists(BATTSIM):
        sys.exit("telemetry-check: build first (build/battsim)")
    with tempfile.TemporaryDirectory() as tmp:
        runs = [(log, a.config) for log in a.logs]
        if not a.logs:
            runs = [(os.path.join(DATA, "predictive-bms", "flights", "%d.csv" % n), a.config) for n in (29, 30, 32, 34)]
            for scenario in sorted(glob.glob(os.path.join(a.suite, "*.json"))):
                log = os.path.join(tmp, os.path.basename(scenario)[:-5] + ".csv")
                subprocess.run([BATTSIM, "simulate", scenario, "-o", log], check=True, capture_output=True)
                cfg = json.load(open(scenario))["monitor_config"]
                runs.append((log, os.path.normpath(os.path.join(os.path.dirname(scenario), cfg))))
        for log, config in runs:
            print(check(log, config, tmp, a.args.split()))
    print("%(logs)d logs: a short flight warned on %(warned)d; %(withdrawn)d withdrawn in flight, "
          "%(warned again)d of them warned again later" % TOTALS)


if __name__ == "__main__":
    main()
