#!/usr/bin/env python3
"""The paper's Figs. 4, 5, 6 (onset of sliding) with finite-element points.

Usage:
    python3 post/fe_onset_figs.py OUTDIR [--bin PATH] [--level N] [--jobs J] [--reuse]

Writes the cases and sweep files into OUTDIR/runs, runs them with `stickslip run` /
`stickslip sweep`, and draws into OUTDIR:

  fe_fig4.png  Q_x/(f_d P) vs c/a, JKR curves for several Psi (dotted: unstable branch) with FE
               points from slip-controlled runs, through the peak and down the softening
               branch that force control cannot follow (ramp laws with Lambda = 0.04, the
               smallest round value whose s0 the finest mesh resolves) and the force-controlled
               Q_max; thin dashed: double C-M for the same laws.
  fe_fig5.png  Psi = 0.1, Lambda = 0.025 and 0.4: FE Q-c points against the double C-M and JKR
               curves.
  fe_fig6.png  f_s/f_d vs the apparent Q_max/(f_d P) for several chi (JKR curves, dashed where
               s0/c > 0.1; double C-M dotted) with FE points from force-controlled sweeps, and
               the step law with Delta = 1e-9 mm (chi -> 0) on three meshes.

and the tables (printed, and in OUTDIR/fe_onset_tables.md, OUTDIR/fe_onset_results.json):
Figs. 4/5 laws also with Lambda = 0.025 (force control), a mesh check (Psi = 0.1, Lambda = 0.04
on L3, L4, L5), and the step law with Delta = 1e-9 mm (Q_max -> f_d P as h -> 0).

Mesh: every law runs on the coarsest VM272 level >= --level (default 4) whose contact edges
satisfy h <= s0/2 (s0/a = 2 Lambda/pi at the centre, eq. (s0); h measured by a normal-load probe
run of each level): Lambda >= 0.031 on L5, >= 0.061 on L4, >= 0.121 on L3. If even L5 does not
resolve s0 the law runs on L5 and is marked unresolved (open markers in Fig. 6).
The step-law check (Delta = 1e-9 mm, f_s = 0.15, 0.3, 0.5, f_d = 0.1) always runs on L3, L4, L5.

Numbers: a = 0.6808 mm (Hertz, P = 10 N/mm) normalises c; f_d P = 1 N/mm.
--reuse skips a run whose case file is unchanged and whose output is complete (for re-drawing).
"""
import argparse
import concurrent.futures as cf
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, HERE)

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import analytic_figs as af  # noqa: E402  (run_csv, plot_styled: the closed-form figures' style)

A = 0.6808          # Hertz semi-width, mm (P = 10 N/mm, VM272)
P = 10.0            # normal load, N/mm
FD = 0.1            # dynamic coefficient of every law
FDP = FD * P        # f_d P = 1 N/mm
LEVELS = (3, 4, 5)

# ---- the laws ---------------------------------------------------------------------------------
FIG4_PSI = [0.01, 0.05, 0.1, 0.2, 0.5]          # FE points, all with Lambda = FIG4_LAMBDA
FIG4_LAMBDA = 0.04      # smallest round Lambda with s0 resolved on L5 (needs Lambda >= pi h/a)
SUPP_LAMBDA = 0.025     # the same Psi with Lambda = 0.025 (force control only; not resolved)
MESH_CHECK = (0.1, 0.04)  # (Psi, Lambda) run on L3, L4, L5 (force control)
FIG4_CURVES = [0.0, 0.01, 0.05, 0.1, 0.2, 0.5]  # closed-form JKR curves
FIG5_PSI = 0.1
FIG5_LAMBDAS = [0.025, 0.05, 0.1, 0.2, 0.4]     # table; the figure shows 0.025 and 0.4
FIG5_SHOWN = (0.025, 0.4)
FIG6_CHI = [0.02, 0.05, 0.1, 0.2]               # FE points
FIG6_RATIOS = [1.25, 1.5, 2.0, 2.5, 3.0]
FIG6_CURVES = [0.001, 0.01, 0.02, 0.05, 0.1, 0.2]
STEP_FS = [0.15, 0.3, 0.5]
FORCE_STEPS = 150       # force-controlled sweeps: load steps up to 1.3 x the largest JKR Q_max
STEP_DELTA = 1e-9


