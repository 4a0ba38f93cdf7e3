#!/usr/bin/env python3
"""Compares two trees of run outputs (DIR_A/<case>/..., DIR_B/<case>/...) file by file, byte
for byte, apart from what measures time: `summary.json` is compared without its timing and
memory fields, its output directory, how the model cache served it (`cache`: a hit gives
the same results as a cold run) and the bytes of the output (`output_bytes`: the timings'
digits are in the files), `history.csv` and `energy.csv` without the `wall_s` column, the
journal `steps.jsonl` line by line as JSON without the timing fields, and the restart states
`state_NNNN.json` without their `id` (it hashes the program's build, which a restructure
changes). Prints every file that differs and the count; exits 1 if any does.

Used to check that a restructure leaves the output of the shipped cases unchanged:

    for c in cases/*.json; do n=$(basename $c .json)
      target/release/stickslip run $c --out /tmp/before/$n --quiet --threads 2; done
    # ... change the code, rebuild, run again into /tmp/after ...
    python3 post/compare_runs.py /tmp/before /tmp/after
"""
import filecmp
import json
import os
import sys

TIMING_KEYS = {"timings_s", "contact_solve_s", "contact_phases_s", "peak_memory_mib", "wall_s", "output_dir",
               "build_s", "sweep_s", "runs", "t_solve", "t_contact", "cache", "output_bytes"}
# Keys that name the program's build rather than what it computed (restart states).
BUILD_KEYS = {"id"}


def strip(d):
    if isinstance(d, dict):
        return {k: strip(v) for k, v in d.items() if k not in TIMING_KEYS}
    if isinstance(d, list):
        return [strip(x) for x in d]
    return d


def strip_build(d):
    """`d` without its timing keys, nor the build's identity at its top level."""
    return {k: v for k, v in strip(d).items() if k not in BUILD_KEYS}


def jsonl_rows(path):
    return [strip(json.loads(line)) for line in open(path).read().splitlines() if line]


def csv_rows(path):
    rows = [line.split(",") for line in open(path).read().splitlines()]
    if rows and "wall_s" in rows[0]:
        k = rows[0].index("wall_s")
        rows = [r[:k] + r[k + 1:] for r in rows]
    return rows


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    a, b = sys.argv[1], sys.argv[2]
    bad = 0
    for case in sorted(os.listdir(a)):
        da, db = os.path.join(a, case), os.path.join(b, case)
        fa = sorted(os.listdir(da))
        fb = sorted(os.listdir(db)) if os.path.isdir(db) else []
        if fa != fb:
            print(f"{case}: file lists differ: {sorted(set(fa) ^ set(fb))}")
            bad += 1
            continue
        for f in fa:
            pa, pb = os.path.join(da, f), os.path.join(db, f)
            if f.startswith("state_") and f.endswith(".json"):
                same = strip_build(json.load(open(pa))) == strip_build(json.load(open(pb)))
            elif f.endswith(".json"):
                same = strip(json.load(open(pa))) == strip(json.load(open(pb)))
            elif f.endswith(".jsonl"):
                same = jsonl_rows(pa) == jsonl_rows(pb)
            elif f.endswith(".csv"):
                same = csv_rows(pa) == csv_rows(pb)
            else:
                same = filecmp.cmp(pa, pb, shallow=False)
            if not same:
                print(f"{case}/{f} differs")
                bad += 1
    print(f"differences: {bad}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
