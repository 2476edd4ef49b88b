#!/bin/sh
# Interrupts N parallel batch runs (Ctrl-C at a random moment in their first 0.25 s) and
# counts the temporary files they leave in --out; any is a bug in the signal cleanup.
#   sh scripts/interrupt-check.sh [N] [BATTSIM]   (defaults: 100, build/battsim)
# Needs the shared data (the Matrice 100 manifest) and python3 for the random moments.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
n=${1:-100}
bin=${2:-$root/build/battsim}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT INT TERM
left=0
runs=0
for i in $(seq 1 "$n"); do
  rm -rf "$dir/out" "$dir/t.md"
  t=$(python3 -c "import random; random.seed($i); print(round(random.uniform(0.03, 0.25), 3))")
  timeout -s INT "$t" "$bin" batch -m "$root/configs/manifests/cmu-m100.json" -j2 --out "$dir/out" -o "$dir/t.md" \
    >/dev/null 2>&1 || true
  c=$(find "$dir" -name '*.tmp.*' | wc -l)
  left=$((left + c))
  runs=$((runs + 1))
done
echo "interrupt-check: $left temporary file(s) left over $runs interrupted batch -j2 runs"
[ "$left" -eq 0 ]