def law_key(r, lam):
    return f"r{r:.6g}_L{lam:.6g}"


def ramp(r, lam):
    return {"shape": "ramp", "fs": round(FD * r, 12), "fd": FD, "lambda": lam,
            "radius": 4.0, "load": P}


# ---- running ----------------------------------------------------------------------------------
class Runner:
    def __init__(self, binary, outdir, reuse, jobs):
        self.bin = binary
        self.runs = os.path.join(outdir, "runs")
        self.reuse = reuse
        self.jobs = jobs
        os.makedirs(self.runs, exist_ok=True)
        with open(os.path.join(REPO, "cases", "fig2.json")) as f:
            self.base = json.load(f)
        self.log = []   # (name, exit code, message)

    def case(self, level, stage, friction=None):
        c = json.loads(json.dumps(self.base))
        c["mesh"] = os.path.join(REPO, "meshes", f"vm272_L{level}.msh")
        c["output"] = {"vtu": False}
        if friction is not None:
            c["contact"]["friction"] = friction
        c["stages"] = [c["stages"][0]] + (stage if isinstance(stage, list) else [stage])
        return c

    def _write(self, path, obj):
        text = json.dumps(obj, indent=1)
        same = os.path.isfile(path) and open(path).read() == text
        if not same:
            with open(path, "w") as f:
                f.write(text)
        return same

    def run(self, name, case, threads):
        """`stickslip run`; returns (exit code, stderr, run dir)."""
        cpath = os.path.join(self.runs, name + ".json")
        out = os.path.join(self.runs, name)
        same = self._write(cpath, case)
        done = os.path.join(out, "exit_code")
        if self.reuse and same and os.path.isfile(done) and \
                os.path.isfile(os.path.join(out, "summary.json")):
            return int(open(done).read()), "(reused)", out
        if os.path.isdir(out):
            shutil.rmtree(out)
        res = subprocess.run([self.bin, "run", cpath, "--out", out, "--threads", str(threads),
                              "--quiet"], capture_output=True, text=True)
        os.makedirs(out, exist_ok=True)
        with open(done, "w") as f:
            f.write(str(res.returncode))
        with open(os.path.join(out, "stderr.txt"), "w") as f:
            f.write(res.stderr)
        return res.returncode, res.stderr.strip(), out

    def sweep(self, name, case, laws):
        cpath = os.path.join(self.runs, name + ".json")
        spath = os.path.join(self.runs, name + "_laws.json")
        out = os.path.join(self.runs, name)
        same = self._write(cpath, case) & self._write(spath, {"friction": laws})
        table = os.path.join(out, "sweep.json")
        if not (self.reuse and same and os.path.isfile(table)):
            if os.path.isdir(out):
                shutil.rmtree(out)
            res = subprocess.run([self.bin, "sweep", cpath, spath, "--out", out, "--quiet"],
                                 capture_output=True, text=True)
            self.log.append((name, res.returncode, res.stderr.strip()))
            if res.returncode != 0 or not os.path.isfile(table):
                sys.exit(f"sweep {name} failed (exit {res.returncode}):\n{res.stderr}")
        with open(table) as f:
            return json.load(f)


def read_history(run_dir):
    path = os.path.join(run_dir, "history.csv")
    if not os.path.isfile(path):
        return None
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]} if rows else None


def probe_levels(runner, levels):
    """h of the contact edges per level, from a normal-load-only run (Fig. 2's law)."""
    h = {}
    for L in levels:
        case = runner.case(L, [])
        code, err, out = runner.run(f"probe_L{L}", case, threads=2)
        if code != 0:
            sys.exit(f"probe run on L{L} failed (exit {code}): {err}")
        with open(os.path.join(out, "summary.json")) as f:
            h[L] = json.load(f)["friction"]["h_contact"]
    return h


def pick_level(lam, h, lmin):
    """Coarsest level >= lmin with h <= s0/2, where s0 = E* Delta / (pi (f_s - f_d) p0) at the
    centre, i.e. s0/a = 2 Lambda / pi (eq. s0 with p0 = E* a / 2R; the run summary's criterion);
    else the finest level (not resolved)."""
    s0 = 2.0 / math.pi * lam * A
    for L in sorted(h):
        if L >= lmin and h[L] <= 0.5 * s0:
            return L, True
    return max(h), False


