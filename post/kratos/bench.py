#!/usr/bin/env python3
"""Speed against accuracy, stickslip and Kratos Multiphysics side by side (issue 51).

Run through benches/kratos.sh (which makes the venv with the pinned Kratos wheels and gmsh);
directly:

    out/bench/kratos-venv/bin/python post/kratos/bench.py [--reps 3] [--cases hertz,cm] ...

For every repetition, every case and every level it runs our release binary (a copy of
`target/release/stickslip` taken at the start, STICKSLIP_NO_CACHE=1, `--threads T`) and then
Kratos (post/kratos/kratos_vm272.py, OMP_NUM_THREADS=T) on the same level, so that the two
codes alternate (A B A B ...) and a load on the shared machine falls on both alike. Wall time =
the whole process, measured around it by this script, for both codes; the table keeps the
median of the repetitions (and min, max). The errors are those of benches/accuracy.rs
(post/kratos/measures.py), computed from each code's nodal contact tractions of the last
step; Kratos' errors are the same in every repetition (checked: a difference is reported).

Writes out/bench/kratos.csv (one row per code, case, level: medians) and out/bench/kratos.md
(the tables, the ratios at equal error, the run's conditions); nothing is left out: a run that
fails or does not converge is a row with its status.

Cases:
  hertz  cases/hertz.json (frictionless, P = 10 N/mm)
  cm     cases/vm272_cm.json (mu = 0.2, P = 10 N/mm then Q = 0.936 N/mm = 0.468 mu P)
  cm08   the same with Q = 0.8 mu P = 1.6 N/mm
"""
from __future__ import annotations

import argparse
import csv
import hashlib
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)

import measures  # noqa: E402

CASES = {
    "hertz": {"file": "hertz.json", "frictional": False, "q": 0.0},
    "cm": {"file": "vm272_cm.json", "frictional": True, "q": 0.936},
    "cm08": {"file": "vm272_cm.json", "frictional": True, "q": 1.6},
}


def parse_levels(s):
    s = s.strip()
    if not s or s == "none":
        return []
    if "-" in s:
        a, b = s.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(v) for v in s.split(",")]


def parse_per_level(s, default):
    """"5" or "0:5,3:10,4:20" (a level takes the value of the largest key <= it)."""
    if ":" not in s:
        v = int(s)
        return lambda L: v
    table = sorted((int(k), int(v)) for k, v in (t.split(":") for t in s.split(",")))
    def f(L):
        out = default
        for k, v in table:
            if L >= k:
                out = v
        return out
    return f


# ------------------------------------------------------------------------------------------
# stickslip
# ------------------------------------------------------------------------------------------
def read_columns(path, names):
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    return [[float(r[n]) for r in rows] for n in names]


