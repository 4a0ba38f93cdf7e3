#!/usr/bin/env python3
"""Where a run's wall time goes beyond its floor, from the trace marks of `STICKSLIP_TRACE=1`.

    python3 benches/segments.py N [BINARY] [CASE] [cold|first]

Runs the case N times (each into a fresh output directory; `first`: with a fresh model-cache
directory, as a user's first run; `cold`: `--no-cache`), syncs the disk before each run so that
the previous run's dirty pages are not written back during it, and prints per segment of the
run the median and the range over the N runs, in ms:

* start → `pair, dofs`: the process start, the case, the mesh, its checks, the contact pair and
  the DOF numbering (before the floor);
* `pair, dofs` → `numeric factor`: the floor (pattern, assembly alongside the analysis, numeric
  factorisation; within a few ms of the summary's `build_span`, printed below);
* `numeric factor` → `factorised`: the Delassus operator;
* `factorised` → `step 41`: the contact Newton of the 41 steps, beside the writer;
* `step 41` → `simulated`: the driver's share of the last written steps;
* `simulated` → `summarised`: the checks of the summary;
* `summarised` → `writer done` → `run returned` → exit: waiting for the writer, the end of
  the run (the model dropped), the process exit;

then the wall time, the run's floor (`timings_s.build_span` of its summary) and wall / floor.
Defaults: `target/release/stickslip`, `cases/fig2.json`, `first`. The last two segments'
marks are those of the shipped Fig. 2 case (41 steps).
"""
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

SEGMENTS = [
    ("start", "pair, dofs"),
    ("pair, dofs", "numeric factor"),
    ("numeric factor", "factorised"),
    ("factorised", "step 41"),
    ("step 41", "simulated"),
    ("simulated", "summarised"),
    ("summarised", "writer done"),
    ("writer done", "run returned"),
    ("run returned", "exit"),
]


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    n = int(sys.argv[1])
    binary = sys.argv[2] if len(sys.argv) > 2 else "target/release/stickslip"
    case = sys.argv[3] if len(sys.argv) > 3 else "cases/fig2.json"
    mode = sys.argv[4] if len(sys.argv) > 4 else "first"
    if mode not in ("cold", "first"):
        sys.exit("segments.py: the mode is cold or first")
    work = tempfile.mkdtemp(prefix="stickslip-segments-")
    rows = []
    try:
        for _ in range(n):
            out, cache = os.path.join(work, "out"), os.path.join(work, "cache")
            shutil.rmtree(out, ignore_errors=True)
            shutil.rmtree(cache, ignore_errors=True)
            subprocess.run(["sync"], check=False)
            args = ["--cache", cache] if mode == "first" else ["--no-cache"]
            env = dict(os.environ, STICKSLIP_TRACE="1")
            t = time.monotonic()
            p = subprocess.run(
                [binary, "run", case, "--out", out, "--quiet"] + args,
                env=env,
                capture_output=True,
                text=True,
            )
            wall = (time.monotonic() - t) * 1000.0
            if p.returncode != 0:
                sys.exit(f"segments.py: the run failed (exit {p.returncode}):\n{p.stderr}")
            at = {"start": 0.0, "exit": wall}
            for line in p.stderr.splitlines():
                m = re.match(r"trace\s+([\d.]+) ms.*?\[[^\]]*\] (.*)$", line)
                if m and m.group(2) not in at:
                    at[m.group(2)] = float(m.group(1))
            missing = [k for seg in SEGMENTS for k in seg if k not in at]
            if missing:
                sys.exit(f"segments.py: trace marks missing: {sorted(set(missing))}")
            with open(os.path.join(out, "summary.json")) as f:
                span = json.load(f)["timings_s"]["build_span"] * 1000.0
            rows.append([at[b] - at[a] for a, b in SEGMENTS] + [wall, span, wall / span])
    finally:
        shutil.rmtree(work, ignore_errors=True)
    cols = list(zip(*rows))
    for (a, b), c in zip(SEGMENTS, cols):
        print(f"{a:>15} -> {b:<15} {statistics.median(c):7.1f} ms  ({min(c):.1f}-{max(c):.1f})")
    for name, c, unit in zip(["wall", "floor", "wall / floor"], cols[-3:], [" ms", " ms", ""]):
        print(f"{name:>33} {statistics.median(c):7.3f}{unit}  ({min(c):.3f}-{max(c):.3f})")


if __name__ == "__main__":
    main()