def slip_run(runner, name, law, level, threads):
    """Slip-controlled run (`pilot_x: {"slip": ...}`) through the peak and down the softening
    branch. The mean slip when the stick zone vanishes scales with the Cattaneo-Mindlin slip
    f a^2/R (about 0.16 f_s a^2/R for Fig. 2's law): the run goes to 0.4 f_s a^2/R in 400
    steps (widened once if the peak was not passed)."""
    target = 0.4 * law["fs"] * A * A / 4.0
    for attempt in range(2):
        stage = {"name": "slip", "steps": 400, "pilot_x": {"slip": round(target, 9)}}
        code, err, out = runner.run(name, runner.case(level, stage, law), threads)
        h = read_history(out)
        if code != 0 or h is None or fe_curve(h)["passed"]:
            return code, err, out, h
        target *= 2.0
    return code, "peak not passed", out, h


# ---- closed forms -----------------------------------------------------------------------------
def analytic(binary, *args):
    res = subprocess.run([binary, "analytic", *map(str, args)], capture_output=True, text=True)
    if res.returncode != 0:
        sys.exit(f"stickslip analytic {' '.join(map(str, args))} failed:\n{res.stderr}")
    return json.loads(res.stdout)


def theory(binary, chi, r):
    """JKR and double C-M maxima for chi and r = f_s/f_d."""
    d = analytic(binary, "apparent", "--chi", chi, "--fs-over-fd", r)
    return {"q_jkr": d["q_max_jkr"], "c_jkr": d["c_max_jkr"], "q_dcm": d["q_max_dcm"],
            "c_dcm": d["c_max_dcm"], "b_dcm": d["b_max_dcm"], "s0_over_c": d["s0_over_c"],
            "small_scale_ok": d["small_scale_ok"], "dcm_truncated": d["dcm_max_truncated"]}


# ---- FE curve extraction ----------------------------------------------------------------------
def fe_curve(h):
    """Tangential-stage states (c/a, Q/f_dP) through the peak and down the softening branch,
    up to the last state with a stick zone before the contact re-sticks or slides as a whole
    (when the last stick nodes let go, the slip-controlled path is no longer unique: the
    interior may re-stick while the edges slip; those states are dropped). `i_peak` splits the
    stable and the softening branch."""
    tang = h["stage"] >= 1
    q = h["pilot_fx"][tang] / FDP
    c = h["c"][tang] / A
    b = h["b"][tang] / A
    ux = h["pilot_ux"][tang]
    end = len(q)
    for k in range(1, len(q)):
        if c[k] <= 0.0 or c[k] > c[k - 1] + 0.05:
            end = k
            break
    q, c, b, ux = q[:end], c[:end], b[:end], ux[:end]
    i = int(np.argmax(q))
    return {"c": c, "q": q, "b": b, "ux": ux, "i_peak": i, "q_peak": q[i], "c_peak": c[i],
            "b_peak": b[i], "d_peak": ux[i], "q_end": q[-1], "c_end": c[-1],
            "passed": i < len(q) - 1, "d_max": float(ux.max())}


def thin(c, q, dc=0.03):
    """Keep a point when c has moved by >= dc (in c/a) since the last kept one; keep the last."""
    keep = [0]
    for k in range(1, len(c)):
        if abs(c[k] - c[keep[-1]]) >= dc:
            keep.append(k)
    if keep[-1] != len(c) - 1:
        keep.append(len(c) - 1)
    return c[keep], q[keep]


def fe_points(ax, cu, color, dc, label=None):
    """FE (c/a, Q) points: open markers up to the peak, filled past it (softening branch)."""
    i = cu["i_peak"]
    cc, qq = thin(cu["c"][:i + 1], cu["q"][:i + 1], dc)
    ax.plot(cc, qq, "o", ms=4, mfc="none", mew=1.0, color=color, label=label)
    if i + 1 < len(cu["q"]):
        cc, qq = thin(cu["c"][i:], cu["q"][i:], dc / 3)
        ax.plot(cc[1:], qq[1:], "o", ms=4, mew=1.0, color=color)


