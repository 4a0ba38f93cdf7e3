#!/usr/bin/env python3
"""What Kratos' frictional mortar contact gives on the Cattaneo-Mindlin scene: the shear traction
q/(mu p0) along the slave arc against x/a, after the tangential load and after the normal load
alone, for one or more Kratos runs (contact.csv of post/kratos/kratos_vm272.py), with the
closed form and, optionally, one stickslip run (its contact_NNNN.csv).

    python3 post/kratos/shear_profile.py OUT.png LABEL=out/bench/kratos/cm/L1/contact.csv ... \
        [--ours LABEL=DIR/contact_0011.csv] [--q 0.936]
"""
import argparse
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import measures  # noqa: E402


def kratos_rows(path, step):
    rows = measures.read_kratos_csv(path, step)
    x = [float(r["x"]) for r in rows if r["active"] == "1"]
    q = [float(r["q"]) for r in rows if r["active"] == "1"]
    return x, q


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("runs", nargs="+", help="LABEL=contact.csv of a Kratos run")
    ap.add_argument("--ours", help="LABEL=contact_NNNN.csv of a stickslip run")
    ap.add_argument("--q", type=float, default=0.936)
    ap.add_argument("--mu", type=float, default=0.2)
    args = ap.parse_args()
    a, p0, c = measures.closed_forms(args.q, args.mu)
    s = args.mu * p0
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.6), sharey=False)
    xs = [a * (-1 + 2 * i / 800) for i in range(801)]
    ax1.plot([x / a for x in xs], [measures.q_cm(x, a, p0, c, args.mu) / s for x in xs], "k-", lw=1.2,
             label=f"Cattaneo–Mindlin (c/a = {c / a:.3f})")
    ax2.axhline(0.0, color="k", lw=1.2, label="exact (identical materials: no shear)")
    markers = "Dsv^<>"
    for i, spec in enumerate(args.runs):
        label, path = spec.split("=", 1)
        m = markers[i % len(markers)]
        for ax, step in ((ax1, "final"), (ax2, "normal")):
            x, q = kratos_rows(path, step)
            sign = 1.0
            if step == "final" and q and q[max(range(len(q)), key=lambda k: abs(q[k]))] < 0:
                sign = -1.0
            ax.plot([v / a for v in x], [sign * v / s for v in q], marker=m, ms=4, lw=0.8, label=label)
    if args.ours:
        label, path = args.ours.split("=", 1)
        with open(path, newline="") as fh:
            rows = [r for r in csv.DictReader(fh) if float(r["pressure"]) > 0]
        ax1.plot([float(r["x"]) / a for r in rows], [float(r["shear"]) / s for r in rows], "o", ms=2.5,
                 color="tab:blue", label=label)
    ax1.set_title(f"after the tangential load Q = {args.q:g} N/mm", fontsize=10)
    ax2.set_title("after the normal load P = 10 N/mm alone", fontsize=10)
    for ax in (ax1, ax2):
        ax.set_xlabel("x / a")
        ax.set_xlim(-1.1, 1.1)
        ax.grid(True, lw=0.3, alpha=0.5)
        ax.legend(fontsize=7.5)
    ax1.set_ylabel(r"$q / (\mu p_0)$ at the slave nodes")
    fig.tight_layout()
    fig.savefig(args.out, dpi=130)
    print(args.out)


if __name__ == "__main__":
    main()
