#!/usr/bin/env python3
"""The jump to sliding integrated in time: slip rate in (x, t), stick fronts, energy budget.

Usage:
    python3 post/event_figs.py RUNDIR [--case CASE.json] [--out PREFIX] [--event N]
                               [--zoom T0_US] [--vmin V]

RUNDIR is the output of a run whose force-controlled load passed Q_max and whose jump was
integrated in time (`"on_lost_equilibrium": {"dynamic": ...}`, e.g. cases/fig2_event.json),
written with `"output": {"every": 1, "energy": true}` so that every step has its contact table.
Writes PREFIX.png (default RUNDIR/event.png), one figure of eight panels; the left column spans
the whole event, the right column zooms on its end (from T0_US µs after the event's start; by
default the last 3 (t_end − t_K) of the event, t_K where the kinetic energy first reaches 1e-2
of its largest value):

  (a)  the slip rate |slip_rate| (mm/s, log colour scale, clipped below --vmin) in the (t, x)
       plane, x along the lower body's contact face; grey: open nodes (status 0). Overlaid:
       the ends of the stick zone c_left(t), c_right(t) (green) and of the zone where μ has
       not weakened to f_d, b_left(t), b_right(t) (cyan), all from history.csv.
  (b)  c_left, c_right, b_left, b_right against t.
  (b') the front speed |dc/dt| / c_s, c_s = sqrt(E / (2 (1 + ν)) / ρ) of the lower body
       (read from the case file; c_R and c_p, plane strain, drawn for reference). The b front
       is where the accumulated slip reaches the weakening distance: not a material front, it
       can outrun the waves where a whole region slips at once. The raw front positions are quantised to the node spacing h,
       so the raw difference |Δc/Δt| is 0 or h/Δt (grey dots). The smoothed speed is the
       crossing-time estimate: while a front moves monotonically, the speed between two
       successive node crossings is (node spacing) / (time between them), drawn as a
       horizontal bar over that interval. The front that meets its partner (the zone
       vanishes) is taken to reach the centre of the last zone. In the first part of the
       event the stick status of the (barely moving) slip zone may flicker back and forth
       (shaded: "status flicker"); no speed is computed there: it is not a front's motion.
  (c)  the energy budget from energy.csv, every term relative to its value at the event's
       start (the last quasi-static step): work of the pilot ΔW, elastic ΔU, kinetic ΔK,
       frictional dissipation ΔD, normal work ΔN, numerical dissipation ΔD_num of the
       generalised-α scheme, and the supply ΔW − ΔU against the sinks ΔD + ΔK + ΔN + ΔD_num;
       left column |Δ| on a log scale (with the imbalance), right column linear. The dots check
       ΔD independently: ∫ ½ (q_old + q_new) Δslip dx over the contact tables (trapezoid in x).

Inputs: RUNDIR/history.csv (t, kinetic, c_left, c_right, b_left, b_right, n_stick),
RUNDIR/contact_NNNN.csv (x, status, slip_rate, shear, slip_increment), RUNDIR/energy.csv,
RUNDIR/summary.json (the case path, `events`), and the case file (E, ν, density of the bodies).
Units: mm, s (t shown in µs), N/mm, N·mm/mm (per unit thickness, plane strain).
Prints the numbers the figure shows (duration, peak slip rate, front speeds, energy terms).
"""
import argparse
import json
import math
import os
import sys
import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402

US = 1e6  # s -> µs for the time axes


def read_csv(path):
    """A CSV with a header row as a dict of float arrays (NaN kept)."""
    with open(path) as f:
        names = f.readline().strip().split(",")
    data = np.genfromtxt(path, delimiter=",", skip_header=1, dtype=float)
    data = np.atleast_2d(data)
    return {n: data[:, i] for i, n in enumerate(names)}


def event_rows(h, which):
    """Indices (i0, rows) of event `which`: i0 the last quasi-static row before it, rows the
    contiguous rows integrated in time (kinetic > 0 or t increasing)."""
    t, kin = h["t"], h["kinetic"]
    dyn = (kin > 0) | np.r_[False, np.diff(t) > 0]
    starts = [i for i in range(len(dyn)) if dyn[i] and (i == 0 or not dyn[i - 1])]
    if not starts:
        sys.exit("no steps integrated in time in history.csv")
    if which >= len(starts):
        sys.exit(f"event {which} asked for, history.csv has {len(starts)}")
    s = starts[which]
    e = s
    while e + 1 < len(dyn) and dyn[e + 1]:
        e += 1
    return max(s - 1, 0), np.arange(s, e + 1)


