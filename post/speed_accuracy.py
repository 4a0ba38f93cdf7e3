#!/usr/bin/env python3
"""Speed against accuracy: log-log charts of error against wall time over the VM272 ladder.

Usage:
    python3 post/speed_accuracy.py out/bench/accuracy.csv OUTDIR

Reads the CSV written by `cargo bench --bench accuracy` and writes into OUTDIR
  speed_accuracy_pressure.png  max |p - p_H|/p0 over |x| <= 0.95a against wall time
  speed_accuracy_shear.png     max |q - q_CM|/(mu p0) outside the excluded nodes against wall time
for both codes (stickslip: every case and level of the run; CalculiX: the Cattaneo-Mindlin
case on its levels), each point labelled with its mesh level, with the targets (1 % p0, 2 % mu p0)
and a band at 45-60 s for the paper's commercial run (about 45 000 quadratic elements, "under a
minute"; its error was not published and it is not measured here).
Wall time is the wall time of the whole process (both codes), from the same bench run.
"""
import argparse
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {
    ("stickslip", "hertz"): dict(color="tab:blue", marker="o", ls="--", mfc="white",
                                 label="stickslip, Hertz (frictionless)"),
    ("stickslip", "vm272_cm"): dict(color="tab:blue", marker="o", ls="-",
                                    label="stickslip, Cattaneo–Mindlin"),
    ("stickslip", "fig2"): dict(color="tab:green", marker="s", ls=":",
                                label="stickslip, Fig. 2 (q vs eq. qx2CM, of $f_d p_0$)"),
    ("calculix", "vm272_cm"): dict(color="tab:red", marker="^", ls="-",
                                   label="CalculiX 2.20, Cattaneo–Mindlin"),
}


def load(path):
    rows = []
    with open(path, newline="") as fh:
        for r in csv.DictReader(fh):
            if r["status"] != "ok":
                continue
            rows.append(r)
    return rows


def series(rows, code, case, key):
    pts = []
    for r in rows:
        if r["code"] == code and r["case"] == case and r[key] and r["wall_s"]:
            pts.append((float(r["wall_s"]), float(r[key]), int(r["level"])))
    return sorted(pts, key=lambda p: p[2])


def chart(rows, key, cases, target, target_label, ylabel, title, out):
    fig, ax = plt.subplots(figsize=(7.5, 6.0))
    drawn = 0
    for (code, case), st in STYLE.items():
        if case not in cases:
            continue
        pts = series(rows, code, case, key)
        if not pts:
            continue
        x = [p[0] for p in pts]
        y = [p[1] for p in pts]
        ax.plot(x, y, **st)
        drawn += 1
        for xi, yi, lev in pts:
            ax.annotate(f"L{lev}", (xi, yi), textcoords="offset points", xytext=(5, 4),
                        fontsize=8, color=st["color"])
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axhline(target, color="k", lw=0.8, ls="-.")
    ax.text(0.01, target, f" {target_label}", transform=ax.get_yaxis_transform(),
            va="bottom", fontsize=8)
    ax.axvspan(45.0, 60.0, color="0.6", alpha=0.25, lw=0)
    ax.axvline(60.0, color="0.4", lw=1.0)
    ax.text(44.0, 0.6, " paper's ANSYS run\n (~45 000 quadratic\n elements, \"under a\n minute\"; error not\n published, not\n measured here)",
            transform=ax.get_xaxis_transform(), ha="right", va="center", fontsize=7.5, color="0.25")
    lo, hi = ax.get_xlim()
    ax.set_xlim(min(lo, 0.03), max(hi, 600.0))
    ax.set_xlabel("wall time of the whole run (s), 2 threads")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    if drawn:
        ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2,
                  frameon=False)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)
    print(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    ap.add_argument("csv")
    ap.add_argument("outdir")
    args = ap.parse_args()
    rows = load(args.csv)
    if not rows:
        sys.exit(f"{args.csv}: no successful rows")
    os.makedirs(args.outdir, exist_ok=True)
    chart(rows, "p_err_max", ("hertz", "vm272_cm"), 0.01, "target 1 % of $p_0$",
          r"max $|p - p_H|/p_0$ over $|x| \leq 0.95a$",
          "Contact pressure against Hertz, VM272 ladder (P = 10 N/mm)",
          os.path.join(args.outdir, "speed_accuracy_pressure.png"))
    chart(rows, "q_err_max", ("vm272_cm", "fig2"), 0.02, r"target 2 % of $\mu p_0$",
          r"max $|q - q_{CM}|/(\mu p_0)$ outside $c \pm w$, $a - w$ ($w = \max(2h, 0.05a)$)",
          "Shear traction against Cattaneo–Mindlin (μ = 0.2, Q = 0.936 N/mm)",
          os.path.join(args.outdir, "speed_accuracy_shear.png"))


if __name__ == "__main__":
    main()
