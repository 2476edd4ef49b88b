#!/bin/sh
# Sample Slurm job array for `battsim batch` over a large fleet: N array tasks each
# replay one shard (--shard K/N), then one dependent job merges the shards' JSON tables
# into the table a single run would have written (md, csv and json).
#
#   sh scripts/slurm-batch.sh submit MANIFEST OUTDIR [SHARDS]   # from a login node
#   sh scripts/slurm-batch.sh local  MANIFEST OUTDIR [SHARDS]   # same steps, no Slurm (a dry run)
#
# Every task must see the same input list (same manifest, paths and working directory):
# `battsim merge` checks the list's digest and refuses shards of different runs.
# Per-log summaries go to OUTDIR/summaries/<log stem>.json as each log completes, so an
# interrupted task loses only the logs it had not finished.
#SBATCH --job-name=battsim-batch
#SBATCH --cpus-per-task=4
#SBATCH --mem-per-cpu=256M
#SBATCH --time=00:30:00
#SBATCH --output=battsim-batch-%A_%a.out
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${BATTSIM:-$root/build/battsim}
mode=${1:-}

run_shard() {  # MANIFEST OUTDIR K N JOBS
  mkdir -p "$2/shards" "$2/summaries"
  rc=0
  "$bin" batch --manifest "$1" --shard "$3/$4" --jobs "$5" --no-progress --format json \
    --output "$2/shards/shard-$3-of-$4.json" --out "$2/summaries" || rc=$?
  # 1 = some logs failed: they are error rows in the shard's table, which merge keeps.
  if [ "$rc" -ne 0 ] && [ "$rc" -ne 1 ]; then exit "$rc"; fi
}

merge_shards() {  # OUTDIR N
  set -- "$1" "$2" "$(i=1; while [ "$i" -le "$2" ]; do printf '%s ' "$1/shards/shard-$i-of-$2.json"; i=$((i + 1)); done)"
  rc=0
  for fmt in md csv json; do
    # shellcheck disable=SC2086  # the shard list is split on purpose (paths without blanks)
    "$bin" merge $3 --format "$fmt" --output "$1/table.$fmt" --packs "$1/packs.$fmt" || rc=$?
    if [ "$rc" -ne 0 ] && [ "$rc" -ne 1 ]; then exit "$rc"; fi
  done
  echo "merged $2 shards into $1/table.{md,csv,json} and $1/packs.{md,csv,json}"
  exit "$rc"
}

case "$mode" in
  submit)
    manifest=$(cd "$(dirname "$2")" && pwd)/$(basename "$2")
    mkdir -p "$3"
    out=$(cd "$3" && pwd)
    shards=${4:-8}
    # Slurm runs a copy of this script from its spool directory: pass the binary's path.
    BATTSIM=$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")
    export BATTSIM
    # --parsable prints the job id only; the merge waits for every task, failed or not
    # (afterany), and itself fails if a shard's table is missing.
    array=$(sbatch --parsable --array=1-"$shards" "$0" shard "$manifest" "$out" "$shards")
    sbatch --dependency=afterany:"$array" --cpus-per-task=1 "$0" merge "$out" "$shards"
    ;;
  shard)  # inside an array task
    run_shard "$2" "$3" "${SLURM_ARRAY_TASK_ID:?not in a Slurm array task}" "$4" "${SLURM_CPUS_PER_TASK:-1}"
    ;;
  merge)
    merge_shards "$2" "$3"
    ;;
  local)
    shards=${4:-4}
    k=1
    while [ "$k" -le "$shards" ]; do
      run_shard "$2" "$3" "$k" "$shards" 1
      k=$((k + 1))
    done
    merge_shards "$3" "$shards"
    ;;
  *)
    echo "usage: $0 submit|local MANIFEST OUTDIR [SHARDS]" >&2
    exit 2
    ;;
esac
