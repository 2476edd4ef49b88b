#!/usr/bin/env python3
"""Voltage recovery after landing on the reference logger's raw flights.

Fits the rest after the last take-off current with one and with two exponentials
(a grid over the time constants, least squares for the amplitudes) and prints the
polarisation each part carried, in volts and as a resistance at the flight's last
30 s of current. Standard library only.

    python3 scripts/rest-relaxation.py ../shared/data/predictive-bms/flights/{29,30,32,34}.csv
"""
import csv
import math
import sys

FLYING_A = 4.5       # the data README's ground idle is at most 4.5 A
STEP_V = 0.05        # a larger step between rest samples is the logger powering off
SKIP_SAMPLES = 2     # the current's own step settles over the first two samples


def least_squares(columns, y):
    """Coefficients of y on the columns, and the mean squared residual."""
    n = len(columns)
    m = [[sum(a * b for a, b in zip(columns[i], columns[j])) for j in range(n)]
         + [sum(a * b for a, b in zip(columns[i], y))] for i in range(n)]
    for k in range(n):
        p = max(range(k, n), key=lambda r: abs(m[r][k]))
        m[k], m[p] = m[p], m[k]
        if abs(m[k][k]) < 1e-15:
            return None, math.inf
        for r in range(n):
            if r != k:
                f = m[r][k] / m[k][k]
                for c in range(k, n + 1):
                    m[r][c] -= f * m[k][c]
    coef = [m[i][n] / m[i][i] for i in range(n)]
    residual = sum((sum(coef[j] * columns[j][k] for j in range(n)) - y[k]) ** 2 for k in range(len(y)))
    return coef, residual / len(y)


def best_fit(t, v, grids):
    """Best fit of v = a + Σ b_k·exp(−t/τ_k) over the product of the τ grids."""
    ones = [1.0] * len(t)
    best = None

    def search(taus, rest):
        nonlocal best
        if not rest:
            coef, ms = least_squares([ones] + [[math.exp(-x / tau) for x in t] for tau in taus], v)
            if coef and (best is None or ms < best[0]):
                best = (ms, taus, coef)
            return
        for tau in rest[0]:
            search(taus + [tau], rest[1:])

    search([], grids)
    return best


class BadLog(Exception):
    pass


def read_raw(path):
    """time_s, bus voltage, current (A) of a raw flight; BadLog names file, line and column."""
    t, v, i = [], [], []
    try:
        with open(path, newline="") as f:
            for line, row in enumerate(csv.reader(f), start=1):
                if not row:
                    continue
                for col in (1, 2, 7):
                    try:
                        value = float(row[col - 1]) if len(row) >= col else None
                    except ValueError:
                        value = None
                    if value is None or not math.isfinite(value):
                        found = repr(row[col - 1]) if len(row) >= col else "nothing"
                        raise BadLog(f"{path}:{line}:{col}: expected a number (raw flight log: time_ms, bus V, "
                                 f"4 cells, current_ma, ...), found {found}")
                t.append(float(row[0]) / 1000.0)   # time_ms
                v.append(float(row[1]))            # bus voltage
                i.append(float(row[6]) / 1000.0)   # current_ma, positive = discharge
    except OSError as e:
        raise BadLog(f"{path}: cannot read: {e.strerror}")
    if not t:
        raise BadLog(f"{path}: no rows")
    return t, v, i


def main(paths):
    fast = [0.5, 1, 2, 3, 5, 8]
    slow = list(range(6, 40, 2)) + list(range(40, 600, 10))
    single = [x * 0.5 for x in range(1, 20)] + list(range(10, 400, 5))
    failed = 0
    for path in paths:
        try:
            t, v, i = read_raw(path)
        except BadLog as e:  # report it and go on with the other files
            print(e, file=sys.stderr)
            failed += 1
            continue
        flying = [k for k in range(len(i)) if i[k] > FLYING_A]
        if not flying:
            print(f"{path}: no flight")
            continue
        land = flying[-1]
        end = len(t)
        while end > land + SKIP_SAMPLES + 1 and abs(v[end - 1] - v[end - 2]) > STEP_V:
            end -= 1
        first = land + SKIP_SAMPLES
        rt = [x - t[first] for x in t[first:end]]
        rv = v[first:end]
        last = [i[k] for k in range(len(t)) if t[land] - 30.0 < t[k] <= t[land]]
        current = sum(last) / len(last)
        duration = rt[-1] if rt else 0.0
        print(f"{path}: rest {duration:.1f} s after landing, {rv[0] if rv else 0:.2f} -> "
              f"{rv[-1] if rv else 0:.2f} V; last 30 s of flight at {current:.1f} A")
        if duration < 20.0:
            print("  rest too short to fit")
            continue
        ms, taus, coef = best_fit(rt, rv, [single])
        print(f"  one exponential: tau {taus[0]:g} s, {-coef[1]:.3f} V, rms {1000 * math.sqrt(ms):.1f} mV")
        ms, taus, coef = best_fit(rt, rv, [fast, slow])
        parts = ", ".join(f"tau {tau:g} s: {-b:.3f} V ({-1000 * b / current:.1f} mOhm)" for tau, b in zip(taus, coef[1:]))
        print(f"  two exponentials: {parts}; rms {1000 * math.sqrt(ms):.1f} mV")
    return failed


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    sys.exit(1 if main(sys.argv[1:]) else 0)
