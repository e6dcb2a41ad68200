#!/usr/bin/env bash
# Byte-identical outputs of two creepfit binaries (a refactoring must change no output byte):
#
#     scripts/outputs_identical.sh OLD_BIN NEW_BIN
#
# Runs each binary, one after the other, on the bundled data: fit (560 °C and alloy 617), a
# small sweep (tests/data/sweep_small.toml), diagnose and profile (560 °C), predict at
# 560:70 with intervals from that binary's own fit, simulate with the objective at w 0.5,
# two synth sets, one shard of the small sweep merged (partial; refused under --require-all), and holdout (cmv-joint, which refuses:
# two temperatures; alloy 617 with 950 °C left out, with intervals). stdout and stderr of
# the whole run are compared too.
# Both runs use the same paths (the binary copied to one place, the outputs under one
# folder, moved aside after each run), so that argv in manifest.json and any path written
# into a file are the same. Then scripts/outputs_compare.py compares every output file byte
# for byte (see there what it leaves out and what it accepts as run facts: wall times, PIDs,
# the binary's own build stamp, the order of a journal's parallel records). Prints each
# differing file; exit 1 if any.
set -euo pipefail
[ $# -eq 2 ] || { echo "usage: $0 OLD_BIN NEW_BIN" >&2; exit 2; }
root=$(cd "$(dirname "$0")/.." && pwd)
old=$(realpath "$1")
new=$(realpath "$2")
work=$(mktemp -d /tmp/outputs_identical.XXXXXX)
echo "working in $work"
cfg="$root/configs"

run_all() { # $1: binary; runs in $work/run, outputs under out/
    local bin="$work/creepfit"
    cp "$1" "$bin"
    rm -rf "$work/run"
    mkdir -p "$work/run"
    cd "$work/run"
    {
        "$bin" fit "$cfg/560C.toml" --out out/fit-560C -q
        "$bin" fit "$cfg/alloy617.toml" --out out/fit-alloy617 -q
        "$bin" sweep "$root/tests/data/sweep_small.toml" --out out/sweep -q
        "$bin" diagnose "$cfg/560C.toml" --out out/diagnose -q
        "$bin" profile "$cfg/560C.toml" --out out/profile -q
        "$bin" predict "$cfg/560C.toml" --constants out/fit-560C/constants.csv \
            --at 560:70 --intervals --out out/predict -q
        "$bin" simulate "$cfg/560C.toml" --constants out/fit-560C/constants.csv --w 0.5 \
            --out out/simulate
        "$bin" synth out/synth --sets 2 --seed 7
        "$bin" sweep "$root/tests/data/sweep_small.toml" --shard 1/2 --out out/shard-1 -q
        "$bin" merge out/shard-1 out/shard-2 --out out/merge-partial \
            || echo "merge: exit $?"
        "$bin" merge out/shard-1 --require-all --out out/merge-refused \
            || echo "merge --require-all: exit $?"
        # cmv-joint has two temperatures: leaving one out leaves too few for its laws, and
        # both binaries must refuse it alike (the message is compared in stderr.txt).
        "$bin" holdout "$cfg/cmv-joint.toml" --temperature 590 --starts 4 --out out/holdout-cmv -q \
            || echo "holdout cmv-joint: exit $?"
        "$bin" holdout "$cfg/alloy617.toml" --temperature 950 --starts 2 --intervals \
            --out out/holdout-alloy617 -q
    } >stdout.txt 2>stderr.txt
    cd "$root"
}

t0=$SECONDS
run_all "$old"
mv "$work/run" "$work/old"
echo "old binary: $((SECONDS - t0)) s"
t0=$SECONDS
run_all "$new"
mv "$work/run" "$work/new"
echo "new binary: $((SECONDS - t0)) s"

"$root/scripts/outputs_compare.py" "$work/old" "$work/new"