def softening_gap(binary, d, cu):
    """Largest |Q_FE - Q_DCM(c_FE)| (units f_d P) over the FE points past the peak."""
    i = cu["i_peak"]
    if i + 1 >= len(cu["q"]):
        return None
    dc = af.run_csv(binary, "dcm-curve", "--lambda", d["lam"], "--fs-over-fd", d["r"],
                    "--n", 2001)
    ok = np.isfinite(dc["q_ratio"])
    qd = np.interp(cu["c"][i + 1:], dc["c_over_a"][ok], dc["q_ratio"][ok])
    return float(np.max(np.abs(cu["q"][i + 1:] - qd)))


def pct(x, ref):
    return 100.0 * (x / ref - 1.0)


# ---- figures ----------------------------------------------------------------------------------
def fig4(binary, out, d4):
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    colors = plt.cm.viridis(np.linspace(0, 0.9, len(FIG4_CURVES)))
    cmap = dict(zip(FIG4_CURVES, colors))
    for psi, col in cmap.items():
        d = af.run_csv(binary, "jkr-curve", "--psi", psi, "--n", 401)
        af.plot_styled(ax, d["c_over_a"], d["q_ratio"], d["stable"], col, rf"$\Psi$={psi:g}")
        if psi in FIG4_PSI:
            d = af.run_csv(binary, "dcm-curve", "--psi", psi, "--lambda", FIG4_LAMBDA, "--n", 401)
            ok = d["branch"] == "dcm"
            ax.plot(d["c_over_a"][ok], d["q_ratio"][ok], "--", color=col, lw=0.8)
    ax.plot([], [], "--", color="0.4", lw=0.8,
            label=rf"double C-M, $\Lambda$={FIG4_LAMBDA:g} (both branches, up to $b=a$)")
    for psi in FIG4_PSI:
        r = d4[psi]
        if r["curve"] is None:
            continue
        fe_points(ax, r["curve"], cmap[psi], dc=0.03)
        if r.get("q_force") is not None:
            ax.plot(r["c_force"], r["q_force"], "D", ms=4.5, color=cmap[psi], mec="k", mew=0.5)
    ax.plot([], [], "o", ms=4, mfc="none", color="0.3", label="FE, slip control: stable branch")
    ax.plot([], [], "o", ms=4, color="0.3", label="FE, slip control: past the peak")
    ax.plot([], [], "D", ms=4.5, color="0.6", mec="k", mew=0.5,
            label=r"FE $Q_{max}$, force control")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 2.0)
    ax.set_xlabel("$c/a$")
    ax.set_ylabel(r"$Q_x/f_dP$")
    ax.set_title(rf"Fig. 4: JKR limit with FE points (ramp laws, $\Lambda$={FIG4_LAMBDA:g}, "
                 rf"L{d4[FIG4_PSI[0]]['level']})" "\n"
                 "(dotted: unstable under force control)", fontsize=10)
    ax.legend(fontsize=7.5, loc="lower left", ncol=2)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fe_fig4.png"), dpi=150)
    plt.close(fig)


def fig5(binary, out, d5):
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    d = af.run_csv(binary, "jkr-curve", "--psi", FIG5_PSI, "--n", 401)
    af.plot_styled(ax, d["c_over_a"], d["q_ratio"], d["stable"], "k", "JKR")
    for lam, col in zip(FIG5_SHOWN, ("tab:blue", "tab:red")):
        d = af.run_csv(binary, "dcm-curve", "--psi", FIG5_PSI, "--lambda", lam, "--n", 401)
        solid = d["stable"] & (d["branch"] == "dcm")
        af.plot_styled(ax, d["c_over_a"], d["q_ratio"], solid, col,
                       rf"double C-M, $\Lambda$={lam:g}")
        r = d5[lam]
        if r["curve"] is not None:
            fe_points(ax, r["curve"], col, dc=0.025,
                      label=rf"FE, $\Lambda$={lam:g} ($f_s/f_d$={r['r']:g}, L{r['level']}"
                      + ("" if r["resolved"] else r", $h>s_0/2$") + ")")
        if r.get("q_force") is not None:
            ax.plot(r["c_force"], r["q_force"], "D", ms=5, color=col, mec="k", mew=0.5)
    ax.plot([], [], "o", ms=4, color="0.3", label="FE past the peak (slip control)")
    ax.plot([], [], "D", ms=5, color="0.6", mec="k", mew=0.5, label=r"FE $Q_{max}$, force control")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.45)
    ax.set_xlabel("$c/a$")
    ax.set_ylabel(r"$Q_x/f_dP$")
    ax.set_title(r"Fig. 5: double C-M vs JKR, $\Psi$=0.1, with FE points" "\n"
                 r"(dotted: unstable, or C-M with $f_s$ where $b>a$)", fontsize=10)
    ax.legend(fontsize=7.5, loc="lower left")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fe_fig5.png"), dpi=150)
    plt.close(fig)


