#!/usr/bin/env python3
"""Rupture fronts on a planar interface: slip rate in (t, x), front speed against length, and
the energy release rate at the fronts against the fracture energy.

Usage:
    python3 post/rupture_figs.py RUNDIR [--out PNG] [--forced V X_END] [--window K]

RUNDIR is the output of `stickslip run cases/rupture_pmma.json --out RUNDIR` (or of any run
whose dynamic stage has fronts of weakening). Writes PNG (default RUNDIR/rupture.png), three
panels:

  (a)  the slip rate |slip_rate| (mm/s, log colour scale) in the (t, x) plane from the contact
       tables the run wrote, with the fronts front_left(t), front_right(t) of history.csv
       (every time step) drawn over it.
  (b)  the speed v/c_R of each front (least-squares slope of |front| over 2K + 1 steps)
       against its distance ℓ from the centre, with Freund's equation of motion of a
       semi-infinite crack, v = c_R (1 − Γ / G_static(ℓ)), and the curve
       G_static(ℓ) sqrt(1 − v/c_R) = Γ, where G_static = π (1 − ν)(τ0 − f_d p)² ℓ / (2μ);
       τ0 is the shear the pilot and the side tractions put on the interface (pilot_fx over
       the interface length at the end of the last quasi-static stage) and p = Γ/(W/p).
  (c)  G/Γ (the dynamic J-integral over the fracture energy of the front's process zone, both
       from history.csv), averaged over the same 2K + 1 steps, against v/c_R, for the samples
       of a front running on its own (more than 4 mm ahead of the forced patch given by
       --forced V X_END: speed in mm/s and half-length in mm; default 67000 40, the shipped
       case's) and within the fine interface mesh, ℓ ≤ --fine (default 200 mm).

Inputs: RUNDIR/history.csv, RUNDIR/contact_NNNN.csv, RUNDIR/summary.json (the case path) and
the case file (E, ν, density of the first body; the friction law; the mesh's interface
length from the contact tables). Units: mm, s (t shown in µs), MPa, N/mm.
Prints the numbers the figure shows (fastest front, G/Γ per speed band).
"""
import argparse
import glob
import json
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402


def wave_speeds(e, nu, rho):
    """Plane-strain P, S and Rayleigh speeds (bisection on the Rayleigh function)."""
    mu = e / (2 * (1 + nu))
    lam = e * nu / ((1 + nu) * (1 - 2 * nu))
    cp, cs = math.sqrt((lam + 2 * mu) / rho), math.sqrt(mu / rho)

    def d(v):
        ad, a_s = math.sqrt(1 - v * v / cp**2), math.sqrt(1 - v * v / cs**2)
        return 4 * ad * a_s - (1 + a_s * a_s) ** 2

    lo, hi = 0.5 * cs, (1 - 1e-12) * cs
    for _ in range(200):
        m = 0.5 * (lo + hi)
        lo, hi = (m, hi) if d(m) > 0 else (lo, m)
    return cp, cs, 0.5 * (lo + hi)


