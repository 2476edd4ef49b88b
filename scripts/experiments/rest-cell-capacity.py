#!/usr/bin/env python3
"""Can the rests before take-off and after landing name a weak cell by capacity?

At rest no current flows, so neither a lead in a cell's reading (cell 1 against the
monitor's ground, the last cell across the main lead) nor the cell's own resistance is in
it: each cell's state of charge is read off the OCV table from its resting voltage before
take-off and again 30 s after the landing, and a cell's capacity against the others' is
the ratio of the charge drawn to its fall in state of charge (the charge is the same for
all cells of a series string, so only the falls are compared). A cell is named when it
is more than 10 % (+ margin) below the median of the others, and not when a neighbour
sharing a balance tap reads strong by more than half of that (a tap error moves the two
cells sharing it apart; a weak cell sits below all alike).

Variants, all on the same logs:
  as read      the cells' resting voltages as logged;
  offsets      each cell's reading before a take-off from full (>= 95 %) taken as the
               balance charger left it, equal to the others: the differences are the
               taps' offsets and are removed from the readings after the landing;
  tail TAU     offsets, and the pack's rest voltage still to come after the landing
               window extrapolated as one exponential with time constant TAU s (the
               unrelaxed polarisation is common in volts, not in state of charge).

Simulates every scenario of the suites (N copies, seed + 7919·k as `battsim score
--copies` does), takes the joint estimator's named cells from `battsim score --json`, and
prints per variant: the median and 95th-percentile error of the cells' deficits against
the truth, the measured − true deficit of every cell truly more than 8 % weak, and the
outlier flights named by the in-flight check alone and together with the rests (and the
rests' false alarms). Then the dissertation's flights with `configs/sim-4s.json`'s table.
Standard library only (twenty-fifth session, docs/estimator.md).

    python3 scripts/experiments/rest-cell-capacity.py [--suites scenarios,scenarios-holdout] [--copies 4]
"""
import argparse, bisect, glob, json, math, os, statistics, subprocess, sys, tempfile
from concurrent.futures import ThreadPoolExecutor

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from config_edit import battsim_in, shared_data_dir  # noqa: E402
LOADED_A = 3.0      # a sample above this is in flight
REST_A = 1.0        # ... at or below this at rest
SETTLE_S = 30.0     # the landing rest is read from this long after the last loaded sample


def read_log(path):
    """(time_s, current_a, [cell_v]) rows of a headered CSV or a reference raw log."""
    rows = []
    with open(path) as f:
        first = f.readline()
        if first.startswith("time_s"):
            head = first.strip().split(",")
            cells = [i for i, h in enumerate(head) if h.startswith("cell")]
            ti, ii = head.index("time_s"), head.index("current_a")
            for line in f:
                p = line.strip().split(",")
                rows.append((float(p[ti]), float(p[ii]), [float(p[i]) for i in cells]))
        else:  # time_ms, bus_v, cell1..4_v, current_ma, shunt_mv
            f.seek(0)
            for line in f:
                p = line.strip().rstrip(",").split(",")
                if len(p) >= 8:
                    rows.append((float(p[0]) / 1000.0, float(p[6]) / 1000.0, [float(x) for x in p[2:6]]))
    return rows


def soc_at(table, v):
    """State of charge of one cell at rest voltage v (table: equally spaced, 0 → 1)."""
    n = len(table)
    if v <= table[0]:
        return 0.0
    if v >= table[-1]:
        return 1.0 + (v - table[-1]) / ((table[-1] - table[-2]) * (n - 1))
    i = bisect.bisect_right(table, v) - 1
    return (i + (v - table[i]) / (table[i + 1] - table[i])) / (n - 1)


