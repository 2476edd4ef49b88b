#!/bin/sh
# Prints the figures of docs/benchmarks.md: monitor update cost (ns, and x86-64
# instructions per update under callgrind), replay throughput of one log, batch
# throughput on the CMU flights with 1 and 2 jobs, and peak memory of replays of a log
# made 1x, 10x and 100x longer. Needs the shared data; valgrind for the instruction count.
#   BATTSIM=build/battsim BATTSIM_DATA_DIR=../shared/data sh scripts/bench.sh
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${BATTSIM:-$root/build/battsim}
data=${BATTSIM_DATA_DIR:-$root/../shared/data}
# Absolute, since the manifests resolve it from their own folder (a relative one found no logs).
data=$(cd "$data" 2>/dev/null && pwd) || { echo "bench: no data directory ${BATTSIM_DATA_DIR:-$root/../shared/data}" >&2; exit 2; }
export BATTSIM_DATA_DIR="$data"  # the manifests find the logs through it
min_time=${BENCH_MIN_TIME:-2}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM

raw="$data/predictive-bms/flights/30.csv"
cmu="$data/cmu-m100/flights/70.csv"
ref_cfg="$root/configs/reference-modified.json"
cmu_manifest="$root/configs/manifests/cmu-m100.json"
for f in "$bin" "$raw" "$cmu"; do
  [ -e "$f" ] || { echo "bench: missing $f (build first; point BATTSIM_DATA_DIR at the shared data)" >&2; exit 2; }
done

field() { sed -n "s/^$1: //p"; }  # value of one "key: value" line of `battsim bench`
# `battsim bench MODE LOG ...` with the settings of each data set (the CMU ones as in
# configs/manifests/cmu-m100.json, spelt out so that derived logs work too).
bench_raw() { mode=$1; shift; "$bin" bench "$mode" "$@" -c "$ref_cfg"; }
bench_cmu() {
  mode=$1; shift
  "$bin" bench "$mode" "$@" -c "$root/configs/dji-tb47d-6s.json" --time-col time --time-unit s \
    --voltage-col battery_voltage --current-col battery_current --current-unit A
}

# LOG, copies, time scale (1 = seconds, 1000 = ms), header lines: the log repeated with
# its time shifted so it runs on (each copy starts one last-step after the previous end).
repeat_log() {
  awk -F, -v OFS=, -v n="$2" -v hdr="$4" -v scale="$3" '
    FNR == NR { if (FNR > hdr) { prev = last; last = $1 } ; next }
    FNR <= hdr { if (copy == 0) print; next }
    FNR == hdr + 1 { span = last + (last - prev); off = copy * span; copy++ }
    { $1 = (scale == 1) ? sprintf("%.3f", $1 + off) : sprintf("%d", $1 + off); print }
  ' "$1" $(i=0; while [ $i -lt "$2" ]; do printf '%s ' "$1"; i=$((i + 1)); done)
}

echo "# battsim benchmarks ($(date -u +%Y-%m-%dT%H:%MZ))"
echo
echo "## machine"
echo "cpu: $(sed -n 's/^model name[^:]*: //p' /proc/cpuinfo | head -1), $(nproc) cores online"
echo "memory: $(awk '/MemTotal/ {printf "%.1f GiB", $2 / 1048576}' /proc/meminfo)"
echo "kernel: $(uname -sr)"
echo "compiler: $(${CXX:-c++} --version | head -1)"
echo "load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "battsim: $("$bin" --version)"

echo
echo "## monitor update cost (core::Monitor::update, samples held in memory)"
for est in reference joint; do
  out=$(bench_raw monitor "$raw" --estimator "$est" --min-time "$min_time")
  echo "4S raw flight 30, $est: $(echo "$out" | field ns_per_update) ns/update wall, $(echo "$out" | field cpu_ns_per_update) CPU, over $(echo "$out" | field updates) updates"
  out=$(bench_cmu monitor "$cmu" --estimator "$est" --min-time "$min_time")
  echo "6S CMU flight 70, $est: $(echo "$out" | field ns_per_update) ns/update wall, $(echo "$out" | field cpu_ns_per_update) CPU, over $(echo "$out" | field updates) updates"