def samples(t, ell, ratio, k):
    """(t, ℓ, v, mean G/Γ) over windows of 2k + 1 steps."""
    out = []
    for i in range(k, len(t) - k):
        w = slice(i - k, i + k + 1)
        v = np.polyfit(t[w], ell[w], 1)[0]
        out.append((t[i], ell[i], v, np.mean(ratio[w])))
    return np.array(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("rundir")
    ap.add_argument("--out")
    ap.add_argument("--forced", nargs=2, type=float, default=[67000.0, 40.0])
    ap.add_argument("--window", type=int, default=15)
    ap.add_argument("--fine", type=float, default=200.0)
    a = ap.parse_args()
    run = a.rundir
    summary = json.load(open(os.path.join(run, "summary.json")))
    case_path = summary["case"]
    case = json.load(open(case_path))
    body = case["bodies"][0]
    e, nu, rho = body["E"], body["nu"], body["density"]
    mu = e / (2 * (1 + nu))
    cp, cs, cr = wave_speeds(e, nu, rho)
    fr = summary["friction"]
    fd, w_p = fr["f_d"], fr["w_over_p"]

    h = np.genfromtxt(os.path.join(run, "history.csv"), delimiter=",", names=True)
    dyn = h[(h["t"] > 0) & np.isfinite(h["front_left"]) & np.isfinite(h["front_right"])]
    quasi = h[h["t"] == 0]
    t = dyn["t"]

    # Interface length and τ0 from the contact tables and the last quasi-static step.
    tables = sorted(glob.glob(os.path.join(run, "contact_*.csv")))
    first = np.genfromtxt(tables[0], delimiter=",", names=True)
    length = first["x"].max() - first["x"].min()
    tau0 = quasi["pilot_fx"][-1] / length

    fig, ax = plt.subplots(1, 3, figsize=(17, 5.2))
    # (a) slip rate in (t, x)
    steps = {int(s): tt for s, tt in zip(h["step"], h["t"])}
    cols, times = [], []
    for f in tables:
        st = int(os.path.basename(f)[8:12])
        if steps.get(st, 0.0) <= 0.0:
            continue
        c = np.genfromtxt(f, delimiter=",", names=True)
        o = np.argsort(c["x"])
        cols.append(np.abs(c["slip_rate"][o]))
        times.append(steps[st])
        xs = c["x"][o]
    if cols:
        z = np.array(cols).T
        z = np.where(z > 1e-2, z, np.nan)
        im = ax[0].pcolormesh(np.array(times) * 1e6, xs, z, norm=LogNorm(vmin=1e-1), shading="nearest", cmap="viridis")
        fig.colorbar(im, ax=ax[0], label="slip rate (mm/s)")
    ax[0].plot(t * 1e6, dyn["front_left"], "r-", lw=0.8)
    ax[0].plot(t * 1e6, dyn["front_right"], "r-", lw=0.8, label="fronts of weakening (every step)")
    ax[0].set_xlabel("t (µs)")
    ax[0].set_ylabel("x (mm)")
    ax[0].set_ylim(-1.3 * np.nanmax(np.abs(dyn["front_right"])), 1.3 * np.nanmax(np.abs(dyn["front_right"])))
    ax[0].set_title("(a) slip rate and fronts of weakening")
    ax[0].legend(loc="upper left", fontsize=8)

    # (b), (c)
    vf, xf = a.forced
    k = a.window
    allv = []
    for side, mark in (("right", "o"), ("left", "x")):
        ell = np.abs(dyn[f"front_{side}"])
        ratio = dyn[f"g_{side}"] / dyn[f"gamma_{side}"]
        s = samples(t, ell, ratio, k)
        own = (s[:, 1] - np.minimum(vf * s[:, 0], xf) > 4.0) & (s[:, 1] <= a.fine) & np.isfinite(s[:, 3])
        ax[1].plot(s[:, 1], s[:, 2] / cr, mark, ms=2, label=f"{side} front")
        ax[2].plot(s[own, 2] / cr, s[own, 3], mark, ms=2, label=f"{side} front, running on its own")
        allv.append(s[own])
    gam = np.nanmedian(dyn["gamma_right"])
    p = gam / w_p
    g_static = lambda ell: math.pi * (1 - nu) * (tau0 - fd * p) ** 2 * ell / (2 * mu)  # noqa: E731
    ells = np.linspace(1.0, np.nanmax(np.abs(dyn["front_right"])), 400)
    ratio_s = gam / np.array([g_static(l) for l in ells])
    ax[1].plot(ells, np.clip(1 - ratio_s, 0, None), "k-", label="Freund: G_static (1 − v/c_R) = Γ")
    ax[1].plot(ells, np.clip(1 - ratio_s**2, 0, None), "k--", label="G_static sqrt(1 − v/c_R) = Γ")
    ax[1].axhline(1.0, color="grey", lw=0.6)
    ax[1].axvline(a.fine, color="grey", ls=":", lw=0.8)
    ax[1].text(a.fine, 0.05, " end of the fine mesh", fontsize=8, color="grey")
    ax[1].set_xlabel("ℓ = |front| (mm)")
    ax[1].set_xlim(0, 1.1 * a.fine)
    ax[1].set_ylabel("v / c_R")
    ax[1].set_ylim(0, 1.1)
    ax[1].set_title(f"(b) front speed (c_R = {cr / 1e3:.0f} m/s, c_s = {cs / 1e3:.0f} m/s)")
    ax[1].legend(fontsize=8)
    ax[2].axhspan(0.95, 1.05, color="0.9")
    ax[2].axhline(1.0, color="k", lw=0.6)
    ax[2].set_xlabel("v / c_R")
    ax[2].set_ylabel("G / Γ (dynamic J-integral)")
    ax[2].set_ylim(0, 1.3)
    ax[2].set_xlim(0, 1)
    ax[2].set_title("(c) energy release rate at the fronts")
    ax[2].legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    out = a.out or os.path.join(run, "rupture.png")
    fig.savefig(out, dpi=110)

    s = np.vstack(allv)
    print(f"tau0 = {tau0:.4f} MPa, p at the fronts = {p:.4f} MPa, Gamma = {gam:.4e} N/mm")
    print(f"fastest front running on its own: {s[:, 2].max() / cr:.3f} c_R")
    for lo in np.arange(0.1, 1.0, 0.1):
        m = (s[:, 2] >= lo * cr) & (s[:, 2] < (lo + 0.1) * cr)
        if m.any():
            print(f"v/c_R {lo:.1f}-{lo + 0.1:.1f}: {m.sum():4d} samples, G/Gamma mean {s[m, 3].mean():.4f}, range [{s[m, 3].min():.4f}, {s[m, 3].max():.4f}]")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
