#!/usr/bin/env bash
# kill -9 half-way through a resumable command, then rerun it into the same folder: how long
# the rerun takes against an uninterrupted run, and whether its result files are byte-identical.
# Usage: scripts/resume_kill9.sh diagnose|profile|holdout CONFIG [OUT] [FRACTION] [-- EXTRA ARGS]
#   (default OUT /tmp/creepfit-kill9-<command>, FRACTION 0.5 of the uninterrupted wall time)
# Every run uses --threads 2 --quiet; wall times are noisy on a shared machine (the load
# average is printed before and after).
set -euo pipefail
cd "$(dirname "$0")/.."
cmd="$1"; cfg="$2"; shift 2
out="/tmp/creepfit-kill9-$cmd"; frac=0.5
if [ $# -gt 0 ] && [ "$1" != "--" ]; then out="$1"; shift; fi
if [ $# -gt 0 ] && [ "$1" != "--" ]; then frac="$1"; shift; fi
[ "${1:-}" = "--" ] && shift
extra=("$@")
[ -x /usr/bin/time ] || { echo "error: /usr/bin/time missing (apt-get install time)" >&2; exit 1; }
[ -x target/release/creepfit ] || { echo "error: build first: cargo build --release" >&2; exit 1; }
rm -rf "$out"; mkdir -p "$out"
# A copy: a rebuild during the measurement must not change the binary between the runs.
bin="$out/creepfit"; cp target/release/creepfit "$bin"
now() { date +%s.%N; }
# A run into folder $1, its wall time and CPU time (user + system, s) into $1.time.
run() { /usr/bin/time -f '%e %U %S' -o "$1.time" "$bin" "$cmd" "$cfg" "${extra[@]}" --threads 2 --quiet --out "$1"; }
cpu() { awk '{print $2 + $3}' "$1.time"; }
echo "# $cmd $cfg ${extra[*]}; $(nproc) cores; load before: $(cut -d' ' -f1-3 /proc/loadavg)"
t0=$(now); run "$out/plain" > "$out/plain.log" 2>&1; t1=$(now)
full=$(awk "BEGIN{print $t1-$t0}")
echo "uninterrupted: $full s wall, $(cpu "$out/plain") s CPU"
wait_s=$(awk "BEGIN{print $full*$frac}")
# The binary itself in the background (not a function: its pid would be a subshell's).
"$bin" "$cmd" "$cfg" "${extra[@]}" --threads 2 --quiet --out "$out/resumed" > "$out/killed.log" 2>&1 &
pid=$!
sleep "$wait_s"
kill -9 "$pid"
wait "$pid" 2>/dev/null || true
if kill -0 "$pid" 2>/dev/null; then echo "error: pid $pid still runs" >&2; exit 1; fi
kept=$(($(wc -l < "$out/resumed/journal.jsonl") - 1))
total=$(($(wc -l < "$out/plain/journal.jsonl") - 1))
echo "kill -9 after $wait_s s: $kept of $total journal records kept"
t0=$(now); run "$out/resumed" > "$out/resumed.log" 2>&1; t1=$(now)
again=$(awk "BEGIN{print $t1-$t0}")
echo "rerun after the kill: $again s wall = $(awk "BEGIN{printf \"%.1f\", 100*$again/$full}") % of uninterrupted; $(cpu "$out/resumed") s CPU = $(awk "BEGIN{printf \"%.1f\", 100*$(cpu "$out/resumed")/$(cpu "$out/plain")}") %"
echo "total with the killed part: $(awk "BEGIN{printf \"%.1f\", $wait_s+$again}") s"
status=0
for f in $(cd "$out/plain" && find . -type f ! -name journal.jsonl ! -name manifest.json ! -name timings.json ! -name .creepfit.lock | sort); do
    if cmp -s "$out/plain/$f" "$out/resumed/$f"; then echo "identical: $f"; else echo "DIFFERS: $f"; status=1; fi
done
echo "timings.json of the rerun:"; cat "$out/resumed/timings.json"; echo
echo "# load after: $(cut -d' ' -f1-3 /proc/loadavg)"
exit $status