def shear_wave_speed(case_path):
    """c_s, c_p (plane strain), c_R (mm/s) of the lower body, and c_s of every body."""
    with open(case_path) as f:
        case = json.load(f)
    speeds = []
    for b in case["bodies"]:
        g = b["E"] / (2.0 * (1.0 + b["nu"]))
        speeds.append((b.get("group", "?"), math.sqrt(g / b["density"])))
    lower = [b for b in case["bodies"] if b.get("group") == "lower_body"] or case["bodies"][:1]
    nu = lower[0]["nu"]
    cs = math.sqrt(lower[0]["E"] / (2.0 * (1.0 + nu)) / lower[0]["density"])
    cp = cs * math.sqrt(2.0 * (1.0 - nu) / (1.0 - 2.0 * nu))  # plane strain
    cr = cs * (0.862 + 1.14 * nu) / (1.0 + nu)  # Rayleigh (Viktorov's approximation)
    return cs, cp, cr, speeds


def flicker_end(pos_left, pos_right, n_stick, k0):
    """First row index (relative to the event rows) from which the stick zone stays inside
    the one at the event's start: before it, the status flickers. pos_* are arrays over
    [start row, event rows...] (index 0 is the quasi-static start)."""
    tol = 1e-9
    out = (n_stick[1:] > n_stick[0]) | (pos_right[1:] > pos_right[0] + tol) | (
        pos_left[1:] < pos_left[0] - tol
    )
    idx = np.nonzero(out)[0]
    return 1 if len(idx) == 0 else idx[-1] + 2


def crossings(t, left, right, k_from):
    """Crossing-time speeds of the two fronts from row k_from on (rows where both are
    defined, the envelope of the inward motion). Returns per front a list of
    (t_a, t_b, speed) and the monotone envelope arrays."""
    res = {}
    n = len(t)
    env_l = np.full(n, np.nan)
    env_r = np.full(n, np.nan)
    cur_l, cur_r = left[k_from], right[k_from]
    vanish = None
    for k in range(k_from, n):
        if np.isnan(left[k]) or np.isnan(right[k]):
            vanish = k
            centre = 0.5 * (cur_l + cur_r)
            env_l[k] = env_r[k] = centre
            break
        cur_l = max(cur_l, left[k])
        cur_r = min(cur_r, right[k])
        env_l[k], env_r[k] = cur_l, cur_r
    for name, env in (("left", env_l), ("right", env_r)):
        changes = [
            k
            for k in range(k_from + 1, n)
            if not np.isnan(env[k]) and env[k] != env[k - 1]
        ]
        segs = []
        for a, b in zip(changes[:-1], changes[1:]):
            segs.append((t[a], t[b], abs(env[b] - env[a]) / (t[b] - t[a])))
        res[name] = segs
    return res, env_l, env_r, vanish


