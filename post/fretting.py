"""Fretting loops: Q against the pilot displacement over three cycles of `cases/fretting.json`
(VM272 on L4, P = 10 N/mm, Q between ±1.5 N/mm) for constant μ = 0.2, and for a ramp
slip-weakening law (f_s = 0.2, f_d = 0.15, Δ = 2e-4 mm) with the accumulated slip and with
healing (`"history": "since_stick"`); and the shear traction at the turning points against the
Mindlin–Deresiewicz closed form (constant μ).

Usage: python3 post/fretting.py [--bin PATH] [--out docs/figs/fretting.png]
Prints the dissipation per cycle of each run (from summary.json) and the largest traction
deviation from Mindlin–Deresiewicz at the turning points.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fe_common import die, find_bin, read_contact, read_history  # noqa: E402

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
CASE = os.path.join(HERE, "..", "cases", "fretting.json")
WEAKENING = {"shape": "ramp", "fs": 0.2, "fd": 0.15, "delta": 2e-4}


def run(binary, tmp, name, friction):
    """Runs the fretting case with `friction`, every step written; returns its output dir."""
    with open(CASE) as f:
        case = json.load(f)
    case["mesh"] = os.path.abspath(os.path.join(os.path.dirname(CASE), case["mesh"]))
    case["contact"]["friction"] = friction
    case["output"] = {"every": 1}
    path = os.path.join(tmp, f"{name}.json")
    with open(path, "w") as f:
        json.dump(case, f)
    out = os.path.join(tmp, name)
    res = subprocess.run([binary, "run", path, "--out", out, "--quiet"],
                         capture_output=True, text=True)
    if res.returncode != 0:
        die(f"{name}: exit {res.returncode}\n{res.stderr}")
    return out


def md_traction(x, q, q_star, branch, mu=0.2, p_load=10.0, a=None, p0=None):
    """Mindlin–Deresiewicz shear traction (2-D): q*(x) ∓ 2 q_CM(x; c′)."""
    def cm(x, c):
        return mu * (p0 * np.sqrt(np.clip(1 - (x / a) ** 2, 0, None))
                     - p0 * (c / a) * np.sqrt(np.clip(1 - (x / c) ** 2, 0, None)) * (np.abs(x) < c))
    c_star = a * np.sqrt(1 - q_star / (mu * p_load))
    change = q_star - q if branch == "unloading" else q + q_star
    c = a * np.sqrt(max(1 - change / (2 * mu * p_load), 0.0))
    first = cm(x, c_star)
    return first - 2 * cm(x, c) if branch == "unloading" else -first + 2 * cm(x, c)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin")
    ap.add_argument("--out", default=os.path.join(HERE, "..", "docs", "figs", "fretting.png"))
    args = ap.parse_args()
    binary = find_bin(args.bin)
    runs = [
        ("constant μ = 0.2", {"shape": "constant", "mu": 0.2}),
        ("ramp, accumulated slip", dict(WEAKENING, history="accumulated")),
        ("ramp, healing (since_stick)", dict(WEAKENING, history="since_stick")),
    ]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.8))
    with tempfile.TemporaryDirectory() as tmp:
        outs = []
        for i, (label, friction) in enumerate(runs):
            out = run(binary, tmp, f"run{i}", friction)
            outs.append(out)
            h = read_history(out)
            with open(os.path.join(out, "summary.json")) as f:
                s = json.load(f)
            per = [c["dissipation"] for c in s["energy"]["per_cycle"]]
            print(f"{label}: dissipation per cycle " + ", ".join(f"{d:.4e}" for d in per)
                  + f" N mm/mm; energy balance {s['energy']['balance_relative']:.1e}")
            keep = h["stage"] >= 1
            if i == 0:
                # The fully stuck compliance of the first tangential step: subtracting it
                # leaves the part of the displacement the slip makes, which opens the loops.
                c0 = (h["pilot_ux"][1] - h["pilot_ux"][0]) / (h["pilot_fx"][1] - h["pilot_fx"][0])
            ax1.plot(1e3 * (h["pilot_ux"][keep] - c0 * h["pilot_fx"][keep]), h["pilot_fx"][keep],
                     lw=1.2, label=label)
        ax1.set_xlabel("pilot displacement less its stuck compliance, u_x − C0 Q (µm)")
        ax1.set_ylabel("Q (N/mm)")
        ax1.set_title("Fretting loops, three cycles (VM272, L4, P = 10 N/mm)")
        ax1.legend(fontsize=8)
        ax1.grid(alpha=0.3)
        # Traction at the turning points of the constant-μ run against M–D.
        h = read_history(outs[0])
        a, p0 = 0.68075, None
        worst = 0.0
        for t, branch, q_turn, style in [(3.0, "unloading", -1.5, "C0"), (4.0, "reloading", 1.5, "C3")]:
            i = int(np.argmin(np.abs(h["time"] - t)))
            step = int(h["step"][i])
            c, _, _ = read_contact(outs[0], step)
            if p0 is None:
                p0 = 2 * 10.0 / (np.pi * a)
            x = c["x"]
            order = np.arange(len(x))
            ref = md_traction(x[order], h["pilot_fx"][i], 1.5, branch, a=a, p0=p0)
            inside = np.abs(x[order]) < 0.95 * a
            worst = max(worst, np.max(np.abs(c["shear"][order] - ref)[inside]) / (0.2 * p0))
            ax2.plot(x[order] / a, c["shear"][order] / (0.2 * p0), style + "o", ms=2.5,
                     label=f"FE, Q = {q_turn:+.1f} (end of {branch})")
            ax2.plot(x[order] / a, ref / (0.2 * p0), style + "-", lw=1,
                     label=f"Mindlin–Deresiewicz, Q = {q_turn:+.1f}")
        print(f"turning points: max |q − q_MD| = {worst:.4f} μp0 over |x| < 0.95a")
        ax2.set_xlim(-1.1, 1.1)
        ax2.set_xlabel("x / a")
        ax2.set_ylabel("q / (μ p0)")
        ax2.set_title("Shear traction at the turning points (constant μ)")
        ax2.legend(fontsize=7)
        ax2.grid(alpha=0.3)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    fig.savefig(args.out, dpi=130)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