def run_ours(binary, case, level, threads, tmp):
    spec = CASES[case]
    with open(os.path.join(REPO, "cases", spec["file"])) as fh:
        v = json.load(fh)
    v["mesh"] = os.path.join(REPO, "meshes", f"vm272_L{level}.msh")
    v["output"] = {"vtu": True, "every": 100000}
    if spec["frictional"]:
        v["stages"][1]["pilot_x"]["force"] = spec["q"]
    path = os.path.join(tmp, f"{case}_L{level}.json")
    with open(path, "w") as fh:
        json.dump(v, fh, indent=1)
    out = os.path.join(tmp, f"{case}_L{level}")
    shutil.rmtree(out, ignore_errors=True)
    env = dict(os.environ, STICKSLIP_NO_CACHE="1")
    t = time.perf_counter()
    pr = subprocess.run([binary, "run", path, "--out", out, "--quiet", "--threads", str(threads)],
                        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    wall = time.perf_counter() - t
    rec = {"code": "stickslip", "case": case, "level": level, "wall_s": wall, "threads": threads}
    if pr.returncode != 0:
        msg = next((l for l in pr.stderr.decode(errors="replace").splitlines() if l.startswith("error")), "")
        rec["status"] = f"exit {pr.returncode}: {msg[:80]}"
        return rec
    rec["status"] = "ok"
    with open(os.path.join(out, "summary.json")) as fh:
        s = json.load(fh)
    rec["elements"] = s.get("triangles")
    rec["nodes"] = s.get("nodes")
    rec["dofs"] = s.get("dofs_free")
    rec["newton_iterations"] = s.get("newton_iterations")
    step, c_fe = read_columns(os.path.join(out, "history.csv"), ["step", "c"])
    last = int(step[-1])
    x, p, q = read_columns(os.path.join(out, f"contact_{last:04d}.csv"), ["x", "pressure", "shear"])
    sc = measures.score(x, p, q, level, spec["frictional"], spec["q"], 0.2)
    if spec["frictional"]:
        _, _, c = measures.closed_forms(spec["q"], 0.2)
        sc["c_fe"] = c_fe[-1]
        sc["c_err_rel"] = c_fe[-1] / c - 1.0
    rec.update(sc)
    rec["p_integral"] = p_integral(x, p)
    shutil.rmtree(out, ignore_errors=True)
    return rec


def p_integral(x, p):
    pts = sorted(zip(x, p))
    return sum(0.5 * (p0 + p1) * (x1 - x0) for (x0, p0), (x1, p1) in zip(pts, pts[1:]))


# ------------------------------------------------------------------------------------------
# Kratos
# ------------------------------------------------------------------------------------------
def run_kratos(args, case, level, nsteps, tsteps):
    import kratos_vm272 as kv

    spec = CASES[case]
    ka = kv.default_args()
    ka.case = "cm" if spec["frictional"] else "hertz"
    ka.q = spec["q"] if spec["frictional"] else 0.936
    ka.threads = args.threads
    ka.out = os.path.join(REPO, "out", "bench", "kratos")
    ka.tag = case
    ka.normal_steps = nsteps
    ka.tangential_steps = tsteps
    ka.timeout = args.kratos_timeout
    for k, v in json.loads(args.kratos_args).items():
        setattr(ka, k, v)
    rec = kv.run_level(ka, level)
    rec["case"] = case   # the bench's case name (cm08 runs the driver's "cm" with another Q)
    rec["wall_s"] = rec.pop("wall_time_s")
    rec["newton_iterations"] = rec.get("iterations")
    x, p = kv.final_xp(os.path.join(REPO, rec["dir"], "contact.csv"))
    rec["p_integral"] = p_integral(x, p) if x else None
    rec["kratos_import_s"] = rec.get("import_s")
    rec["kratos_initialize_s"] = rec.get("initialize_s")
    rec["kratos_loop_s"] = rec.get("solve_loop_s")
    if rec.get("steps_run"):
        rec["iterations_per_step"] = rec["iterations"] / rec["steps_run"]
    rec["settings"] = f"{nsteps} normal" + (f" + {tsteps} tangential" if spec["frictional"] else "") + " increments"
    return rec


# ------------------------------------------------------------------------------------------
# tables
# ------------------------------------------------------------------------------------------
ERR_KEYS = ("p_err_max", "p_err_rms", "q_err_max", "q_err_rms", "c_err_rel", "a_fe_over_a", "p_integral")
COLS = ["case", "code", "level", "elements", "nodes", "dofs", "threads", "reps", "wall_s", "wall_min_s",
        "wall_max_s", "walls_s", "newton_iterations", "p_err_max", "p_err_rms", "q_err_max", "q_err_rms",
        "c_err_rel", "a_fe_over_a", "p_integral", "status", "settings", "iterations_per_step",
        "steps_not_converged", "kratos_import_s", "kratos_initialize_s", "kratos_loop_s", "max_rss_mib"]


def merge(recs):
    """Median over the repetitions of one (code, case, level)."""
    r0 = dict(recs[-1])
    walls = [r["wall_s"] for r in recs]
    r0["reps"] = len(recs)
    r0["wall_s"] = statistics.median(walls)
    r0["wall_min_s"] = min(walls)
    r0["wall_max_s"] = max(walls)
    r0["walls_s"] = ";".join(f"{w:.3f}" for w in walls)
    for k in ("kratos_import_s", "kratos_initialize_s", "kratos_loop_s"):
        vals = [r[k] for r in recs if r.get(k) is not None]
        if vals:
            r0[k] = statistics.median(vals)
    statuses = sorted({r["status"] for r in recs})
    r0["status"] = statuses[0] if len(statuses) == 1 else " / ".join(statuses)
    for k in ERR_KEYS:
        vals = {round(r[k], 10) for r in recs if r.get(k) is not None and not math.isnan(r[k])}
        if len(vals) > 1:
            r0["status"] += f"; {k} differs between repetitions ({min(vals):.4g}..{max(vals):.4g})"
    return r0


def fmt(v, d=4):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "—"
    if isinstance(v, float):
        return f"{v:.{d}f}"
    return str(v)


def front(rows, key):
    """Cheapest-first points of a ladder that are more accurate than every cheaper one."""
    pts = sorted(((r["wall_s"], r[key], r["level"]) for r in rows
                  if r["status"] == "ok" and r.get(key) is not None and r[key] > 0), key=lambda t: t[0])
    out = []
    for w, e, L in pts:
        if not out or e < out[-1][1]:
            out.append((w, e, L))
    return out


def time_at_error(fr, e):
    """Wall time the ladder `fr` needs for error e: log-log interpolation between the two front
    points around e. Returns (time, note): note '≤' when the cheapest point is already better
    (its time is an upper bound), None when no point reaches e."""
    if not fr:
        return None, "no ok run"
    if e >= fr[0][1]:
        return fr[0][0], "≤"
    for (w0, e0, _), (w1, e1, _) in zip(fr, fr[1:]):
        if e1 <= e < e0:
            t = (math.log(e) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(w0) + t * (math.log(w1) - math.log(w0))), ""
    return None, f"not reached (best {fr[-1][1]:.4f})"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", default="hertz,cm")
    ap.add_argument("--levels", default="0-5", help="our levels (meshes/vm272_L{k}.msh)")
    ap.add_argument("--kratos-levels", default="0-4")
    ap.add_argument("--kratos-cm-levels", default=None, help="Kratos levels of the frictional cases (default --kratos-levels)")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--bin", default=os.path.join(REPO, "target", "release", "stickslip"))
    ap.add_argument("--normal-steps", default="0:5,3:10,4:20,5:40",
                    help="Kratos normal increments per level, e.g. '5' or '0:5,4:20'")
    ap.add_argument("--cm-normal-steps", default="20",
                    help="Kratos normal increments of the frictional cases (5 diverges; see docs/kratos.md)")
    ap.add_argument("--tangential-steps", default="10", help="Kratos tangential increments per level")
    ap.add_argument("--kratos-args", default="{}", help="JSON of further kratos_vm272 options, e.g. '{\"f_stick_res_rtol\": 1e-3}'")
    ap.add_argument("--kratos-timeout", type=float, default=1800.0)
    ap.add_argument("--csv", default=os.path.join(REPO, "out", "bench", "kratos.csv"))
    ap.add_argument("--report-only", action="store_true",
                    help="rewrite the .md report from --csv (and its _run.json) without running anything")
    args = ap.parse_args()
    if args.report_only:
        meta = {"head": "Run: (conditions not recorded)", "cases": None}
        try:
            with open(os.path.splitext(args.csv)[0] + "_run.json") as fh:
                meta = json.load(fh)
        except FileNotFoundError:
            pass
        rows = rows_from_csv(args.csv)
        cases = meta["cases"] or sorted({r["case"] for r in rows})
        report(args, rows, cases, meta["head"])
        return

    outdir = os.path.join(REPO, "out", "bench", "kratos")
    os.makedirs(outdir, exist_ok=True)
    tmp = os.path.join(outdir, "ours")
    os.makedirs(tmp, exist_ok=True)
    # the binary is copied once, so that a rebuild during the bench does not change it
    binary = os.path.join(outdir, "stickslip.bin")
    shutil.copy2(args.bin, binary)
    with open(binary, "rb") as fh:
        bin_hash = hashlib.sha256(fh.read()).hexdigest()[:16]
    git = subprocess.run(["git", "-C", REPO, "describe", "--always", "--dirty"], capture_output=True, text=True).stdout.strip()

    # the closed forms agree with `stickslip analytic`
    an = json.loads(subprocess.run([binary, "analytic", "hertz"], capture_output=True, text=True).stdout)
    a, p0, _ = measures.closed_forms()
    assert abs(an["a"] - a) < 1e-12 and abs(an["p0"] - p0) < 1e-9, (an, a, p0)

    cases = [c for c in args.cases.split(",") if c]
    ours_levels = parse_levels(args.levels)
    k_levels = parse_levels(args.kratos_levels)
    k_cm_levels = parse_levels(args.kratos_cm_levels) if args.kratos_cm_levels is not None else k_levels
    nsteps = parse_per_level(args.normal_steps, 5)
    cm_nsteps = parse_per_level(args.cm_normal_steps, 20)
    tsteps = parse_per_level(args.tangential_steps, 10)
    runs = {}
    t_all = time.perf_counter()
    for rep in range(args.reps):
        for case in cases:
            kl = k_cm_levels if CASES[case]["frictional"] else k_levels
            for level in sorted(set(ours_levels) | set(kl)):
                if level in ours_levels:
                    r = run_ours(binary, case, level, args.threads, tmp)
                    runs.setdefault(("stickslip", case, level), []).append(r)
                    print(f"rep {rep} {case} L{level} stickslip {r['wall_s']:.2f} s {r['status']}", file=sys.stderr, flush=True)
                if level in kl:
                    ns = cm_nsteps(level) if CASES[case]["frictional"] else nsteps(level)
                    r = run_kratos(args, case, level, ns, tsteps(level))
                    runs.setdefault(("kratos", case, level), []).append(r)
                    print(f"rep {rep} {case} L{level} kratos {r['wall_s']:.2f} s {r['status']} p_err_max={fmt(r.get('p_err_max'))} q_err_max={fmt(r.get('q_err_max'))}",
                          file=sys.stderr, flush=True)
        write_outputs(args, runs, cases, binary, bin_hash, git, time.perf_counter() - t_all, rep + 1)


def write_outputs(args, runs, cases, binary, bin_hash, git, elapsed, reps_done):
    rows = [merge(v) for k, v in sorted(runs.items(), key=lambda kv: (kv[0][1], kv[0][0], kv[0][2]))]
    tmp = args.csv + ".tmp"
    with open(tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=COLS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{r[k]:.6e}" if isinstance(r.get(k), float) else r.get(k, "")) for k in COLS})
    os.replace(tmp, args.csv)
    head = (f"Run: {time.strftime('%Y-%m-%d %H:%M')}, {reps_done} repetition(s), {args.threads} threads for each code "
            f"(stickslip `--threads {args.threads}`; Kratos OMP_NUM_THREADS={args.threads}), the two codes alternating; "
            f"stickslip binary sha256 {bin_hash}… (tree {git}); whole bench {elapsed:.0f} s.")
    with open(os.path.splitext(args.csv)[0] + "_run.json", "w") as fh:
        json.dump({"head": head, "cases": cases}, fh)
    report(args, rows, cases, head)


def rows_from_csv(path):
    """The merged rows of a bench CSV, numbers as numbers (for --report-only)."""
    out = []
    with open(path, newline="") as fh:
        for r in csv.DictReader(fh):
            row = {}
            for k, v in r.items():
                if v in ("", None):
                    row[k] = None
                    continue
                try:
                    row[k] = int(v) if k in ("level", "elements", "nodes", "dofs", "threads", "reps",
                                             "newton_iterations", "steps_not_converged") else float(v)
                except ValueError:
                    row[k] = v
            out.append(row)
    return out


def report(args, rows, cases, head):
    md = []
    out = md.append
    out(head + "\n")
    out("| case | code | L | elements | nodes | DOFs | wall s (median) | min–max | Newton its | p err max | p err RMS | q err max | q err RMS | c err | a_FE/a | ∫p dx | status |")
    out("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        out(f"| {r['case']} | {r['code']} | {r['level']} | {fmt(r.get('elements'))} | {fmt(r.get('nodes'))} | {fmt(r.get('dofs'))} | "
            f"{r['wall_s']:.2f} | {r['wall_min_s']:.2f}–{r['wall_max_s']:.2f} | {fmt(r.get('newton_iterations'))} | "
            f"{fmt(r.get('p_err_max'))} | {fmt(r.get('p_err_rms'))} | {fmt(r.get('q_err_max'))} | {fmt(r.get('q_err_rms'))} | "
            f"{fmt(r.get('c_err_rel') * 100 if r.get('c_err_rel') is not None else None, 2)}{'%' if r.get('c_err_rel') is not None else ''} | "
            f"{fmt(r.get('a_fe_over_a'))} | {fmt(r.get('p_integral'), 3)} | {r['status']}"
            + (f" ({r['settings']})" if r.get("settings") else "") + " |")
    out("")
    for case in cases:
        measures_ = [("p_err_max", "max |p − p_H|/p0")]
        if CASES[case]["frictional"]:
            measures_.append(("q_err_max", "max |q − q_CM|/(μp0)"))
        for key, label in measures_:
            ours = [r for r in rows if r["code"] == "stickslip" and r["case"] == case]
            kr = [r for r in rows if r["code"] == "kratos" and r["case"] == case]
            fr = front(ours, key)
            if not kr:
                continue
            out(f"\n{case}, {label}: Kratos' wall time over ours at Kratos' error (ours interpolated log–log along our ladder's cheapest-first front):\n")
            out("| Kratos L | Kratos wall s | Kratos error | our wall s at that error | ratio | note |")
            out("|---|---|---|---|---|---|")
            for r in kr:
                e = r.get(key)
                if e is None or math.isnan(e):
                    out(f"| {r['level']} | {r['wall_s']:.2f} | — | — | — | {r['status']} |")
                    continue
                t, note = time_at_error(fr, e)
                ratio = "—"
                if t:
                    ratio = ("≥ " if note == "≤" else "") + f"{r['wall_s'] / t:.0f}"
                why = "our cheapest level is already as accurate" if note == "≤" else note
                if r["status"] != "ok":
                    # shown for what it is: the time of a run whose answer is not a valid result
                    ratio = f"({ratio})" if t else ratio
                    why = f"Kratos run not ok: {r['status']}" + (f"; {why}" if why else "")
                out(f"| {r['level']} | {r['wall_s']:.2f} | {e:.4f} | {fmt(t, 3)} | {ratio} | {why} |")
    with open(os.path.splitext(args.csv)[0] + ".md", "w") as fh:
        fh.write("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