def load_contact(rundir, steps):
    """x (from the first table), status, slip_rate, shear, slip_increment per step (rows of
    NaN where a table is missing)."""
    xs = st = sr = q = ds = None
    missing = []
    for i, s in enumerate(steps):
        p = os.path.join(rundir, f"contact_{int(s):04d}.csv")
        if not os.path.exists(p):
            missing.append(int(s))
            continue
        c = read_csv(p)
        if xs is None:
            m = len(c["x"])
            st, sr, q, ds = (np.full((len(steps), m), np.nan) for _ in range(4))
            xs = c["x"]
        st[i], sr[i], q[i], ds[i] = c["status"], c["slip_rate"], c["shear"], c["slip_increment"]
    if xs is None:
        sys.exit("no contact_NNNN.csv for the event's steps: run with \"output\": {\"every\": 1}")
    return xs, st, sr, q, ds, missing


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("rundir", help="output directory of the run")
    ap.add_argument("--case", help="case file (default: summary.json's `case`)")
    ap.add_argument("--out", help="PNG path prefix (default RUNDIR/event)")
    ap.add_argument("--event", type=int, default=0, help="which event of the run (0: first)")
    ap.add_argument("--zoom", type=float, help="start of the right column's window, µs after "
                    "the event's start (default: the last 3 (t_end - t_K), t_K where the "
                    "kinetic energy first reaches 1e-2 of its peak)")
    ap.add_argument("--vmin", type=float, default=1e-8, help="lowest slip rate coloured, mm/s")
    ap.add_argument("--dpi", type=int, default=85)
    args = ap.parse_args()

    rd = args.rundir
    with open(os.path.join(rd, "summary.json")) as f:
        summary = json.load(f)
    case_path = args.case or summary.get("case")
    if not case_path or not os.path.exists(case_path):
        sys.exit(f"case file {case_path!r} not found: pass --case")
    c_s, c_p, c_r, all_cs = shear_wave_speed(case_path)

    h = read_csv(os.path.join(rd, "history.csv"))
    i0, rows = event_rows(h, args.event)
    k = np.r_[i0, rows]  # the start (quasi-static) and the event's rows
    steps = h["step"][k].astype(int)
    t = h["t"][k] - h["t"][i0]
    tu = t * US
    # The smallest step: the stage's dt, which takes every change of the contact's state.
    dt = np.diff(t[1:]).min() if len(t) > 2 else t[-1]

    ev = (summary.get("events") or [{}])
    ev = ev[args.event] if args.event < len(ev) else {}

    # ---- contact tables (event rows only; the start's table may not be written) ----
    x, st, sr, q, ds, missing = load_contact(rd, steps[1:])
    incontact = st > 0
    rate = np.where(incontact, np.abs(sr), np.nan)
    neg = np.where(incontact & (sr < 0), -sr, 0.0)
    spacing = np.median(np.diff(x))

    cl, cr = h["c_left"][k], h["c_right"][k]
    bl, br = h["b_left"][k], h["b_right"][k]
    nst = h["n_stick"][k]
    f_end = flicker_end(cl, cr, nst, 0)  # row in k (0 = start)
    c_segs, c_envl, c_envr, c_van = crossings(t, cl, cr, f_end)
    b_segs, _, _, b_van = crossings(t, bl, br, 0)

    # ---- energy ----
    e = read_csv(os.path.join(rd, "energy.csv"))
    estep = e["step"].astype(int)
    pos = {s: i for i, s in enumerate(estep)}
    if any(s not in pos for s in steps):
        sys.exit("energy.csv lacks some of the event's steps: run with output.energy = true")
    ek = np.array([pos[s] for s in steps])
    d = {n: e[n][ek] - e[n][ek[0]] for n in
         ("work_pilot", "work_tractions", "work_supports", "elastic", "kinetic",
          "dissipation", "normal_work", "numerical", "residual")}
    work = d["work_pilot"] + d["work_tractions"] + d["work_supports"]
    supply = work - d["elastic"]
    sinks = d["dissipation"] + d["kinetic"] + d["normal_work"] + d["numerical"]
    imbalance = supply - sinks
    # independent check of ΔD from the contact tables
    dcheck = np.zeros(len(steps))
    qprev = None
    for i in range(len(steps) - 1):
        qi = q[i]
        if np.isnan(qi).any():
            dcheck[i + 1] = dcheck[i]
            continue
        qa = qi if qprev is None else 0.5 * (qi + qprev)
        dcheck[i + 1] = dcheck[i] + np.trapezoid(qa * ds[i], x)
        qprev = qi

    # ---- zoom window ----
    kin = d["kinetic"]
    if args.zoom is not None:
        tz = args.zoom
    else:
        kz = np.argmax(kin >= 1e-2 * kin.max())
        tz = tu[-1] - 3.0 * (tu[-1] - tu[kz])
    tz = min(tz, tu[-1] * 0.98)
    z = tu >= tz

    # ---- numbers ----
    peak = np.nanmax(rate)
    kp = np.unravel_index(np.nanargmax(rate), rate.shape)
    allsegs = [(n, s) for n in ("left", "right") for s in c_segs[n]]
    vmax_c = max((s[2] for _, s in allsegs), default=float("nan"))
    ball = [(n, s) for n in ("left", "right") for s in b_segs[n]]
    vmax_b = max((s[2] for _, s in ball), default=float("nan"))
    print(f"case {case_path}; c_s = {c_s:.4g} mm/s ({c_s / 1e3:.1f} m/s), "
          f"c_p/c_s = {c_p / c_s:.3f}, c_R/c_s = {c_r / c_s:.3f}"
          + ("" if len(all_cs) < 2 else "; bodies: " + ", ".join(f"{g} {v:.4g}" for g, v in all_cs)))
    print(f"event {args.event}: steps {steps[1]}..{steps[-1]} ({len(steps) - 1}), dt = {dt:.4g} s, "
          f"duration {t[-1]:.4g} s; start = step {steps[0]}; summary end: {ev.get('end')}")
    if missing:
        print(f"contact tables missing for steps {missing}")
    print(f"pilot fx over the event {h['pilot_fx'][k[1:]].min():.9f}..{h['pilot_fx'][k[1:]].max():.9f}"
          f" (last quasi-static {h['pilot_fx'][i0]:.9f}); summary q_max "
          f"{summary.get('friction', {}).get('q_max')}")
    print(f"node spacing {spacing:.5f} mm; one node per step reads h/dt = {spacing / dt:.4g} mm/s"
          f" = {spacing / dt / c_s:.3f} c_s")
    print(f"status flicker until t = {tu[f_end]:.2f} µs (step {steps[f_end]}); stick zone "
          f"[{cl[0]:.4f}, {cr[0]:.4f}] mm at the start, b = [{bl[0]:.4f}, {br[0]:.4f}] mm")
    for name, segs in c_segs.items():
        for s in segs:
            print(f"  stick front {name}: {s[0] * US:8.2f}..{s[1] * US:8.2f} µs  "
                  f"{s[2]:.4g} mm/s = {s[2] / c_s:.4f} c_s")
    for name, segs in b_segs.items():
        for s in segs:
            print(f"  b front {name}: {s[0] * US:8.2f}..{s[1] * US:8.2f} µs  "
                  f"{s[2]:.4g} mm/s = {s[2] / c_s:.4f} c_s")
    if c_van is not None:
        print(f"stick zone vanishes at t = {tu[c_van]:.2f} µs (step {steps[c_van]})")
    if b_van is not None:
        print(f"all nodes at f_d from t = {tu[b_van]:.2f} µs (step {steps[b_van]})")
    print(f"peak slip rate {peak:.4g} mm/s at x = {x[kp[1]]:.4f} mm, t = {tu[kp[0] + 1]:.2f} µs "
          f"(step {steps[kp[0] + 1]}); largest backward slip rate {np.nanmax(neg):.3g} mm/s")
    print(f"peak front speed: stick {vmax_c:.4g} mm/s = {vmax_c / c_s:.4f} c_s; "
          f"b {vmax_b:.4g} mm/s = {vmax_b / c_s:.4f} c_s")
    print("energy over the event (N·mm/mm): " + ", ".join(
        f"Δ{n} = {d[n][-1]:.4e}" for n in ("work_pilot", "elastic", "kinetic", "dissipation",
                                           "normal_work", "numerical")))
    print(f"  peak kinetic {kin.max():.4e}; numerical/dissipation = "
          f"{d['numerical'][-1] / d['dissipation'][-1]:.3e}, numerical/kinetic = "
          f"{d['numerical'][-1] / kin[-1]:.3e}; min cumulative numerical {d['numerical'].min():.3e}; "
          f"max |imbalance| {np.abs(imbalance).max():.3e}")
    print(f"  ΔD from the contact tables {dcheck[-1]:.5e} vs energy.csv {d['dissipation'][-1]:.5e} "
          f"({dcheck[-1] / d['dissipation'][-1] - 1:+.2%})")
    print(f"zoom from {tz:.2f} µs")

    # ---- figure ----
    fig, axs = plt.subplots(4, 2, figsize=(13.5, 15.5), sharex="col",
                            gridspec_kw={"height_ratios": [1.35, 1, 1, 1.1]})
    title = "\n".join(textwrap.wrap(summary.get("title", ""), 120))
    fig.suptitle(
        f"Jump to sliding integrated in time: {os.path.basename(case_path)}, "
        f"{os.path.basename(summary.get('mesh', ''))}\n{title}\n"
        f"Δt = {dt:.3g} s, ρ∞ = {ev.get('rho_inf', '?')}, c_s = {c_s / 1e3:.0f} m/s;"
        f" right column: zoom from t = {tz:.1f} µs",
        fontsize=10.5)
    norm = LogNorm(vmin=args.vmin, vmax=peak)
    cmap = plt.get_cmap("inferno").copy()
    cmap.set_under(cmap(0.0))
    cmap.set_bad("0.8")
    T, Xg = np.meshgrid(tu[1:], x, indexing="ij")
    flick = (tu[0], tu[f_end]) if f_end > 1 else None

    for col, sel in ((0, np.ones_like(z)), (1, z)):
        ax = axs[0, col]
        rsel = sel[1:]
        im = ax.pcolormesh(T[rsel], Xg[rsel], np.ma.masked_invalid(rate[rsel]), norm=norm,
                           cmap=cmap, shading="nearest", rasterized=True)
        ms = 1.2 if col == 0 else 2.5
        for arr, colr, lab in ((cl, "#39ff14", "stick-zone ends c_left, c_right"),
                               (cr, "#39ff14", None),
                               (bl, "c", "b_left, b_right (μ > f_d inside)"), (br, "c", None)):
            ax.plot(tu[sel], arr[sel], ".", color=colr, ms=ms, mew=0, label=lab)
        ax.set_ylabel("x along the contact (mm)")
        ax.set_ylim(x.min() - spacing, x.max() + spacing)
        leg = ax.legend(loc="upper left", fontsize=8, framealpha=0.6, markerscale=5)
        leg.get_frame().set_facecolor("0.3")
        for tx in leg.get_texts():
            tx.set_color("w")
        cb = fig.colorbar(im, ax=ax, pad=0.01, extend="min")
        cb.set_label("|slip rate| (mm/s)")
        ax.set_title(("(a) " if col == 0 else "(a') ") + "slip rate in (t, x)"
                     + ("" if col == 0 else " — zoom"), fontsize=10, loc="left")

        ax = axs[1, col]
        ax.step(tu[sel], cr[sel], where="post", color="C3", lw=1.2, label="c_right")
        ax.step(tu[sel], cl[sel], where="post", color="C0", lw=1.2, label="c_left")
        ax.step(tu[sel], br[sel], where="post", color="C3", lw=1, ls="--", label="b_right")
        ax.step(tu[sel], bl[sel], where="post", color="C0", lw=1, ls="--", label="b_left")
        ax.plot(tu[sel], c_envr[sel], color="k", lw=0.6, ls=":",
                label="inward envelope of c (after the flicker)")
        ax.plot(tu[sel], c_envl[sel], color="k", lw=0.6, ls=":")
        ax.axhline(0, color="0.6", lw=0.5)
        ax.set_ylabel("front position x (mm)")
        ax.set_title(("(b) " if col == 0 else "(b') ") + "stick-zone ends c and b (history.csv)",
                     fontsize=10, loc="left")
        ax.legend(loc="upper right" if col == 0 else "lower left", fontsize=8, ncol=2)
        if col == 1:
            ax.set_ylim(-0.17, 0.17)

        ax = axs[2, col]
        for arr, colr in ((cl, "C0"), (cr, "C3")):
            raw = np.abs(np.diff(arr)) / np.diff(t)
            tt = tu[1:]
            ok = (raw > 0) & np.isfinite(raw) & (np.arange(1, len(t)) >= f_end) & sel[1:]
            ax.plot(tt[ok], raw[ok] / c_s, ".", color="0.6", ms=4, mew=0)
        ax.plot([], [], ".", color="0.6", ms=6, label="raw |Δc/Δt| (one node per step)")
        for segs, lab, ls, mk in ((c_segs, "stick front c", "-", "o"),
                                  (b_segs, "front b (μ = f_d)", "--", "s")):
            for name, cc, lw, al in (("left", "C0", 4.0, 0.45), ("right", "C3", 1.4, 1.0)):
                first = True
                for a, b, v in segs[name]:
                    ax.plot([a * US, b * US], [v / c_s] * 2, color=cc, lw=lw, ls=ls, alpha=al,
                            label=f"{lab}, {name}" if first else None)
                    ax.plot([0.5 * (a + b) * US], [v / c_s], mk, color=cc, alpha=al,
                            ms=6 if name == "left" else 3.5, mfc=cc if mk == "o" else "w")
                    first = False
        for v, lab, va in ((c_r, "c_R", "top"), (c_s, "c_s", "bottom"), (c_p, "c_p", "bottom")):
            ax.axhline(v / c_s, color="k", lw=0.6, ls="-." if lab == "c_s" else ":")
            ax.text(1.0, v / c_s, " " + lab, va=va, ha="left", fontsize=8,
                    transform=ax.get_yaxis_transform())
        ax.set_yscale("log")
        ax.set_ylim(3e-4, 4)
        ax.set_ylabel("front speed |dc/dt| / c_s")
        ax.set_title(("(b'') " if col == 0 else "(b''') ")
                     + "front speed: bars = node spacing / time between crossings",
                     fontsize=10, loc="left")
        if col == 0:
            ax.legend(loc="lower left", fontsize=7.5, ncol=1, bbox_to_anchor=(0.13, 0.0))

    # energy: left log |Δ| over the event, right linear over the zoom
    terms = (("work_pilot", "ΔW pilot", "C0", "-"), ("elastic", "ΔU elastic", "C1", "-"),
             ("kinetic", "ΔK kinetic", "C2", "-"), ("dissipation", "ΔD friction", "C3", "-"),
             ("normal_work", "ΔN normal work", "C4", "-"), ("numerical", "ΔD_num numerical", "C5", "-"))
    ax = axs[3, 0]
    for n, lab, colr, ls in terms:
        v = d[n]
        ax.plot(tu, np.where(v > 0, v, np.nan), color=colr, lw=1.2, label=f"|{lab}|")
        ax.plot(tu, np.where(v < 0, -v, np.nan), color=colr, lw=1.0, ls=(0, (2, 1.5)))
    ax.plot(tu, np.where(np.abs(imbalance) > 0, np.abs(imbalance), np.nan), color="k", lw=0.8,
            ls=":", label="|supply − sinks|")
    ax.set_yscale("log")
    ax.set_ylim(1e-15, 1e-2)
    ax.set_ylabel("|energy change| (N·mm/mm)")
    ax.set_title("(c) energy budget from the event's start, |Δ| (solid > 0, dashed < 0)",
                 fontsize=10, loc="left")
    ax.legend(loc="upper left", fontsize=7.5, ncol=2, bbox_to_anchor=(0.12, 1.0))
    ax = axs[3, 1]
    for n, lab, colr, ls in terms:
        ax.plot(tu[z], d[n][z], color=colr, ls=ls, lw=1.4, label=lab)
    ax.plot(tu[z], supply[z], color="k", lw=3, alpha=0.3, label="supply ΔW − ΔU")
    ax.plot(tu[z], sinks[z], color="k", lw=0.9, ls="--", label="sinks ΔD + ΔK + ΔN + ΔD_num")
    stride = max(1, z.sum() // 25)
    zi = np.nonzero(z)[0][::stride]
    ax.plot(tu[zi], dcheck[zi], "o", color="C3", ms=3.5, mfc="none",
            label="ΔD = ∫ q Δslip dx (contact_*.csv)")
    ax.axhline(0, color="0.6", lw=0.5)
    ax.set_ylabel("energy change (N·mm/mm)")
    ax.set_title("(c') energy budget from the event's start — zoom", fontsize=10, loc="left")
    ax.legend(loc="lower left", fontsize=7.5, ncol=2)

    ax = axs[0, 1]
    ax.plot([tu[kp[0] + 1]], [x[kp[1]]], "x", color="b", ms=8, mew=1.5)
    ax.annotate(f"peak {peak:.3g} mm/s", (tu[kp[0] + 1], x[kp[1]]), xytext=(8, -22),
                textcoords="offset points", color="b", fontsize=8,
                bbox=dict(boxstyle="round,pad=0.2", fc="w", ec="none", alpha=0.7))
    marks = [(c_van, "stick zone gone"), (b_van, "all at f_d")]
    for r in range(1, 4):
        for kv, lab in marks:
            if kv is not None:
                axs[r, 1].axvline(tu[kv], color="0.4", lw=0.7, ls=":")
    for i, (kv, lab) in enumerate(marks):
        if kv is not None:
            axs[1, 1].text(tu[kv], 0.98 - 0.08 * i, " " + lab, fontsize=7.5, color="0.3",
                           va="top", transform=axs[1, 1].get_xaxis_transform())
    for col in (0, 1):
        axs[3, col].set_xlabel("t after the event's start (µs)")
    if flick is not None:
        for r in range(1, 4):
            axs[r, 0].axvspan(*flick, color="0.85", zorder=0)
        axs[1, 0].text(0.5 * (flick[0] + flick[1]), 0.5, "status\nflicker", ha="center",
                       va="center", fontsize=8, color="0.25",
                       transform=axs[1, 0].get_xaxis_transform())
    axs[0, 0].set_xlim(tu[0], tu[-1])
    axs[0, 1].set_xlim(tz, tu[-1])
    fig.tight_layout(rect=(0, 0, 1, 0.955))
    prefix = args.out or os.path.join(rd, "event")
    path = prefix if prefix.endswith(".png") else prefix + ".png"
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.savefig(path, dpi=args.dpi)
    print(f"wrote {path} ({os.path.getsize(path) / 1024:.0f} KB)")


if __name__ == "__main__":
    main()
