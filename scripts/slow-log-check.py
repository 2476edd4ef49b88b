#!/usr/bin/env python3
"""The dissertation's four flights written more slowly (README, "Input formats", on --average-ms).

Keeps every k-th row of each flight (k = 1, 2, 3), from each starting row, and replays the
result with the joint estimator on configs/sim-4s.json; with --average-ms also the full log
through `--average-ms MS`. Prints, per log, the capacity at the landing and each warning with
its time into the flight (from the replay's own take-off). A log written every third row
(about 0.2 s, a PX4 log's 5 Hz) is what a slower logger gives without any averaging.

    python3 scripts/slow-log-check.py [--every 1,2,3] [--average-ms 200] [--battsim build/battsim]

Needs ../shared/data (or BATTSIM_DATA_DIR); standard library only; about 20 s.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def replay(battsim, log, extra):
    cmd = [battsim, "replay", log, "-c", os.path.join(ROOT, "configs", "sim-4s.json"), "--estimator", "joint",
           "--json"] + extra
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def describe(summary):
    flight = summary["flight"]
    start = flight["start_s"]
    warnings = ", ".join("%s %.0f s" % (w["name"], w["first_time_s"] - start)
                         for w in summary.get("warnings", []))
    return "%.3f Ah  %s" % (flight["capacity_ah"]["final"], warnings or "no warning")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--every", default="1,2,3", help="keep every k-th row, for each k (comma-separated)")
    ap.add_argument("--average-ms", type=float, default=None, help="also replay the full log with this window")
    ap.add_argument("--battsim", default=os.path.join(ROOT, "build", "battsim"))
    args = ap.parse_args()
    data = os.environ.get("BATTSIM_DATA_DIR", os.path.join(ROOT, "..", "shared", "data"))
    flights = os.path.join(data, "predictive-bms", "flights")
    if not os.path.isdir(flights):
        sys.exit("slow-log-check: no %s (the shared data); set BATTSIM_DATA_DIR" % flights)
    with tempfile.TemporaryDirectory(prefix="slow-log-") as tmp:
        for flight in ("29", "30", "32", "34"):
            rows = [l for l in open(os.path.join(flights, flight + ".csv")).read().splitlines() if l.strip()]
            for k in (int(x) for x in args.every.split(",")):
                for first in range(k):
                    log = os.path.join(tmp, "f%s-every%d-from%d.csv" % (flight, k, first))
                    with open(log, "w") as f:
                        f.write("\n".join(rows[first::k]) + "\n")
                    label = "every row" if k == 1 else "every %d rows from row %d" % (k, first + 1)
                    print("flight %s, %-24s %s" % (flight, label + ":", describe(replay(args.battsim, log, []))))
            if args.average_ms is not None:
                log = os.path.join(flights, flight + ".csv")
                label = "--average-ms %g" % args.average_ms
                summary = replay(args.battsim, log, ["--average-ms", "%g" % args.average_ms])
                print("flight %s, %-24s %s" % (flight, label + ":", describe(summary)))


if __name__ == "__main__":
    main()
