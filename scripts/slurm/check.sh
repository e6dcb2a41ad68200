#!/usr/bin/env bash
# CI's Slurm check (called from .ci/run; needs root, installs Slurm when missing):
#  1. scripts/slurm/run-local.sh configs/560C.toml 60 3 OUT on a real one-node Slurm must end
#     with OUT/ranked.csv byte-identical (cmp) to `creepfit sweep configs/560C.toml --starts 60`.
#  2. On the same cluster, an array whose task 2 is cancelled before it runs: the dependent
#     merge job (afterany) still runs and writes a partial result that says so
#     (summary.json "complete": false, shard 2 "absent"); resubmitting the whole array resumes
#     it (tasks 1 and 3 compute nothing) and the new merge equals the reference again.
set -euo pipefail
cd "$(dirname "$0")/../.."
repo=$(pwd)
work=$(mktemp -d /tmp/creepfit-slurm-check.XXXXXX)
export CREEPFIT_SLURM_STATE=${CREEPFIT_SLURM_STATE:-$work/cluster}
export SLURM_CONF="$CREEPFIT_SLURM_STATE/slurm.conf"
cleanup() {
    local rc=$?
    scripts/slurm/run-local.sh --stop >/dev/null 2>&1 || true
    [ "$rc" -eq 0 ] && rm -rf "$work"
    exit "$rc"
}
trap cleanup EXIT
t0=$(date +%s)

echo "-- 1. run-local.sh configs/560C.toml 60 3 against the unsharded sweep"
# The binary: $CREEPFIT when set (.ci/run hands over the one its test build made, so that CI
# builds the release library once for the tests and once for the Python wheel, not a third
# time here), else this checkout's release build.
if [ -z "${CREEPFIT:-}" ]; then
    cargo build --release --quiet
    export CREEPFIT=$repo/target/release/creepfit
fi
bin=$CREEPFIT
"$bin" sweep configs/560C.toml --starts 60 --out "$work/reference" >/dev/null
CREEPFIT_SLURM_KEEP=1 scripts/slurm/run-local.sh configs/560C.toml 60 3 "$work/slurm"
cmp "$work/slurm/ranked.csv" "$work/reference/ranked.csv"
cmp "$work/slurm/minima.csv" "$work/reference/minima.csv"
grep -q '"complete": true' "$work/slurm/summary.json"
echo "ranked.csv and minima.csv from the job array are byte-identical to the unsharded sweep's"

echo "-- 2. a cancelled task: the merge (afterany) writes a partial result; a resubmission completes it"
wait_job() { # until the job (all its array tasks) has left the queue
    local i
    for i in $(seq 1 600); do
        [ -z "$(squeue -h -j "$1" 2>/dev/null)" ] && return 0
        sleep 1
    done
    echo "error: job $1 still queued after 600 s" >&2
    squeue >&2
    return 1
}
out=$work/partial
ids=$(scripts/slurm/submit.sh configs/560C.toml 60 3 "$out" --partition=creepfit \
    --cpus-per-task=1 --hold | awk '/^submitted:/ {print $3, $5}')
read -r array merge <<<"$ids"
scancel "${array}_2"
scontrol release "$array"
scontrol release "$merge"
wait_job "$array"
wait_job "$merge"
scontrol -o show job "$merge" | grep -q 'JobState=COMPLETED' || {
    scontrol -o show job "$merge" >&2
    exit 1
}
grep -q "shard 2/3 absent: 0 of 200 fits" "$out"/logs/merge-"$merge".log
python3 - "$out/summary.json" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
assert s["complete"] is False, s["complete"]
assert [(m["shard"], m["of"], m["state"]) for m in s["missing"]] == [(2, 3, "absent")], s["missing"]
assert s["fits"] == 410, s["fits"]
EOF
echo "task 2 cancelled: the merge ran and says complete: false, missing shard 2/3 (absent), 410 of 610 fits"
rm -rf "$out/logs"
ids=$(scripts/slurm/submit.sh configs/560C.toml 60 3 "$out" --partition=creepfit \
    --cpus-per-task=1 | awk '/^submitted:/ {print $3, $5}')
read -r array merge <<<"$ids"
wait_job "$array"
wait_job "$merge"
grep -q "0 fits computed now" "$out/logs/sweep-${array}_1.log"
grep -q "200 fits computed now" "$out/logs/sweep-${array}_2.log"
cmp "$out/ranked.csv" "$work/reference/ranked.csv"
grep -q '"complete": true' "$out/summary.json"
echo "resubmitted array: shard 2 computed, shards 1 and 3 resumed with nothing to do; merge identical to the reference"
echo "slurm check done in $(($(date +%s) - t0)) s"
