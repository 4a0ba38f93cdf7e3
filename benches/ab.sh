#!/usr/bin/env bash
# A/B timing of two stickslip binaries (or one binary under two environments) on one case, in
# alternating runs so that the machine's drift falls on both alike; prints the median and the
# minimum process wall time of each and the median of the per-pair ratios B/A, then each side's
# wall time against its own floor (`timings_s.build_span` of the run's summary.json: the
# assembly, analysis and factorisation as they ran) and what the run spent beyond it, the
# difference of the latter pair by pair (its median, and a sign test of how often B is lower),
# and each side's numeric factorisation times (`timings_s.factorise`), sorted.
#
#   benches/ab.sh N BIN_A BIN_B [CASE] [cold|warm] [ENV_A] [ENV_B]
#
# cold: every run with --no-cache (the whole build of the model); first: every run with a fresh
# cache directory (the whole build, and the entry written: a user's first run); warm: each
# binary has its own fresh cache directory, filled by one untimed run, and the N timed runs are
# hits. cold-first: side A cold, side B first (with A = B, what writing the cache entry costs
# a first run).
# ENV_A / ENV_B: space-separated VAR=value assignments for each side (e.g. the ordering:
# `STICKSLIP_ORDERING=amd` against `STICKSLIP_ORDERING=nd` with the same binary).
#
# Example (what one commit bought; build the older one into another target directory):
#   git worktree add /tmp/old <commit> && (cd /tmp/old && cargo build --release)
#   benches/ab.sh 12 /tmp/old/target/release/stickslip target/release/stickslip cases/fig2.json warm
set -euo pipefail
N=$1 A=$2 B=$3 CASE=${4:-cases/fig2.json} MODE=${5:-cold} EA=${6:-} EB=${7:-}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
case "$MODE" in cold | first | warm | cold-first) ;; *) echo "ab.sh: MODE must be cold, first, warm or cold-first" >&2; exit 2 ;; esac
# The mode of side $1.
mode_of() { if [ "$MODE" = cold-first ]; then [ "$1" = A ] && echo cold || echo first; else echo "$MODE"; fi; }
args() { # side
  case "$(mode_of "$1")" in
    warm | first) echo "--cache $work/cache_$1" ;;
    *) echo "--no-cache" ;;
  esac
}
run() { # side bin env
  local t0 t1
  # A first run starts from an empty cache directory (removed before the clock starts).
  if [ "$(mode_of "$1")" = first ]; then rm -rf "$work/cache_$1"; fi
  t0=$(date +%s%N)
  env $3 "$2" run "$CASE" --out "$work/out_$1" --quiet --threads "${STICKSLIP_THREADS:-2}" $(args "$1") >/dev/null
  t1=$(date +%s%N)
  # The run's dirty pages (a first run's cache entry: 148 MB on L5, 0.6 GB on L7) go to the
  # disk before the next run starts, outside the timed span, as in the scaling bench: else the
  # kernel's writeback of one side's entry runs during the other side's floor.
  sync
  # The wall time, the run's floor (`timings_s.build_span` of its summary; 0 if none) and its
  # numeric factorisation (`timings_s.factorise`).
  local floor
  floor=$(python3 -c 'import json,sys
try:
    t = json.load(open(sys.argv[1]))["timings_s"]; print("%s,%s" % (t["build_span"], t["factorise"]))
except Exception: print("0,0")' "$work/out_$1/summary.json")
  echo "$(( (t1 - t0) / 1000 ))e-6,$floor"
}
if [ "$MODE" = warm ]; then run A "$A" "$EA" >/dev/null; run B "$B" "$EB" >/dev/null; fi
for _ in $(seq "$N"); do
  echo "$(run A "$A" "$EA") $(run B "$B" "$EB")"
done | python3 -c '
import statistics as st, sys
r = [tuple(tuple(map(float, s.split(","))) for s in l.split()) for l in sys.stdin]
a = [x[0] for x, _ in r]; b = [y[0] for _, y in r]
print("A: median %.3f s, min %.3f s | B: median %.3f s, min %.3f s | B/A: median of %d pairs %.3f"
      % (st.median(a), min(a), st.median(b), min(b), len(r), st.median([y[0] / x[0] for x, y in r])))
# Each run against its own floor (the assembly, analysis and factorisation as they ran).
if all(x[1] > 0 and y[1] > 0 for x, y in r):
    for side, k in (("A", 0), ("B", 1)):
        v = [p[k] for p in r]
        print("%s: wall / floor median %.3f (%s), wall - floor median %.3f s"
              % (side, st.median([w / f for w, f, _ in v]), " ".join("%.2f" % (w / f) for w, f, _ in v),
                 st.median([w - f for w, f, _ in v])))
    # The work after the floor, pair by pair (the runs of a pair are next to each other, so
    # the drift of the machine falls on both): the median difference, and in how many pairs
    # that of B is the smaller, with the p of a two-sided sign test (how often a fair coin
    # splits the pairs at least that unevenly: below 0.05 the difference is unlikely to be
    # the noise).
    d = [(y[0] - y[1]) - (x[0] - x[1]) for x, y in r]
    n, k = len(d), sum(1 for v in d if v < 0)
    import math
    tail = sum(math.comb(n, i) for i in range(0, min(k, n - k) + 1)) / 2 ** n
    print("B - A, wall - floor: median of pairs %+.1f ms; B lower in %d of %d pairs (sign test p = %.3f)"
          % (1e3 * st.median(d), k, n, min(1.0, 2 * tail)))
    # The numeric factorisation of each run, sorted (its slow outliers move the floor).
    for side, k in (("A", 0), ("B", 1)):
        print("%s: factorise s, sorted: %s" % (side, " ".join("%.2f" % p[k][2] for p in sorted(r, key=lambda p: p[k][2]))))'
