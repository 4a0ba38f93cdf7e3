#!/usr/bin/env bash
# A/B timing of the 50-law sweep of `cargo bench --bench sweep` for two stickslip binaries, in
# alternating runs: per repeat and binary, the single run with output at the last step only (the
# bench's "strict" run) and the sweep of the 50 laws, each a process with no model cache; prints
# both wall times and their ratio, then the medians, and how often B's sweep was the faster
# of a pair (a sign test). `SWEEP_AB_SINGLE=0`: the sweeps alone, without the single runs.
#
#   benches/sweep_ab.sh N BIN_A BIN_B [LEVEL]
#
# The case is cases/fig2.json on meshes/vm272_L{LEVEL}.msh (default 5) and the laws are the
# bench's (benches/sweep.rs, `laws`): ramp, step and exponential, f_d = 0.1, f_s/f_d = 1.2–3.
set -euo pipefail
N=$1 A=$2 B=$3 LEVEL=${4:-5}
repo=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 - "$repo" "$work" "$LEVEL" <<'PY'
import json, sys
repo, work, level = sys.argv[1:4]
case = json.load(open(f"{repo}/cases/fig2.json"))
case["mesh"] = f"{repo}/meshes/vm272_L{level}.msh"
json.dump(case, open(f"{work}/case.json", "w"))
strict = dict(case, output={"vtu": True, "every": 100000})
json.dump(strict, open(f"{work}/strict.json", "w"))
laws = []
for shape, lambdas in [("ramp", [0.02, 0.05, 0.1, 0.2]), ("step", [0.02, 0.05, 0.1]),
                       ("exponential", [0.02, 0.05, 0.1])]:
    for ratio in [1.2, 1.5, 2.0, 2.5, 3.0]:
        for lam in lambdas:
            laws.append({"shape": shape, "fs": 0.1 * ratio, "fd": 0.1, "lambda": lam,
                         "radius": 4.0, "load": 10.0})
json.dump({"friction": laws}, open(f"{work}/laws.json", "w"))
PY
now() { date +%s.%N; }
for r in $(seq 1 "$N"); do
  for side in A B; do
    bin=$A; [ "$side" = B ] && bin=$B
    rm -rf "$work/o" "$work/s"
    t0=$(now)
    if [ "${SWEEP_AB_SINGLE:-1}" != 0 ]; then
      STICKSLIP_NO_CACHE=1 "$bin" run "$work/strict.json" --out "$work/o" --quiet
    fi
    t1=$(now)
    STICKSLIP_NO_CACHE=1 "$bin" sweep "$work/case.json" "$work/laws.json" --out "$work/s" --quiet
    t2=$(now)
    echo "$side $t0 $t1 $t2" >> "$work/times"
  done
done
python3 - "$work/times" <<'PY'
import statistics, sys
rows = [(s, float(b) - float(a), float(c) - float(b))
        for s, a, b, c in (l.split() for l in open(sys.argv[1]))]
single_runs = any(r[1] > 0.01 for r in rows)
for side in "AB":
    single = [float(r[1]) for r in rows if r[0] == side]
    sweep = [float(r[2]) for r in rows if r[0] == side]
    if not single_runs:
        print(f"{side}: sweep {' '.join(f'{x:.2f}' for x in sweep)} s (median {statistics.median(sweep):.3f} s)")
        continue
    ratios = [w / s for s, w in zip(single, sweep)]
    print(f"{side}: single run {' '.join(f'{x:.2f}' for x in single)} s; sweep "
          f"{' '.join(f'{x:.2f}' for x in sweep)} s; sweep / single "
          f"{' '.join(f'{x:.2f}' for x in ratios)} (medians {statistics.median(single):.3f} s, "
          f"{statistics.median(sweep):.3f} s, {statistics.median(ratios):.2f})")
# The sweeps pair by pair (the two runs of a repeat are next to each other): in how many
# pairs that of B is the faster, with the p of a two-sided sign test (below 0.05 the
# difference is unlikely to be the noise).
import math
a = [r[2] for r in rows if r[0] == "A"]
b = [r[2] for r in rows if r[0] == "B"]
n, k = len(a), sum(1 for x, y in zip(a, b) if y < x)
tail = sum(math.comb(n, i) for i in range(0, min(k, n - k) + 1)) / 2 ** n
print(f"sweep B - A: median of pairs {1e3 * statistics.median([y - x for x, y in zip(a, b)]):+.0f} ms; "
      f"B faster in {k} of {n} pairs (sign test p = {min(1.0, 2 * tail):.3f})")
PY