done
if command -v valgrind >/dev/null 2>&1 && command -v callgrind_annotate >/dev/null 2>&1; then
  # Only Monitor::update and what it calls is counted (--toggle-collect).
  count() {  # label, then the arguments of `battsim bench monitor`
    label=$1; shift
    out=$(valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.out" \
            '--toggle-collect=battsim::core::Monitor::update*' \
            "$bin" bench monitor "$@" --passes 1 2>/dev/null)
    updates=$(echo "$out" | field updates)
    total=$(callgrind_annotate "$tmp/cg.out" 2>/dev/null | awk '/PROGRAM TOTALS/ { gsub(",", "", $1); print $1 }')
    echo "callgrind, $label: $total instructions / $updates updates = $((total / updates)) instructions per update"
  }
  for est in reference joint; do
    count "raw, $est" "$raw" -c "$ref_cfg" --estimator "$est"
    # (the CMU log is in the manifest, which gives its columns and config)
    count "cmu, $est" "$cmu" --manifest "$cmu_manifest" --estimator "$est"
  done
  count "raw, joint, OCV table (configs/sim-4s.json)" "$raw" -c "$root/configs/sim-4s.json" --estimator joint
  count "raw, reference, fitted model extensions (configs/fitted/pbms-flight30-cnhl5.json)" "$raw" \
    -c "$root/configs/fitted/pbms-flight30-cnhl5.json" --estimator reference
else
  echo "callgrind: valgrind not installed, instruction count skipped"
fi

echo
echo "## replay throughput (end to end: open, parse, monitor, summary; one core)"
repeat_log "$raw" 10 1000 0 > "$tmp/raw10.csv"
repeat_log "$cmu" 10 1 1 > "$tmp/cmu10.csv"
for log in "$raw" "$tmp/raw10.csv" "$cmu" "$tmp/cmu10.csv"; do
  case $log in
    *raw10.csv|*/30.csv) out=$(bench_raw replay "$log" --min-time "$min_time") ;;
    *) out=$(bench_cmu replay "$log" --min-time "$min_time") ;;
  esac
  echo "$(basename "$log") ($(wc -c < "$log") bytes, $(echo "$out" | field runs) runs): $(echo "$out" | field samples_per_s) samples/s, $(echo "$out" | field mb_per_s) MB/s wall, $(echo "$out" | field mb_per_cpu_s) MB per CPU-second, $(echo "$out" | field cpu_ns_per_sample) CPU ns/sample"
done

echo
echo "## batch throughput (140 CMU M100 flights, $(du -sb "$data/cmu-m100/flights" | cut -f1) bytes)"
for jobs in 1 2; do
  out=$("$bin" bench batch --manifest "$cmu_manifest" --jobs $jobs --min-time "$min_time")
  echo "jobs $jobs, $(echo "$out" | field runs) batches: $(echo "$out" | field seconds) s wall, $(echo "$out" | field cpu_seconds) s CPU, $(echo "$out" | field logs_per_s) logs/s, $(echo "$out" | field samples_per_s) samples/s, $(echo "$out" | field mb_per_s) MB/s, $(echo "$out" | field mb_per_cpu_s) MB per CPU-second, peak $(echo "$out" | field peak_rss_kib) KiB"
done

echo
echo "## peak memory of one replay vs log length (ru_maxrss of a fresh process)"
# The summary keeps at most 16384 time buckets of the flight (SummaryAccumulator), so
# memory grows until a flight of ~16k samples and stays flat beyond.
for n in 1 10 100 300; do
  repeat_log "$cmu" $n 1 1 > "$tmp/cmu_x$n.csv"
  out=$(bench_cmu replay "$tmp/cmu_x$n.csv" --min-runs 1 --min-time 0)
  echo "CMU 70 x$n: $(wc -c < "$tmp/cmu_x$n.csv") bytes, $(echo "$out" | field samples) samples, peak $(echo "$out" | field peak_rss_kib) KiB"
  rm -f "$tmp/cmu_x$n.csv"
done
for n in 1 10 100; do
  repeat_log "$raw" $n 1000 0 > "$tmp/raw_x$n.csv"
  out=$(bench_raw replay "$tmp/raw_x$n.csv" --min-runs 1 --min-time 0)
  echo "raw 30 x$n: $(wc -c < "$tmp/raw_x$n.csv") bytes, $(echo "$out" | field samples) samples, peak $(echo "$out" | field peak_rss_kib) KiB"
  rm -f "$tmp/raw_x$n.csv"
done
