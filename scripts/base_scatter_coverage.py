#!/usr/bin/env python3
"""The scatter interval of `diagnose`'s base fit on generated null sets, without the rest of
the diagnosis: each set of the specimens world (scenario `none`) is generated with
`creepfit synth`, diagnosed until the base fit's record reaches the journal (the multistart's
best, polished, with its 95 % scatter intervals), then stopped. Appends one line per set to
OUT/base.jsonl (seed, kinds, scatter, lo95, hi95, the truth's scatter) and prints the
coverage per kind; rerun to resume. Two sets at a time, one thread each.

    scripts/base_scatter_coverage.py target/release/creepfit OUT 180001 200
"""
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

BIN, OUT, FIRST, N = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
os.makedirs(OUT, exist_ok=True)
PATH = os.path.join(OUT, "base.jsonl")
DONE = set()
if os.path.exists(PATH):
    DONE = {json.loads(l)["seed"] for l in open(PATH)}


def base_record(journal):
    try:
        for line in open(journal):
            r = json.loads(line).get("record")
            if r and r["key"].startswith("fits/0/base"):
                return r["value"]["best"]
    except (FileNotFoundError, json.JSONDecodeError):
        pass
    return None


def one(seed):
    if seed in DONE:
        return None
    d = os.path.join(OUT, "sets", str(seed))
    subprocess.run([BIN, "synth", d, "--world", "specimens", "--seed", str(seed), "--sets", "1",
                    "--scenario", "none"], capture_output=True, check=True)
    set_dir = os.path.join(d, f"set-{seed}")
    out = os.path.join(d, "diag")
    subprocess.run(["rm", "-rf", out], check=True)
    p = subprocess.Popen([BIN, "diagnose", os.path.join(set_dir, "config.toml"), "--threads", "1",
                          "-q", "--out", out], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    rec, t0 = None, time.time()
    while rec is None and p.poll() is None:
        time.sleep(0.5)
        rec = base_record(os.path.join(out, "journal.jsonl"))
    rec = rec or base_record(os.path.join(out, "journal.jsonl"))
    p.kill()
    p.wait()
    truth = json.load(open(os.path.join(set_dir, "truth.json")))["specimens"]
    row = {"seed": seed, "truth": [truth["rate_sd"], truth["ductility_sd"]], "wall_s": time.time() - t0}
    sp = rec and rec.get("specimen")
    if not sp:
        row["error"] = "no base fit" if rec is None else "no specimen effects"
    else:
        row.update(kinds=sp["kinds"], scatter=sp["scatter"], lo95=sp["scatter_lo95"], hi95=sp["scatter_hi95"])
    return row


with ThreadPoolExecutor(2) as ex, open(PATH, "a") as f:
    for r in ex.map(one, range(FIRST, FIRST + N)):
        if r:
            f.write(json.dumps(r) + "\n")
            f.flush()

rows = [json.loads(l) for l in open(PATH)]
rows = [r for r in rows if FIRST <= r["seed"] < FIRST + N]
for i, kind in enumerate(["rate", "ductility"]):
    n = cov = above = below = 0
    for r in rows:
        t = r["truth"][i]
        if not t or "error" in r:
            continue
        k = dict(zip(r["kinds"], zip(r["lo95"], r["hi95"])))
        lo, hi = k.get(kind, (0.0, 0.0))
        n += 1
        cov += lo <= t <= hi
        above += t > hi
        below += t < lo
    print(f"{kind}: covered {cov} of {n}; truth above the interval {above}, below {below}")
print(f"failed: {sum('error' in r for r in rows)} of {len(rows)}")
