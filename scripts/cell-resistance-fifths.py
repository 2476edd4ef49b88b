#!/usr/bin/env python3
"""Each cell's in-flight resistance, fifth by fifth, on the reference logger's raw flights.

Cell k's resistance is the least-squares slope of −ΔV_k on ΔI over pairs two samples apart
(about 0.13 s) with |ΔI| > 3 A, in five equal slices of the flight (current above 8 A).
Prints each cell's value and cell 1's and cell 4's excess over the mean of cells 2 and 3,
in milliohms and as a ratio: a cell's own resistance falls as the pack warms in flight,
a wire's or a connector's does not, so a constant excess in milliohms points at a path in
series with the reading rather than at the cell. Standard library only.

    python3 scripts/cell-resistance-fifths.py ../shared/data/predictive-bms/flights/{29,30,32,34}.csv
"""
import csv
import sys

FLYING_A = 8.0
MIN_STEP_A = 3.0
LAG = 2
MAX_PAIR_S = 0.3
SLICES = 5


def read(path):
    rows = []
    with open(path, newline="") as f:
        for r in csv.reader(f):
            if len(r) < 8:
                continue
            rows.append((float(r[0]) / 1000.0, float(r[6]) / 1000.0, [float(x) for x in r[2:6]]))
    return rows


def main(paths):
    for path in paths:
        rows = read(path)
        flying = [k for k, r in enumerate(rows) if r[1] > FLYING_A]
        t0, t1 = rows[flying[0]][0], rows[flying[-1]][0]
        print(path)
        print("  fifth  pairs   cell 1   cell 2   cell 3   cell 4 (mΩ)   cell 1 − mean(2,3)   cell 4 − mean(2,3)")
        for s in range(SLICES):
            lo = t0 + (t1 - t0) * s / SLICES
            hi = t0 + (t1 - t0) * (s + 1) / SLICES
            sxx = 0.0
            sxy = [0.0] * 4
            n = 0
            for k in range(LAG, len(rows)):
                t, i, v = rows[k]
                tp, ip, vp = rows[k - LAG]
                if not (lo <= t < hi) or t - tp > MAX_PAIR_S or i < 1.0 or ip < 1.0:
                    continue
                di = i - ip
                if abs(di) <= MIN_STEP_A:
                    continue
                sxx += di * di
                for c in range(4):
                    sxy[c] += di * (v[c] - vp[c])
                n += 1
            if sxx == 0.0:
                continue
            r = [-x / sxx * 1000.0 for x in sxy]
            inner = 0.5 * (r[1] + r[2])
            print(f"  {s + 1:5d} {n:6d} {r[0]:8.2f} {r[1]:8.2f} {r[2]:8.2f} {r[3]:8.2f}"
                  f"        {r[0] - inner:+6.2f} ({r[0] / inner:4.2f}×)      {r[3] - inner:+6.2f} ({r[3] / inner:4.2f}×)")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
