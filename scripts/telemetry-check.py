#!/usr/bin/env python3
"""What a ground station hears from the monitor's MAVLink telemetry (docs/telemetry.md).

Replays logs with `battsim replay --estimator joint --json --tlog`, reads the .tlog back with
its own decoder (checksums checked) and prints, per log: frames and bytes per second of log
time, each STATUSTEXT with its flight time against the summary's warning, and the last
BATTERY_STATUS. Without LOGs: the dissertation's four flights (configs/sim-4s.json) and every
scenario of --suite (simulated into a scratch directory, each with its own monitor config).

    python3 scripts/telemetry-check.py [--suite configs/scenarios] [LOG ...] [-c CONFIG]

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

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BATTSIM = os.path.join(ROOT, "build", "battsim")
DATA = os.environ.get("BATTSIM_DATA_DIR", os.path.join(ROOT, "..", "shared", "data"))
CRC_EXTRA = {0: 50, 147: 154, 253: 83}
FULL_LENGTH = {0: 9, 147: 54, 253: 54}
CHARGE = {0: "undefined", 1: "ok", 2: "low", 3: "critical", 6: "unhealthy"}


def crc(data, c=0xFFFF):
    for b in data:
        c ^= b
        for _ in range(8):
            c = (c >> 1) ^ 0x8408 if c & 1 else c >> 1
    return c


def frames(tlog):
    """(time_s, msgid, payload zero-filled) for every frame; raises on a bad one."""
    out, i = [], 0
    while i < len(tlog):
        t = struct.unpack_from(">Q", tlog, i)[0] * 1e-6
        i += 8
        if tlog[i] != 0xFD:
            raise ValueError("no frame at byte %d" % i)
        n = tlog[i + 1]
        msgid = tlog[i + 7] | tlog[i + 8] << 8 | tlog[i + 9] << 16
        if crc(tlog[i + 1:i + 10 + n] + bytes([CRC_EXTRA[msgid]])) != struct.unpack_from("<H", tlog, i + 10 + n)[0]:
            raise ValueError("bad checksum at byte %d" % i)
        out.append((t, msgid, tlog[i + 10:i + 10 + n] + bytes(FULL_LENGTH[msgid] - n)))
        i += 12 + n
    return out


def check(log, config, tmp):
    tlog = os.path.join(tmp, "out.tlog")
    r = subprocess.run([BATTSIM, "replay", log, "-c", config, "--estimator", "joint", "--json", "--tlog", tlog],
                       capture_output=True, text=True)
    if r.returncode != 0:
        return "%s: replay failed: %s" % (os.path.basename(log), r.stderr.strip())
    summary = json.loads(r.stdout)
    data = open(tlog, "rb").read()
    fr = frames(data)
    span = fr[-1][0] - fr[0][0] if len(fr) > 1 else 1.0
    start = (summary.get("flight") or {}).get("start_s")
    lines = ["%s: %d frames, %.0f B/s on the wire" % (os.path.basename(log), len(fr), (len(data) - 8 * len(fr)) / span)]
    warned = {w["name"]: w for w in summary.get("warnings", [])}
    for t, msgid, p in fr:
        if msgid == 253:
            text = p[1:51].split(b"\0")[0].decode()
            at = "flight %.1f s" % (t - start) if start is not None and t >= start else "log %.1f s (on the ground)" % t
            lines.append("  %s  \"%s\"" % (at, text))
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
            print(check(log, config, tmp))


if __name__ == "__main__":
    main()
