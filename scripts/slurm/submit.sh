#!/usr/bin/env bash
# Submit a creepfit sweep to Slurm: a job array of TASKS tasks (sweep.sbatch), each computing
# one shard into OUT/shard-I-of-TASKS/, and a merge job (merge.sbatch) that runs after all of
# them (afterany) and writes the merged ranked.csv, minima.csv, summary.json and plots to OUT.
#
#   scripts/slurm/submit.sh CONFIG STARTS TASKS OUT [SBATCH OPTION...]
#
# SBATCH OPTIONs (e.g. --partition=long --time=04:00:00 --cpus-per-task=16) are passed to
# both sbatch calls and override the scripts' #SBATCH lines. Logs go to OUT/logs/. Prints
# "submitted: array ID merge ID" (the line scripts/slurm/run-local.sh reads).
set -euo pipefail
if [ $# -lt 4 ]; then
    sed -n '2,12p' "$0" >&2
    exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
config=$(realpath -e "$1")
starts=$2
tasks=$3
out=$(realpath -m "$4")
shift 4
case "$starts$tasks" in
    *[!0-9]*) echo "error: STARTS and TASKS must be positive integers" >&2; exit 2 ;;
esac
if [ "$tasks" -lt 1 ]; then
    echo "error: TASKS must be at least 1" >&2
    exit 2
fi
mkdir -p "$out/logs"
array=$(sbatch --parsable --array="1-$tasks" --output="$out/logs/sweep-%A_%a.log" \
    "$@" "$here/sweep.sbatch" "$config" "$starts" "$out")
array=${array%%;*}
merge=$(sbatch --parsable --dependency="afterany:$array" --output="$out/logs/merge-%j.log" \
    "$@" "$here/merge.sbatch" "$out")
merge=${merge%%;*}
echo "submitted: array $array merge $merge"
echo "array job $array: $tasks tasks into $out/shard-I-of-$tasks/; merge job $merge into $out after all of them (squeue -u \$USER shows them)"
