#!/usr/bin/env python3
"""Each phase of the Fig. 2 run against the number of DOFs, log-log, over the VM272 ladder.

Usage:
    python3 post/scaling_chart.py out/bench/scaling.csv docs/figs/scaling.png

Reads the CSV written by `cargo bench --bench scaling` (one row per level) and draws the phases
of `summary.json` (assemble, analyse, factorise, condense = the Delassus operator, the contact
Newton part of solve, write, write wait), the floor (assemble + analyse + factorise) and the
process wall time, each labelled with its least-squares exponent over the levels given by
--fit (default 3-7), with N^1 and N^1.5 guide slopes. Where the CSV has them (the
`factor_*` columns), a second panel draws the factorisation's modelled operations
(`factor_flops` of the summary: K̂ itself, the coupling the constraint rows add, the constraint
block) with their exponents: counts, not times, the same on every machine.
"""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

SERIES = [
    ("assemble", "assemble", dict(color="tab:green", marker="s")),
    ("analyse", "analyse", dict(color="tab:olive", marker="v")),
    ("factorise", "factorise", dict(color="tab:red", marker="o")),
    ("constraint_block", "of factorise: constraint block (dense W and its LDLᵀ)", dict(color="tab:pink", marker="d")),
    ("condense", "condense (W handed over)", dict(color="tab:purple", marker="D")),
    ("contact_newton", "contact Newton", dict(color="tab:orange", marker="^")),
    ("write", "write (background)", dict(color="tab:gray", marker="x")),
    ("floor", "floor = assemble + analyse + factorise (as they ran, overlapped)", dict(color="black", ls="--", marker="")),
    ("wall", "process wall", dict(color="black", marker="o", mfc="white")),
]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("csv")
    ap.add_argument("png")
    ap.add_argument("--fit", default="3-7")
    a = ap.parse_args()
    lo, hi = (int(x) for x in a.fit.split("-"))
    rows = [r for r in csv.DictReader(open(a.csv)) if r["status"] != "failed"]
    for r in rows:
        span = float(r.get("build_span") or 0.0)
        r["floor"] = span if span > 0 else (
            float(r["assemble"]) + float(r["analyse"]) + float(r["factorise"]))
    n = np.array([float(r["dofs"]) for r in rows])
    levels = [int(r["level"]) for r in rows]
    fit = np.array([lo <= lv <= hi for lv in levels])
    flops = [("flops_k", "K̂ itself", dict(color="tab:blue", marker="o")),
             ("flops_coupling", "coupling the constraint rows add", dict(color="tab:red", marker="s")),
             ("flops_block", "constraint block (dense LDLᵀ of W)", dict(color="tab:pink", marker="d"))]
    has_flops = any(float(r.get("flops_k") or 0.0) > 0 for r in rows)
    if has_flops:
        fig, (ax, bx) = plt.subplots(1, 2, figsize=(14, 6))
    else:
        fig, ax = plt.subplots(figsize=(8, 6))
    for key, label, style in SERIES:
        y = np.array([float(r.get(key) or 0.0) for r in rows])
        ok = y > 0
        if not ok.any():
            continue
        sel = fit & ok
        e = np.polyfit(np.log(n[sel]), np.log(y[sel]), 1)[0] if sel.sum() >= 2 else float("nan")
        ax.loglog(n[ok], y[ok], label=f"{label}  (N^{e:.2f})", **style)
    x0, x1 = n.min(), n.max()
    ref = float(rows[-1]["floor"])
    for p, ls in [(1.0, ":"), (1.5, "-.")]:
        ax.loglog([x0, x1], [ref * (x0 / x1) ** p, ref], color="lightgray", ls=ls, lw=1,
                  label=f"slope {p:g}")
    for lv, x, r in zip(levels, n, rows):
        ax.annotate(f"L{lv}", (x, float(r["wall"])), textcoords="offset points", xytext=(0, 6),
                    ha="center", fontsize=8)
    ax.set_xlabel("free DOFs N")
    ax.set_ylabel("time (s)")
    ax.set_title(f"Fig. 2 run by phase against DOFs (exponents fitted over L{lo}–L{hi})")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    if has_flops:
        for key, label, style in flops:
            y = np.array([float(r.get(key) or 0.0) for r in rows])
            ok = y > 0
            sel = fit & ok
            e = np.polyfit(np.log(n[sel]), np.log(y[sel]), 1)[0] if sel.sum() >= 2 else float("nan")
            bx.loglog(n[ok], y[ok], label=f"{label}  (N^{e:.2f})", **style)
        y5 = [float(r["flops_k"]) for r in rows if r["level"] == "5"]
        if y5:
            n5 = n[levels.index(5)]
            for p, ls in [(1.5, "-."), (3.0, ":")]:
                bx.loglog([x0, x1], [y5[0] * (x0 / n5) ** p, y5[0] * (x1 / n5) ** p],
                          color="lightgray", ls=ls, lw=1, label=f"slope {p:g}")
        bx.set_xlabel("free DOFs N")
        bx.set_ylabel("modelled operations")
        bx.set_title("The factorisation's modelled operations (machine-independent)")
        bx.grid(True, which="both", alpha=0.3)
        bx.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(a.png, dpi=120)
    print(f"wrote {a.png}")


if __name__ == "__main__":
    main()