def fig6(binary, out, d6, steps):
    fig, ax = plt.subplots(figsize=(6.4, 5.0))
    colors = plt.cm.plasma(np.linspace(0, 0.85, len(FIG6_CURVES)))
    cmap = dict(zip(FIG6_CURVES, colors))
    ax.axvline(1.0, color="k", lw=1.0, label=r"$\chi$=0 (C-M with $f_d$)")
    for chi, col in cmap.items():
        d = af.run_csv(binary, "apparent-curve", "--chi", chi, "--ratio-max", 3, "--n", 121,
                       "--dcm")
        af.plot_styled(ax, d["q_max_jkr"], d["fs_over_fd"], d["small_scale_ok"], col,
                       rf"$\chi$={chi:g}", other_style="--")
        ax.plot(d["q_max_dcm"][3::6], d["fs_over_fd"][3::6], "+", ms=4, mew=0.8, color=col)
    ax.plot([], [], "+", ms=4, mew=0.8, color="0.4", label="double C-M")
    for chi in FIG6_CHI:
        for res in (True, False):
            pts = [(r["q_fe"], r["r"]) for r in d6 if abs(r["chi"] - chi) < 1e-12
                   and r["q_fe"] is not None and bool(r["resolved"]) == res]
            if pts:
                x, y = zip(*pts)
                ax.plot(x, y, "o", ms=5.5, color=cmap[chi] if res else "w", mec=cmap[chi] if
                        not res else "k", mew=0.6 if res else 1.3, zorder=4)
    ax.plot([], [], "o", ms=5.5, color="0.6", mec="k", mew=0.6, label="FE, force control")
    ax.plot([], [], "o", ms=5.5, color="w", mec="0.4", mew=1.3, label=r"FE, $h>s_0/2$")
    marks = {3: "v", 4: "s", 5: "^"}
    for L in LEVELS:
        pts = [(s["q_fe"], s["r"]) for s in steps if s["level"] == L and s["r"] <= 3.0]
        if pts:
            x, y = zip(*pts)
            ax.plot(x, y, marks[L], ms=5, mfc="none", color="0.25", mew=1.0,
                    label=rf"FE step law, $\Delta$=1e-9 mm, L{L}")
    ax.plot([1, 3], [1, 3], color="0.7", lw=0.8, label=r"$Q_{max}/P=f_s$")
    ax.set_xlim(0.95, 1.8)
    ax.set_ylim(1, 3.05)
    ax.set_xlabel(r"$Q_{max}/f_dP$")
    ax.set_ylabel(r"$f_s/f_d$")
    ax.set_title("Fig. 6: apparent static friction with FE points\n"
                 r"(JKR; dashed: $s_0/c>0.1$ at the maximum)", fontsize=10)
    ax.legend(fontsize=7, loc="lower right", framealpha=0.95)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fe_fig6.png"), dpi=150)
    plt.close(fig)


# ---- tables -----------------------------------------------------------------------------------
def fmt(x, nd=4):
    return "—" if x is None else f"{x:.{nd}f}"


def fmtp(x):
    return "—" if x is None else f"{x:+.2f}"


def md_table(head, rows):
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(str(v) for v in r) + " |" for r in rows]
    return "\n".join(lines)


def law_item(psi=None, lam=None, chi=None, r=None, level=None, h=None, lmin=4, binary=None):
    """A ramp law from two of (Psi, Lambda, chi, r = f_s/f_d), with its mesh level."""
    if r is None:
        r = 1.0 + (math.sqrt(psi / lam) if psi is not None else chi / lam)
    if lam is None:
        lam = chi / (r - 1.0)
    d = {"r": r, "lam": lam, "chi": (r - 1.0) * lam, "psi": (r - 1.0) ** 2 * lam}
    if level is None:
        d["level"], d["resolved_pred"] = pick_level(lam, h, lmin)
    else:
        d["level"], d["resolved_pred"] = level, h[level] <= lam * A / math.pi
    d["theory"] = theory(binary, d["chi"], r)
    d["law"] = ramp(r, lam)
    d["resolved"] = None
    return d


