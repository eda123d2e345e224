#!/usr/bin/env python3
"""Journal durability under load (issue 32): SIGKILL a run N times beside busy loops and
report, for each kill, the age of the events it lost.

Each run writes its journal and, through the measurement hook GSPN_JOURNAL_HANDOVERS
(gspn::runtime::journal::HANDOVERS_ENV), the wall-clock instant (CLOCK_REALTIME, ns) at
which every event was handed to the journal's writer thread. After the SIGKILL the events
handed over but not in the journal are the lost ones; the age of each is the kill's instant
minus its handover. The journal's bound is about the oldest of them (no event older than
the bound may be lost); the newest lost one shows how recent the loss is.

The load (the 1-minute average in /proc/loadavg) must reach --load before the first kill:
the script starts --busy busy loops, and one more every 30 s while the load stays below it
(at most 16). Usage, from the repository's root:

    python3 benches/journal_kill.py --bin target/release/plan-runner

Standard library only. Prints one line per kill and a summary (docs/reliability.md).
"""

import argparse
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time


def loadavg():
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


def busy_loop():
    return subprocess.Popen(["sh", "-c", "while :; do :; done"])


def journal_seqs(path):
    """The seq of every whole event line in the journal (its header, side records and a
    last line cut short left out)."""
    seqs = set()
    with open(path, "rb") as f:
        data = f.read()
    lines = data.split(b"\n")
    # The last element is what follows the last newline: empty, or a line cut short.
    for line in lines[1:-1]:
        if not line.strip():
            continue
        v = json.loads(line)
        if "seq" in v:
            seqs.add(v["seq"])
    return seqs


def handovers(path):
    """seq -> the instant (ns) it was handed to the writer (whole lines only)."""
    out = {}
    with open(path, "rb") as f:
        data = f.read()
    for line in data.split(b"\n")[:-1]:
        seq, ns = line.split()
        out[int(seq)] = int(ns)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", default="target/release/plan-runner")
    ap.add_argument("--plan", default="plans/cyc3.toml")
    ap.add_argument("--time-scale", default="0.01",
                    help="real seconds per model second of the run (default 0.01)")
    ap.add_argument("--kills", type=int, default=20)
    ap.add_argument("--busy", type=int, default=2, help="busy loops started at once")
    ap.add_argument("--load", type=float, default=8.0, help="load average to reach first")
    ap.add_argument("--bound-ms", type=float, default=100.0,
                    help="the stated bound the oldest lost event is checked against")
    ap.add_argument("--seed", type=int, default=1, help="seeds the wait before each kill")
    args = ap.parse_args()

    loops = [busy_loop() for _ in range(args.busy)]
    rng = random.Random(args.seed)
    rows = []
    try:
        last_added = time.time()
        while loadavg() < args.load:
            time.sleep(2)
            if time.time() - last_added >= 30 and len(loops) < 16:
                loops.append(busy_loop())
                last_added = time.time()
        print(f"load {loadavg():.2f} with {len(loops)} busy loops", flush=True)
        with tempfile.TemporaryDirectory(prefix="journal-kill-") as tmp:
            for i in range(args.kills):
                journal = os.path.join(tmp, f"run{i}.jsonl")
                log = os.path.join(tmp, f"run{i}.handovers")
                env = dict(os.environ, GSPN_JOURNAL_HANDOVERS=log)
                cmd = [args.bin, "run", args.plan, "--time-scale", args.time_scale,
                       "--seed", str(i + 1), "--journal", journal, "--quiet"]
                child = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL,
                                         stderr=subprocess.DEVNULL)
                time.sleep(rng.uniform(1.0, 3.0))
                load = loadavg()
                killed = time.time_ns()
                os.kill(child.pid, signal.SIGKILL)
                child.wait()
                on_disk = journal_seqs(journal)
                handed = handovers(log)
                lost = sorted(s for s in handed if s not in on_disk)
                # Lost events must be the last ones handed over (no hole in the journal).
                holes = sum(1 for s in on_disk if lost and s > lost[0])
                ages = [(killed - handed[s]) / 1e6 for s in lost]
                row = {
                    "kill": i + 1,
                    "load": load,
                    "handed": len(handed),
                    "on_disk": len(on_disk),
                    "lost": len(lost),
                    "newest_lost_ms": min(ages) if ages else None,
                    "oldest_lost_ms": max(ages) if ages else None,
                    "holes": holes,
                }
                rows.append(row)
                fmt = lambda v: "-" if v is None else f"{v:.1f}"
                print(f"kill {row['kill']:2}: load {load:5.2f}, {row['handed']} events "
                      f"handed over, {row['lost']} lost, newest lost {fmt(row['newest_lost_ms'])} ms, "
                      f"oldest lost {fmt(row['oldest_lost_ms'])} ms old, holes {holes}",
                      flush=True)
    finally:
        for p in loops:
            p.kill()
            p.wait()
    oldest = [r["oldest_lost_ms"] for r in rows if r["oldest_lost_ms"] is not None]
    over = [r for r in oldest if r > args.bound_ms]
    loads = [r["load"] for r in rows]
    print(f"{len(rows)} kills at load {min(loads):.2f}-{max(loads):.2f}: "
          f"events lost in {len(oldest)}, oldest lost event at most "
          f"{max(oldest) if oldest else 0:.1f} ms old; {len(over)} over {args.bound_ms:g} ms; "
          f"holes {sum(r['holes'] for r in rows)}")
    return 1 if over or any(r["holes"] for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
