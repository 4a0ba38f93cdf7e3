#!/usr/bin/env python3
"""Runs every shipped case and a set of unshipped variants of Fig. 2 with two stickslip binaries
and compares what they answer: exit code, status, Newton iterations and Delassus factorisations,
and `history.csv` value by value (without the `wall_s` and `iterations` columns).

    python3 benches/compare_binaries.py BIN_A BIN_B [NAME ...]

The variants (VTU output off, meshes from meshes/): Fig. 2 on L4, L6 and L7 (L6, L7 built by
`python3 meshes/generate.py vm272_L6 vm272_L7`, skipped when missing), with P = 2 and 40, a
dissimilar pair (lower body E = 70, ν = 0.33), the pilot pulling the bodies apart, the normal
load under displacement control, the alternative radii mesh `vm272_alt`, and a tangential force
during the normal load. Prints one line per case; exits 1 if any answer differs.
"""
import copy
import csv
import glob
import json
import os
import subprocess
import sys
import tempfile

repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
meshes = os.path.join(repo, "meshes")


def cases():
    out = {}
    for f in sorted(glob.glob(os.path.join(repo, "cases", "*.json"))):
        c = json.load(open(f))
        c["mesh"] = os.path.join(meshes, os.path.basename(c["mesh"]))
        c["output"] = {"vtu": False}
        out[os.path.basename(f)[:-5]] = c
    base = out["fig2"]

    def var(name, fn):
        c = copy.deepcopy(base)
        fn(c)
        if os.path.exists(c["mesh"]):
            out[name] = c

    for level in (4, 6, 7):
        var(f"fig2_L{level}", lambda c, l=level: c.__setitem__("mesh", os.path.join(meshes, f"vm272_L{l}.msh")))
    for p in (2.0, 40.0):
        def load(c, p=p):
            c["stages"][0]["pilot_y"] = {"force": -p}
            c["stages"][1]["pilot_x"] = {"force": 0.05 * p}
            c["contact"]["friction"]["load"] = p
        var(f"fig2_P{p:g}", load)
    var("fig2_dissimilar", lambda c: c["bodies"][0].update({"E": 70.0, "nu": 0.33}))
    var("fig2_pull", lambda c: c["stages"][0].__setitem__("pilot_y", {"force": 10.0}))
    var("fig2_displacement", lambda c: c["stages"][0].__setitem__("pilot_y", {"displacement": -0.18}))
    var("fig2_alt", lambda c: c.__setitem__("mesh", os.path.join(meshes, "vm272_alt.msh")))
    var("fig2_normal_with_q", lambda c: c["stages"][0].__setitem__("pilot_x", {"force": 0.5}))
    return out


def run(binary, path, out):
    r = subprocess.run([binary, "run", path, "--no-cache", "--out", out, "--quiet"],
                       capture_output=True, text=True)
    summary = os.path.join(out, "summary.json")
    history = os.path.join(out, "history.csv")
    s = json.load(open(summary)) if os.path.exists(summary) else None
    h = list(csv.reader(open(history))) if os.path.exists(history) else []
    return r.returncode, s, h


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    a, b = sys.argv[1], sys.argv[2]
    wanted = sys.argv[3:]
    all_cases = cases()
    differ = False
    with tempfile.TemporaryDirectory() as work:
        for name, case in all_cases.items():
            if wanted and name not in wanted:
                continue
            path = os.path.join(work, name + ".json")
            json.dump(case, open(path, "w"))
            ra = run(a, path, os.path.join(work, "a_" + name))
            rb = run(b, path, os.path.join(work, "b_" + name))
            line = f"{name}: exit {ra[0]}/{rb[0]}"
            same = ra[0] == rb[0]
            if ra[1] and rb[1]:
                sa, sb = ra[1], rb[1]
                same &= sa.get("status") == sb.get("status")
                line += (f", status {'same' if sa.get('status') == sb.get('status') else 'DIFFERS'}"
                         f", Newton {sa.get('newton_iterations')}/{sb.get('newton_iterations')}"
                         f", factorisations {sa.get('lu_factorisations')}/{sb.get('lu_factorisations')}")
                ha, hb = ra[2], rb[2]
                header = ha[0] if ha else []
                diffs, worst, scaled = 0, 0.0, 0.0
                same &= len(ha) == len(hb)
                # Each column's largest magnitude over both runs (differences of values near
                # zero are judged against it).
                size = {}
                for r in ha[1:] + hb[1:]:
                    for k, x in enumerate(r):
                        try:
                            size[k] = max(size.get(k, 0.0), abs(float(x)))
                        except ValueError:
                            pass
                for r1, r2 in zip(ha[1:], hb[1:]):
                    for k, (x, y) in enumerate(zip(r1, r2)):
                        if header[k] in ("wall_s", "iterations") or x == y:
                            continue
                        diffs += 1
                        try:
                            d = abs(float(x) - float(y))
                            worst = max(worst, d / max(abs(float(x)), abs(float(y))))
                            scaled = max(scaled, d / size[k])
                        except ValueError:
                            worst = float("nan")
                same &= diffs == 0
                first = lambda h: h[1][header.index("iterations")] if len(h) > 1 else "-"
                line += (f", history rows {len(ha) - 1}/{len(hb) - 1}, values differing {diffs}"
                         f" (largest relative {worst:.1e}, to the column's largest {scaled:.1e})"
                         f", first step iterations {first(ha)}/{first(hb)}")
                qb = (sb.get("friction") or {}).get("q_max")
                qa = (sa.get("friction") or {}).get("q_max")
                if qa is not None and qb is not None and qa != qb and qa != 0:
                    line += f", Q_max {qa:.9g}/{qb:.9g} ({(qb - qa) / abs(qa):+.1e})"
            elif (ra[1] is None) != (rb[1] is None):
                same = False
            line += "" if same else "  <-- DIFFERS"
            differ |= not same
            print(line, flush=True)
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
