#!/usr/bin/env bash
# Byte-identical outputs of two creepfit binaries (a refactoring must change no output byte):
#
#     scripts/outputs_identical.sh OLD_BIN NEW_BIN
#
# Runs each binary, one after the other, on the bundled data: fit (560 °C and alloy 617), a
# small sweep (tests/data/sweep_small.toml), diagnose and profile (560 °C), predict at
# 560:70 with intervals from that binary's own fit, and holdout (cmv-joint, which refuses:
# two temperatures; alloy 617 with 950 °C left out, with intervals). stdout and stderr of
# the whole run are compared too.
# Both runs use the same paths (the binary copied to one place, the outputs under one
# folder, moved aside after each run), so that argv in manifest.json and any path written
# into a file are the same. Then every output file is compared byte for byte. Left out:
# timings.json (wall times only). JSON files that hold wall times beside results
# (manifest.json's started/written_unix_s, summary.json's wall_s, …) are compared byte for
# byte first and, when they differ, again without those keys: a file identical but for wall
# times is reported as such and is not a difference. Prints each differing file; exit 1 if any.
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

python3 - "$work/old" "$work/new" <<'EOF'
import json, sys
from pathlib import Path

old, new = Path(sys.argv[1]), Path(sys.argv[2])
SKIP = {"timings.json"}
TIME_KEYS = {"wall_s", "fit_wall_s", "phase_s", "timings_s", "training_fit_s",
             "started_unix_s", "written_unix_s"}

def files(d):
    return {p.relative_to(d) for p in d.rglob("*") if p.is_file() and p.name not in SKIP}

def untimed(v):
    if isinstance(v, dict):
        return {k: untimed(x) for k, x in v.items() if k not in TIME_KEYS}
    if isinstance(v, list):
        return [untimed(x) for x in v]
    return v

a, b = files(old), files(new)
bad = []
for f in sorted(a ^ b):
    bad.append(f"{f}: only in {'old' if f in a else 'new'}")
same = timed = 0
for f in sorted(a & b):
    x, y = (old / f).read_bytes(), (new / f).read_bytes()
    if x == y:
        same += 1
        continue
    if f.suffix in (".json", ".jsonl"):
        try:
            lx = [untimed(json.loads(l)) for l in x.decode().splitlines() if l.strip()] \
                if f.suffix == ".jsonl" else untimed(json.loads(x))
            ly = [untimed(json.loads(l)) for l in y.decode().splitlines() if l.strip()] \
                if f.suffix == ".jsonl" else untimed(json.loads(y))
            if lx == ly:
                timed += 1
                continue
        except ValueError:
            pass
    bad.append(f"{f}: differs")
for line in bad:
    print("DIFFERS", line)
print(f"{len(a | b)} files: {same} byte-identical, {timed} identical but for wall times "
      f"({', '.join(sorted(TIME_KEYS))}), {len(bad)} differing; timings.json not compared")
sys.exit(1 if bad else 0)
EOF
