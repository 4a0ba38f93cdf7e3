#!/usr/bin/env python3
"""Draw the closed-form figures of Papangelo, Ciavarella & Barber (Figs. 1, 4, 5, 6, and the
closed-form curves of Figs. 2, 3) from `stickslip analytic ...` CSV output.

Usage:
    python3 post/analytic_figs.py OUTDIR [--bin PATH]

The binary defaults to $STICKSLIP_BIN, else target/release/stickslip.
Line styles follow the paper: dotted = unstable branch (Figs. 4, 5) or the Cattaneo-Mindlin
(f = f_s) continuation where b would exceed a (Fig. 5); dashed = small-scale criterion
s0 << c not satisfied (Fig. 6, threshold s0/c <= 0.1 at the maximum).
"""
import argparse
import csv
import io
import os
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def run_csv(binary, *args):
    """Run `binary analytic ARGS` and return its CSV as a dict of columns."""
    cmd = [binary, "analytic", *map(str, args)]
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        sys.exit(f"command failed: {' '.join(cmd)}\n{res.stderr}")
    rows = list(csv.DictReader(io.StringIO(res.stdout)))
    cols = {}
    for key in rows[0]:
        vals = [r[key] for r in rows]
        if all(v in ("true", "false") for v in vals):
            cols[key] = np.array([v == "true" for v in vals])
        else:
            try:
                cols[key] = np.array([float(v) if v != "" else np.nan for v in vals])
            except ValueError:
                cols[key] = np.array(vals)
    return cols


def segments(mask):
    """Contiguous runs of equal mask values as (start, stop_inclusive, value); neighbouring runs
    share their boundary point so that the drawn line is continuous."""
    out, start = [], 0
    for i in range(1, len(mask) + 1):
        if i == len(mask) or mask[i] != mask[start]:
            out.append((start, min(i, len(mask) - 1), bool(mask[start])))
            start = i
    return out


def plot_styled(ax, x, y, solid_mask, color, label, other_style=":"):
    """Solid where solid_mask, other_style elsewhere; the legend shows a solid line."""
    for s, e, ok in segments(solid_mask):
        ax.plot(x[s:e + 1], y[s:e + 1], "-" if ok else other_style, color=color)
    ax.plot([], [], "-", color=color, label=label)


def fig1(b, out):
    fig, ax = plt.subplots(figsize=(6, 4))
    ramp = run_csv(b, "law-curve", "--shape", "ramp", "--fs", 1, "--fd", 0, "--delta", 1,
                   "--u-max", 3, "--n", 601)
    step = run_csv(b, "law-curve", "--shape", "step", "--fs", 1, "--fd", 0, "--delta", 1,
                   "--u-max", 3, "--n", 601)
    ax.plot(ramp["u"], ramp["mu"], "-", color="0.3", lw=1.2, label="ramp")
    ax.plot(step["u"], step["mu"], "-", color="0.6", lw=1.2, label="step")
    for (ac, bc, ls) in [(1.6, 1.5, "-."), (8.0, 4.5, ":"), (8.0, 1.2, "--")]:
        d = run_csv(b, "implied-law", "--a-over-c", ac, "--b-over-c", bc, "--n", 401)
        u = np.append(d["u_over_delta"], 3.0)
        f = np.append(d["f_norm"], 0.0)
        ax.plot(u, f, ls, color="k", label=f"double C-M, a/c={ac:g}, b/c={bc:g}")
    ax.set_xlim(0, 3)
    ax.set_ylim(-0.02, 1.05)
    ax.set_xlabel(r"$u/\Delta$")
    ax.set_ylabel(r"$(f-f_d)/(f_s-f_d)$")
    ax.set_title("Fig. 1: friction law implied by the double C-M solution")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig1_implied_law.png"), dpi=150)
    plt.close(fig)


def fig4(b, out):
    fig, ax = plt.subplots(figsize=(6, 4.5))
    psis = [0.0, 0.01, 0.05, 0.1, 0.2, 0.5]
    colors = plt.cm.viridis(np.linspace(0, 0.9, len(psis)))
    for psi, col in zip(psis, colors):
        d = run_csv(b, "jkr-curve", "--psi", psi, "--n", 401)
        plot_styled(ax, d["c_over_a"], d["q_ratio"], d["stable"], col, rf"$\Psi$={psi:g}")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, None)
    ax.set_xlabel("$c/a$")
    ax.set_ylabel(r"$Q_x/f_dP$")
    ax.set_title("Fig. 4: JKR limit (dotted: unstable under force control)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig4_jkr.png"), dpi=150)
    plt.close(fig)


