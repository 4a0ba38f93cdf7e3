#!/usr/bin/env python3
"""Compares two trees of run outputs (DIR_A/<case>/..., DIR_B/<case>/...) file by file, byte
for byte, apart from what measures time: `summary.json` is compared without its timing and
memory fields, its output directory, how the model cache served it (`cache`: a hit gives
the same results as a cold run) and the bytes written (`output_bytes`: the files carry
timings), `history.csv` and `energy.csv` without the `wall_s` column, the journal
`steps.jsonl` line by line without its timings, and restart states without their timings and
the program's identity (`id`: two builds differ in it by design). Prints every file that
differs and the count; exits 1 if any does.

With `--rtol X`, numbers need only agree within X of the largest magnitude of their CSV column
(or, in JSON, of the two numbers, at least 1), or within `--atol Y` absolutely (for columns of
round-off around zero, such as a pilot displacement that symmetry makes zero), and the files
that differ only so are counted with their largest such difference; for a change that moves
the last bits (another order of summation in a kernel).

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


def strip(d):
    if isinstance(d, dict):
        return {k: strip(v) for k, v in d.items() if k not in TIMING_KEYS}
    if isinstance(d, list):
        return [strip(x) for x in d]
    return d


RTOL = None
ATOL = 0.0
WORST = {}


def close(a, b, scale):
    """Whether two parsed values agree within RTOL of `scale` (recording the difference)."""
    if isinstance(a, bool) or isinstance(b, bool) or not all(isinstance(x, (int, float)) for x in (a, b)):
        return a == b
    if abs(a - b) <= ATOL:
        return True
    d = abs(a - b) / max(scale, 1e-300)
    WORST[CURRENT[0]] = max(WORST.get(CURRENT[0], 0.0), d)
    return d <= RTOL


CURRENT = [""]


def same_json(a, b):
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same_json(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same_json(x, y) for x, y in zip(a, b))
    if RTOL is not None and isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return close(a, b, max(abs(a), abs(b), 1.0))
    return a == b


def num(x):
    try:
        return float(x)
    except ValueError:
        return x


def same_csv(ra, rb):
    if RTOL is None or len(ra) != len(rb) or any(len(x) != len(y) for x, y in zip(ra, rb)):
        return ra == rb
    cols = list(zip(*[[num(c) for c in r] for r in ra[1:]])) if len(ra) > 1 else []
    scale = [max((abs(v) for v in c if isinstance(v, float)), default=1.0) for c in cols]
    ok = ra[0] == rb[0]
    for x, y in zip(ra[1:], rb[1:]):
        for k, (p, q) in enumerate(zip(x, y)):
            p, q = num(p), num(q)
            if isinstance(p, float) and isinstance(q, float):
                ok &= close(p, q, scale[k])
            else:
                ok &= p == q
    return ok


def same_vtu(pa, pb):
    """`.vtu` files (uncompressed): integer arrays equal, float arrays within RTOL of their
    largest value (post/vtu_diff.py reads them)."""
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from vtu_diff import arrays
    a, b = arrays(pa), arrays(pb)
    if a.keys() != b.keys():
        return False
    ok = True
    for k in a:
        if a[k].shape != b[k].shape:
            return False
        if a[k].dtype.kind != "f":
            ok &= bool((a[k] == b[k]).all())
        elif a[k].size:
            scale = float(abs(a[k]).max()) or 1.0
            ok &= close(0.0, float(abs(a[k] - b[k]).max()), scale)
    return ok


def csv_rows(path):
    rows = [line.split(",") for line in open(path).read().splitlines()]
    if rows and "wall_s" in rows[0]:
        k = rows[0].index("wall_s")
        rows = [r[:k] + r[k + 1:] for r in rows]
    return rows


def main():
    global RTOL, ATOL
    args = sys.argv[1:]
    while len(args) > 2 and args[0] in ("--rtol", "--atol"):
        if args[0] == "--rtol":
            RTOL = float(args[1])
        else:
            ATOL = float(args[1])
        args = args[2:]
    if len(args) != 2:
        sys.exit(__doc__)
    a, b = args
    bad = 0
    for case in sorted(c for c in os.listdir(a) if os.path.isdir(os.path.join(a, c))):
        da, db = os.path.join(a, case), os.path.join(b, case)
        fa = sorted(os.listdir(da))
        fb = sorted(os.listdir(db)) if os.path.isdir(db) else []
        if fa != fb:
            print(f"{case}: file lists differ: {sorted(set(fa) ^ set(fb))}")
            bad += 1
            continue
        for f in fa:
            pa, pb = os.path.join(da, f), os.path.join(db, f)
            CURRENT[0] = f"{case}/{f}"
            if f.startswith("state_") and f.endswith(".json"):
                ja, jb = json.load(open(pa)), json.load(open(pb))
                ja.pop("id", None)
                jb.pop("id", None)
                same = same_json(strip(ja), strip(jb))
            elif f.endswith(".json"):
                same = same_json(strip(json.load(open(pa))), strip(json.load(open(pb))))
            elif f.endswith(".jsonl"):
                la, lb = open(pa).read().splitlines(), open(pb).read().splitlines()
                same = len(la) == len(lb) and all(
                    same_json(strip(json.loads(x)), strip(json.loads(y))) for x, y in zip(la, lb))
            elif f.endswith(".csv"):
                same = same_csv(csv_rows(pa), csv_rows(pb))
            else:
                same = filecmp.cmp(pa, pb, shallow=False)
                if not same and RTOL is not None and f.endswith(".vtu"):
                    same = same_vtu(pa, pb)
            if not same:
                print(f"{case}/{f} differs")
                bad += 1
    if RTOL is not None:
        moved = {k: v for k, v in WORST.items() if v > 0}
        if moved:
            k = max(moved, key=moved.get)
            print(f"files with numbers moved within {RTOL:g}: {len(moved)}; largest {moved[k]:.2e} ({k})")
    print(f"differences: {bad}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
