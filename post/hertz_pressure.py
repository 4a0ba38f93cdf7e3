#!/usr/bin/env python3
"""FE contact pressure against the Hertz closed form (VM272 normal load).

Usage:
    python3 post/hertz_pressure.py RUN_DIR OUT.png [--step N] [--load P] [--bin PATH]

Plots p(x)/p0 against x/a for the last written contact step of RUN_DIR (output of
`stickslip run cases/hertz.json --out RUN_DIR`), vertex and mid-edge nodes as separate point
sets, with p = p0 sqrt(1 - x^2/a^2); a and p0 come from `stickslip analytic hertz --load P`
(P defaults to the normal contact force of that step in history.csv; R, E, nu are the VM272
defaults of the CLI). Prints max |p - p_H|/p0 over |x| <= 0.95 a.
The binary is --bin, else $STICKSLIP_BIN, else target/release/stickslip.
"""
import argparse

import numpy as np

import fe_common as fc


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    ap.add_argument("run_dir")
    ap.add_argument("out_png")
    ap.add_argument("--step", type=int, help="contact step to plot (default: last written)")
    ap.add_argument("--load", type=float, help="normal load P (N/mm; default: from history.csv)")
    ap.add_argument("--bin", help="stickslip binary")
    args = ap.parse_args()

    binary = fc.find_bin(args.bin)
    d, path, step = fc.read_contact(args.run_dir, args.step)
    hist = fc.history_row(args.run_dir, step)
    load = args.load if args.load is not None else abs(hist["contact_fy"])
    h = fc.analytic_json(binary, "hertz", "--load", load)
    a, p0 = h["a"], h["p0"]

    x, p, vtx = d["x"], d["pressure"], d["vertex"]
    xi = x / a
    p_h = p0 * np.sqrt(np.clip(1.0 - xi**2, 0.0, None))
    err = np.abs(p - p_h) / p0
    inner = np.abs(xi) <= 0.95
    i_max = np.flatnonzero(inner)[np.argmax(err[inner])]
    in_contact = p > 0
    a_fe = hist["a"]
    le = fc.arc_edge_length(x, vtx, a)

    print(f"file                      : {path} (step {step})")
    print(f"load P                    : {load:.6g} N/mm")
    print(f"Hertz a, p0               : {a:.6f} mm, {p0:.6f} N/mm^2")
    print(f"FE a (history)            : {a_fe:.6f} mm  (a_FE/a_H = {a_fe / a:.5f})")
    print(f"FE contact extent         : x in [{x[in_contact].min() / a:+.4f}, "
          f"{x[in_contact].max() / a:+.4f}] a, {in_contact.sum()} nodes")
    print(f"arc edge length           : {le:.5f} mm = a/{a / le:.1f}")
    print(f"FE max p / p0             : {p.max() / p0:.5f}")
    print(f"max |p - p_H|/p0, |x|<=0.95a: {err[inner].max():.5f} at x/a = {xi[i_max]:+.4f} "
          f"({'vertex' if vtx[i_max] else 'mid-edge'} node)")
    print(f"  vertex nodes only       : {err[inner & vtx].max():.5f}")
    print(f"  mid-edge nodes only     : {err[inner & ~vtx].max():.5f}")
    print(f"max |p - p_H|/p0, |x|<=0.8a : {err[np.abs(xi) <= 0.8].max():.5f}")
    asym = np.abs(np.interp(-x[inner], x, p) - p[inner]).max() / p0
    print(f"asymmetry max |p(x)-p(-x)|/p0: {asym:.2e}")

    plt = fc.style()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    xs = np.linspace(-1, 1, 801)
    ax.plot(xs, np.sqrt(1 - xs**2), "k-", lw=1.4, label=r"Hertz  $p_0\sqrt{1-x^2/a^2}$", zorder=1)
    ax.plot(xi[vtx], p[vtx] / p0, "o", ms=4.2, mfc="tab:green", mec="darkgreen", mew=0.6,
            label="FE, vertex nodes", zorder=3)
    ax.plot(xi[~vtx], p[~vtx] / p0, "s", ms=3.6, mfc="none", mec="tab:orange", mew=0.9,
            label="FE, mid-edge nodes", zorder=2)
    ax.axvspan(-1.3, -0.95, color="0.92", zorder=0, lw=0)
    ax.axvspan(0.95, 1.3, color="0.92", zorder=0, lw=0)
    ax.set_xlim(-1.25, 1.25)
    ax.set_ylim(-0.03, 1.12)
    ax.set_xlabel(r"$x/a$")
    ax.set_ylabel(r"$p(x)/p_0$")
    ax.set_title(rf"Normal contact, $P$ = {load:g} N/mm  ($a$ = {a:.4f} mm, $p_0$ = {p0:.3f} N/mm$^2$)",
                 fontsize=10)
    ax.text(0.02, 0.04, rf"max $|p-p_H|/p_0$ = {err[inner].max():.4f}  ($|x|\leq0.95a$)"
            "\n" rf"FE $a$/Hertz $a$ = {a_fe / a:.4f}",
            transform=ax.transAxes, fontsize=8.5, va="bottom")
    ax.legend(loc="upper right")
    fig.tight_layout()
    fig.savefig(args.out_png)
    print(f"wrote {args.out_png}")


if __name__ == "__main__":
    main()