def fig5(b, out):
    psi = 0.1
    fig, ax = plt.subplots(figsize=(6, 4.5))
    d = run_csv(b, "jkr-curve", "--psi", psi, "--n", 401)
    plot_styled(ax, d["c_over_a"], d["q_ratio"], d["stable"], "k", "JKR")
    for lam, col in [(0.025, "tab:blue"), (0.4, "tab:red")]:
        d = run_csv(b, "dcm-curve", "--psi", psi, "--lambda", lam, "--n", 401)
        solid = d["stable"] & (d["branch"] == "dcm")
        plot_styled(ax, d["c_over_a"], d["q_ratio"], solid, col,
                    rf"double C-M, $\Lambda$={lam:g}")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, None)
    ax.set_xlabel("$c/a$")
    ax.set_ylabel(r"$Q_x/f_dP$")
    ax.set_title(r"Fig. 5: double C-M vs JKR, $\Psi$=0.1" "\n"
                 r"(dotted: unstable, or C-M with $f_s$ where $b>a$)", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig5_dcm_vs_jkr.png"), dpi=150)
    plt.close(fig)


def fig6(b, out):
    fig, ax = plt.subplots(figsize=(6, 4.5))
    chis = [0.001, 0.01, 0.05, 0.1, 0.2]
    colors = plt.cm.plasma(np.linspace(0, 0.85, len(chis)))
    ax.axvline(1.0, color="k", lw=1.0, label=r"$\chi$=0")
    for chi, col in zip(chis, colors):
        d = run_csv(b, "apparent-curve", "--chi", chi, "--ratio-max", 3, "--n", 121, "--dcm")
        plot_styled(ax, d["q_max_jkr"], d["fs_over_fd"], d["small_scale_ok"], col,
                    rf"$\chi$={chi:g} (JKR)", other_style="--")
        ax.plot(d["q_max_dcm"][::6], d["fs_over_fd"][::6], "o", ms=3, color=col, mfc="none")
    ax.plot([], [], "o", ms=3, color="0.4", mfc="none", label="double C-M")
    ax.plot([1, 3], [1, 3], color="0.7", lw=0.8, label=r"$Q_{max}/P=f_s$")
    ax.set_xlim(0.95, 2.0)
    ax.set_ylim(1, 3)
    ax.set_xlabel(r"$Q_{max}/f_dP$")
    ax.set_ylabel(r"$f_s/f_d$")
    ax.set_title(r"Fig. 6: apparent static friction (dashed: $s_0/c>0.1$)", fontsize=10)
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig6_apparent.png"), dpi=150)
    plt.close(fig)


def fig23(b, out):
    for name, q, lam in [("fig2_traction", 0.8, 0.05), ("fig3_traction", 0.9, 0.277)]:
        d = run_csv(b, "traction", "--fs", 0.15, "--fd", 0.1, "--lambda", lam,
                    "--q-ratio", q, "--n", 801)
        fig, ax = plt.subplots(figsize=(6, 4))
        x = d["x_over_a"]
        ax.plot(x, d["q_dcm"], "-", color="k", lw=1.5, label="double C-M (qx2CM)")
        ax.plot(x, d["q_cm_fd"], "-.", color="tab:blue", label=r"C-M, $f=f_d$")
        qj = np.where(d["q_jkr"] < 3 * np.nanmax(d["q_dcm"]), d["q_jkr"], np.nan)
        ax.plot(x, qj, "--", color="tab:red", label="JKR (qxJKRDelta)")
        ax.set_xlim(-1, 1)
        ax.set_ylim(0, 1.3 * np.nanmax(d["q_dcm"]))
        ax.set_xlabel("$x/a$")
        ax.set_ylabel(r"$q_x$ (N/mm$^2$)")
        ax.set_title(rf"$Q_x$={q:g}$f_dP$, $f_s$=0.15, $f_d$=0.1, $\Lambda$={lam:g} (closed forms)",
                     fontsize=10)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(out, name + ".png"), dpi=150)
        plt.close(fig)


def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("outdir")
    p.add_argument("--bin", default=os.environ.get("STICKSLIP_BIN", "target/release/stickslip"))
    a = p.parse_args()
    os.makedirs(a.outdir, exist_ok=True)
    for f in (fig1, fig4, fig5, fig6, fig23):
        f(a.bin, a.outdir)
    print(f"figures written to {a.outdir}")


if __name__ == "__main__":
    main()
