#!/usr/bin/env python3
"""Each phase of the Fig. 2 run against the number of DOFs, log-log, over the VM272 ladder.

Usage:
    python3 post/scaling_chart.py out/bench/scaling.csv docs/figs/scaling.png

Reads the CSV written by `cargo bench --bench scaling` (one row per level) and draws the phases
of `summary.json` (assemble, analyse, factorise, condense = the Delassus operator, the contact
Newton part of solve, write, write wait), the floor (assemble + analyse + factorise) and the
process wall time, each labelled with its least-squares exponent over the levels given by
--fit (default 3-7), with N^1 and N^1.5 guide slopes.
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
    fig.tight_layout()
    fig.savefig(a.png, dpi=120)
    print(f"wrote {a.png}")


if __name__ == "__main__":
    main()