def median(xs):
    xs = sorted(xs)
    m = len(xs)
    return xs[m // 2] if m % 2 else 0.5 * (xs[m // 2 - 1] + xs[m // 2])


def rest_deficits(rows, table, variant, tau_s=0.0):
    """Per-cell capacity deficits against the median of the others, or None (no rests,
    not from full where the offsets need it, or less than 25 % of charge drawn)."""
    loaded = [i for i, r in enumerate(rows) if r[1] > LOADED_A]
    if not loaded:
        return None
    i0, i1 = loaded[0], loaded[-1]
    while i0 > 0 and rows[i0 - 1][1] > REST_A:  # back over the take-off ramp
        i0 -= 1
    j = i0 - 1
    while j >= 0 and rows[j][1] <= REST_A:
        j -= 1
    pre = rows[j + 1:i0]  # the last rest before the take-off
    post = [r for r in rows[i1 + 1:] if r[0] >= rows[i1][0] + SETTLE_S and r[1] <= REST_A]
    if len(pre) < 20 or len(post) < 40:
        return None
    n = len(rows[0][2])
    v0 = [statistics.fmean(r[2][k] for r in pre) for k in range(n)]
    m0 = statistics.fmean(v0)
    s0 = soc_at(table, m0)
    if variant == "as read":
        v1 = [statistics.fmean(r[2][k] for r in post) for k in range(n)]
        ds = [soc_at(table, v0[k]) - soc_at(table, v1[k]) for k in range(n)]
    else:
        if s0 < 0.95:
            return None
        late = post[len(post) // 2:]
        tail_v = 0.0
        if tau_s > 0.0:
            early = post[:len(post) // 2]
            t1 = rows[i1][0]
            ta = statistics.fmean(r[0] for r in early) - t1
            tb = statistics.fmean(r[0] for r in late) - t1
            va = statistics.fmean(statistics.fmean(r[2]) for r in early)
            vb = statistics.fmean(statistics.fmean(r[2]) for r in late)
            amp = (vb - va) / (math.exp(-ta / tau_s) - math.exp(-tb / tau_s))
            tail_v = amp * math.exp(-tb / tau_s)
        v1 = [statistics.fmean(r[2][k] for r in late) + tail_v for k in range(n)]
        ds = [s0 - soc_at(table, v1[k] - (v0[k] - m0)) for k in range(n)]
    if statistics.fmean(ds) < 0.25:
        return None
    return [1.0 - median(ds[:k] + ds[k + 1:]) / ds[k] for k in range(n)]


def name_cell(deficit, margin):
    if deficit is None:
        return None
    k = max(range(len(deficit)), key=lambda i: deficit[i])
    if deficit[k] <= 0.10 + margin:
        return None
    for nb in (k - 1, k + 1):
        if 0 <= nb < len(deficit) and -deficit[nb] > 0.5 * deficit[k]:
            return None  # a balance-tap artefact
    return k + 1


def simulate(args):
    battsim, tmp, scen, k = args
    s = json.load(open(scen))
    name = s["name"] + (f"@{k}" if k else "")
    log = os.path.join(tmp, name + ".csv")
    subprocess.run([battsim, "simulate", scen, "-o", log, "--seed", str(s["seed"] + 7919 * k)], check=True,
                   capture_output=True)
    truth = json.load(open(log[:-4] + ".truth.json"))
    caps = [c["capacity_ah"] for c in truth["pack"]["per_cell"]]
    true_def = [1.0 - caps[i] / median(caps[:i] + caps[i + 1:]) for i in range(len(caps))]
    return name, read_log(log), truth["monitor_config"]["joint"]["ocv_cell_voltage_v"], true_def


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--suites", default="scenarios,scenarios-holdout")
    ap.add_argument("--copies", type=int, default=4)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    a = ap.parse_args()
    battsim = battsim_in(a.build)
    variants = [("as read", 0.0), ("offsets", 0.0), ("tail 22 s", 22.0), ("tail 40 s", 40.0)]
    for suite in a.suites.split(","):
        sdir = os.path.join(ROOT, "configs", suite)
        scored = json.loads(subprocess.run([battsim, "score", "-j2", "--copies", str(a.copies), "--json", sdir],
                                           check=True, capture_output=True, text=True).stdout)
        joint = {f["name"]: (f["outlier_cells"], f["estimators"]["joint"]["named_cell"]) for f in scored["flights"]}
        scens = [p for p in sorted(glob.glob(os.path.join(sdir, "*.json")))
                 if json.load(open(p)).get("schema") == "battsim.scenario"]
        with tempfile.TemporaryDirectory() as tmp, ThreadPoolExecutor(2) as pool:
            flights = list(pool.map(simulate, [(battsim, tmp, p, k) for p in scens for k in range(a.copies)]))
        outliers = sum(1 for n, *_ in flights if joint[n][0])
        in_flight = sum(1 for n, *_ in flights if joint[n][1] and joint[n][1] in joint[n][0])
        print(f"{suite}: {len(flights)} flights, {outliers} with an outlier cell, {in_flight} named in flight")
        for label, tau in variants:
            variant = "as read" if label == "as read" else "offsets"
            errs, weak, read = [], [], 0
            res = {}
            for name, rows, table, true_def in flights:
                d = rest_deficits(rows, table, variant, tau)
                res[name] = d
                if d is None:
                    continue
                read += 1
                errs += [abs(x - y) for x, y in zip(d, true_def)]
                weak += [x - y for x, y in zip(d, true_def) if y > 0.08]
            errs.sort()
            line = (f"  {label:10s} read {read}: |deficit error| median {statistics.median(errs):.4f}, "
                    f"95th pct {errs[int(0.95 * len(errs))]:.4f}; cells > 8 % weak, measured − true: "
                    + " ".join(f"{x:+.3f}" for x in weak))
            print(line)
            for margin in (0.0, 0.01):
                named = false = added = 0
                for name, *_ in flights:
                    out, jn = joint[name]
                    rn = name_cell(res[name], margin)
                    union = jn if jn else rn
                    named += bool(union and union in out)
                    false += bool(rn and rn not in out)
                    added += bool(rn and rn in out and not jn)
                print(f"    margin {margin:.2f}: named with the rests {named}/{outliers} "
                      f"(+{added}), the rests' false alarms {false}")
    table = json.load(open(os.path.join(ROOT, "configs", "sim-4s.json")))["joint"]["ocv_cell_voltage_v"]
    data = shared_data_dir(ROOT)
    print("dissertation flights (configs/sim-4s.json's table), deficits of cells 1..4:")
    for n in (29, 30, 32, 34):
        path = os.path.join(data, "predictive-bms", "flights", f"{n}.csv")
        if not os.path.exists(path):
            print(f"  {n}: {path} not found")
            continue
        rows = read_log(path)
        for label, tau in variants:
            d = rest_deficits(rows, table, "as read" if label == "as read" else "offsets", tau)
            print(f"  {n} {label:10s} " + ("no landing rest of 30 s + 40 samples" if d is None
                                          else " ".join(f"{x:+.3f}" for x in d)))


if __name__ == "__main__":
    main()