def main():
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("outdir")
    p.add_argument("--bin", default=None, help="stickslip binary (default $STICKSLIP_BIN, "
                   "else target/release/stickslip)")
    p.add_argument("--level", type=int, default=4, choices=LEVELS,
                   help="coarsest mesh level to use (default 4); finer where s0 needs it")
    p.add_argument("--jobs", type=int, default=2, help="slip-controlled runs in parallel")
    p.add_argument("--reuse", action="store_true", help="keep unchanged, finished runs")
    a = p.parse_args()
    binary = a.bin or os.environ.get("STICKSLIP_BIN") or os.path.join(
        REPO, "target", "release", "stickslip")
    if not (os.path.isfile(binary) and os.access(binary, os.X_OK)):
        sys.exit(f"stickslip binary not found at {binary}: `cargo build --release` or --bin")
    binary = os.path.abspath(binary)
    os.makedirs(a.outdir, exist_ok=True)
    t0 = time.time()
    runner = Runner(binary, a.outdir, a.reuse, a.jobs)
    h = probe_levels(runner, LEVELS)
    print("contact edge size h per level: " +
          ", ".join(f"L{L} {h[L]:.5f} mm (a/{A / h[L]:.1f}; s0 resolved for "
                    f"Lambda >= {math.pi * h[L] / A:.3f})" for L in LEVELS))
    mk = dict(h=h, lmin=a.level, binary=binary)

    # ---- laws -----------------------------------------------------------------------------------
    d4 = {psi: law_item(psi=psi, lam=FIG4_LAMBDA, **mk) for psi in FIG4_PSI}
    d5 = {lam: law_item(psi=FIG5_PSI, lam=lam, **mk) for lam in FIG5_LAMBDAS}
    supp = {psi: law_item(psi=psi, lam=SUPP_LAMBDA, **mk) for psi in FIG4_PSI}
    mesh = {L: law_item(psi=MESH_CHECK[0], lam=MESH_CHECK[1], level=L, **{**mk, "lmin": L})
            for L in LEVELS}
    fig6_rows = [law_item(chi=chi, r=r, **mk) for chi in FIG6_CHI for r in FIG6_RATIOS]

    # ---- slip control (Figs. 4, 5), runs in parallel ------------------------------------------
    disp = {}
    for d in list(d4.values()) + list(d5.values()):
        disp.setdefault((law_key(d["r"], d["lam"]), d["level"]), d)

    def job(item):
        (k, L), d = item
        return item[0], slip_run(runner, f"slip_{k}_L{L}", d["law"], L,
                                 threads=1 if a.jobs > 1 else 2)

    with cf.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as ex:
        for key, (code, err, out, hist) in ex.map(job, list(disp.items())):
            res = dict(code=code, err=err, curve=fe_curve(hist) if hist is not None else None)
            runner.log.append((f"slip_{key[0]}_L{key[1]}", code, err))
            sp = os.path.join(out, "summary.json")
            if os.path.isfile(sp):
                res["resolved"] = json.load(open(sp))["friction"]["resolved"]
            for d in list(d4.values()) + list(d5.values()):
                if (law_key(d["r"], d["lam"]), d["level"]) == key:
                    d.update(res)
    print(f"slip-controlled runs done ({time.time() - t0:.0f} s)")

    # ---- force control: one sweep per level -----------------------------------------------------
    force_items = (list(d4.values()) + list(d5.values()) + list(supp.values()) +
                   list(mesh.values()) + fig6_rows)
    by_level = {}
    for d in force_items:
        by_level.setdefault(d["level"], []).append(d)
    for L, items in sorted(by_level.items()):
        qtop = max(d["theory"]["q_jkr"] for d in items)
        case = runner.case(L, {"name": "tangential", "steps": FORCE_STEPS,
                               "pilot_x": {"force": round(1.3 * qtop * FDP, 3)}})
        laws, seen = [], {}
        for d in items:
            key = json.dumps(d["law"], sort_keys=True)
            if key not in seen:
                seen[key] = len(laws)
                laws.append(d["law"])
            d["sweep_index"] = seen[key]
        res = runner.sweep(f"sweep_L{L}", case, laws)
        rows = sorted(res["rows"], key=lambda r: r["index"])
        for d in items:
            row = rows[d["sweep_index"]]
            f = row["friction"]
            lost = row["status"].startswith("equilibrium lost")
            d["q_force"] = f["q_max"] / FDP if lost else None
            d["c_force"] = row["c"] / A
            d["q_fe"] = d["q_force"]
            d["status"] = row["status"]
            d["resolved"] = f["resolved"] if d.get("resolved") is None else d["resolved"]
            if not lost:
                runner.log.append((f"sweep_L{L} law {d['sweep_index']}", "-", row["status"]))
        print(f"sweep on L{L}: {len(laws)} laws, {res['sweep_s']:.1f} s "
              f"({time.time() - t0:.0f} s so far)")

    # ---- step law, Delta -> 0 ---------------------------------------------------------------
    steps = []
    step_laws = [{"shape": "step", "fs": fs, "fd": FD, "delta": STEP_DELTA} for fs in STEP_FS]
    for L in LEVELS:
        case = runner.case(L, {"name": "tangential", "steps": 40, "pilot_x": {"force": 2.0}})
        res = runner.sweep(f"step_L{L}", case, step_laws)
        for row in sorted(res["rows"], key=lambda r: r["index"]):
            f = row["friction"]
            lost = row["status"].startswith("equilibrium lost")
            steps.append({"level": L, "fs": f["f_s"], "r": f["f_s"] / FD, "h": h[L],
                          "q_fe": f["q_max"] / FDP if lost else None, "status": row["status"],
                          "c_force": row["c"] / A, "q_jkr": f["apparent_friction_jkr"] / FD})
        print(f"step-law sweep on L{L}: {res['sweep_s']:.1f} s ({time.time() - t0:.0f} s so far)")

    # ---- figures ------------------------------------------------------------------------------
    fig4(binary, a.outdir, d4)
    fig5(binary, a.outdir, d5)
    fig6(binary, a.outdir, fig6_rows, steps)

    # ---- tables -------------------------------------------------------------------------------
    head = ["Ψ", "f_s/f_d", "Λ", "χ", "mesh", "h/s0", "Q_max FE force", "Q_max FE slip",
            "JKR", "DCM", "FE−JKR %", "FE−DCM %", "c/a FE slip peak", "c/a FE lowest",
            "max ΔQ to DCM(c) past the peak", "c_max/a JKR",
            "c_max/a DCM"]

    def h_s0(d):
        return h[d["level"]] / (2.0 / math.pi * d["lam"] * A)

    def law_rows(items, with_disp=True):
        rows = []
        for d in items:
            t, cu = d["theory"], d.get("curve") if with_disp else None
            qf = d.get("q_force")
            rows.append([f"{d['psi']:g}", f"{d['r']:.3f}", f"{d['lam']:g}", f"{d['chi']:.4f}",
                         f"L{d['level']}", f"{h_s0(d):.2f}" + ("" if d["resolved"] else " ✗"),
                         fmt(qf), fmt(cu["q_peak"]) if cu else "—",
                         fmt(t["q_jkr"]), fmt(t["q_dcm"]),
                         fmtp(pct(qf, t["q_jkr"]) if qf else None),
                         fmtp(pct(qf, t["q_dcm"]) if qf else None),
                         fmt(cu["c_peak"], 3) if cu else "—",
                         fmt(cu["c_end"], 3) if cu else "—",
                         fmt(softening_gap(binary, d, cu), 4) if cu else "—",
                         fmt(t["c_jkr"], 3),
                         fmt(t["c_dcm"], 3)])
        return rows

    t4 = md_table(head, law_rows([d4[x] for x in FIG4_PSI]))
    t4s = md_table(head, law_rows([supp[x] for x in FIG4_PSI], with_disp=False))
    t5 = md_table(head, law_rows([d5[x] for x in FIG5_LAMBDAS]))
    tm = md_table(head, law_rows([mesh[L] for L in LEVELS], with_disp=False))
    head6 = ["χ", "f_s/f_d", "Λ", "mesh", "h/s0", "s0/c at JKR max", "Q_max FE", "JKR", "DCM",
             "FE−JKR %", "FE−DCM %", "c/a FE (last)", "c_max/a DCM"]
    rows6 = []
    for d in fig6_rows:
        t = d["theory"]
        q = d["q_fe"]
        rows6.append([f"{d['chi']:g}", f"{d['r']:g}", f"{d['lam']:.4g}", f"L{d['level']}",
                      f"{h_s0(d):.2f}" + ("" if d["resolved"] else " ✗"),
                      f"{t['s0_over_c']:.3f}", fmt(q),
                      fmt(t["q_jkr"]), fmt(t["q_dcm"]), fmtp(pct(q, t["q_jkr"]) if q else None),
                      fmtp(pct(q, t["q_dcm"]) if q else None), fmt(d["c_force"], 3),
                      fmt(t["c_dcm"], 3)])
    t6 = md_table(head6, rows6)
    heads = ["f_s", "f_s/f_d", "mesh", "h/a", "Q_max/(f_d P) FE", "excess (Q_max − f_d P)/f_d P",
             "closed form (Δ = 1e-9)"]
    rowss = [[f"{s['fs']:g}", f"{s['r']:g}", f"L{s['level']}", f"{s['h'] / A:.4f}",
              fmt(s["q_fe"]), fmt(s["q_fe"] - 1.0 if s["q_fe"] else None),
              fmt(s["q_jkr"], 5)] for s in steps]
    order_lines = []
    for fs in STEP_FS:
        ex = {s["level"]: s["q_fe"] - 1.0 for s in steps if s["fs"] == fs and s["q_fe"]}
        if all(L in ex for L in LEVELS):
            p1 = math.log(ex[3] / ex[4]) / math.log(h[3] / h[4])
            p2 = math.log(ex[4] / ex[5]) / math.log(h[4] / h[5])
            order_lines.append(f"f_s = {fs:g}: excess ∝ h^p with p = {p1:.2f} (L3→L4), "
                               f"{p2:.2f} (L4→L5)")
    ts = md_table(heads, rowss)
    legend = ("Q_max in units of f_d P. 'FE force': force control past the peak (bisection "
              "bracket, 12 halvings); 'FE slip': largest sampled Q under slip control, which "
              "continues past the peak down to 'c/a FE lowest'; the gap to the double C-M "
              "curve Q(c) of the same law is measured there, in f_d P; "
              "deviations use the force-controlled value. h/s0 with s0 = 2Λa/π at the centre; "
              "✗ = h > s0/2 (not resolved).")
    out_md = [legend, "",
              f"### Fig. 4: Ψ series (ramp laws, Λ = {FIG4_LAMBDA:g})", "", t4, "",
              f"### Fig. 4 laws with Λ = {SUPP_LAMBDA:g} (force control)", "", t4s, "",
              f"### Mesh check: Ψ = {MESH_CHECK[0]:g}, Λ = {MESH_CHECK[1]:g} on L3, L4, L5",
              "", tm, "",
              f"### Fig. 5: Ψ = {FIG5_PSI:g}, Λ series", "", t5, "",
              "### Fig. 6: χ series (force control)", "", t6, "",
              f"### Step law, Δ = {STEP_DELTA:g} mm (χ → 0), f_d = {FD:g}", "", ts, ""] + \
             ["* " + s for s in order_lines]
    text = "\n".join(out_md)
    print()
    print(text)
    with open(os.path.join(a.outdir, "fe_onset_tables.md"), "w") as f:
        f.write(text + "\n")

    def clean(d):
        return {str(k): (v.tolist() if isinstance(v, np.ndarray) else
                         (clean(v) if isinstance(v, dict) else v)) for k, v in d.items()}
    with open(os.path.join(a.outdir, "fe_onset_results.json"), "w") as f:
        json.dump({"h": h, "fig4": [clean(d4[x]) for x in FIG4_PSI],
                   "fig4_lambda_0.025": [clean(supp[x]) for x in FIG4_PSI],
                   "mesh_check": [clean(mesh[L]) for L in LEVELS],
                   "fig5": [clean(d5[x]) for x in FIG5_LAMBDAS],
                   "fig6": [clean(d) for d in fig6_rows], "step": steps}, f, indent=1)

    print()
    bad = [(n, c, e) for n, c, e in runner.log if c != 0]
    if bad:
        print("runs that did not finish normally:")
        for n, c, e in bad:
            print(f"  {n}: exit {c}: {e.splitlines()[-1] if e else ''}")
    print(f"figures and tables written to {a.outdir} ({time.time() - t0:.0f} s)")


if __name__ == "__main__":
    main()
