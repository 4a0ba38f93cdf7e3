#!/usr/bin/env python3
"""Error against wall time, three codes: stickslip and Kratos (one run of post/kratos/bench.py)
and CalculiX (its rows of the documented 2026-11-26 accuracy-bench run, or a CSV given).

    python3 post/kratos/chart.py out/bench/kratos.csv docs/figs \
        [--calculix post/kratos/calculix_2026-11-26.csv]

Writes OUTDIR/speed_accuracy_3codes_pressure.png (max |p - p_H|/p0 over |x| <= 0.95a, Hertz and
Cattaneo-Mindlin) and OUTDIR/speed_accuracy_3codes_shear.png (max |q - q_CM|/(mu p0), C-M).
Only rows with status "ok" are drawn as points of a ladder; a row that is not ok (a Kratos run
with non-converged steps, or one that converged to a wrong contact set) is drawn as a hollow
cross of its code's colour, labelled in the legend as not a valid result, so that it is seen
and not mistaken for one.
"""
import argparse
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = {
    ("stickslip", "hertz"): dict(color="tab:blue", marker="o", ls="--", mfc="white",
                                 label="stickslip (P2 triangles), Hertz"),
    ("stickslip", "cm"): dict(color="tab:blue", marker="o", ls="-",
                              label="stickslip (P2 triangles), Cattaneo–Mindlin"),
    ("kratos", "hertz"): dict(color="tab:purple", marker="D", ls="--", mfc="white",
                              label="Kratos 10.4.4 ALM mortar (P1 triangles), Hertz"),
    ("kratos", "cm"): dict(color="tab:purple", marker="D", ls="-",
                           label="Kratos 10.4.4 ALM mortar (P1 triangles), Cattaneo–Mindlin"),
    ("stickslip+", "hertz"): dict(color="tab:cyan", marker="o", ls="-.", mfc="white",
                                  label="stickslip, Hertz, EXTRA"),
    ("kratos+", "hertz"): dict(color="tab:pink", marker="D", ls="-.", mfc="white",
                               label="Kratos, Hertz, EXTRA"),
    ("calculix", "cm"): dict(color="tab:red", marker="^", ls="-",
                             label="CalculiX 2.20 (CPE6, penalty), C–M, 2026-11-26 run"),
}


def load(path):
    with open(path, newline="") as fh:
        lines = [l for l in fh if not l.startswith("#")]
    return list(csv.DictReader(lines))


def chart(rows, key, cases, target, target_label, ylabel, title, out, threads):
    fig, ax = plt.subplots(figsize=(7.8, 6.2))
    for (code, case), st in STYLE.items():
        if case not in cases:
            continue
        sel = [r for r in rows if r["code"] == code and r["case"] == case and r.get(key)]
        ok = sorted(((float(r["wall_s"]), float(r[key]), int(r["level"])) for r in sel
                     if r.get("status", "ok") == "ok"), key=lambda p: p[2])
        bad = [(float(r["wall_s"]), float(r[key]), int(r["level"])) for r in sel
               if r.get("status", "ok") != "ok"]
        if ok:
            ax.plot([p[0] for p in ok], [p[1] for p in ok], **st)
            dy = -11 if st.get("ls") == "--" else 4   # Hertz labels below, C-M above
            for x, y, L in ok:
                ax.annotate(f"L{L}", (x, y), textcoords="offset points", xytext=(5, dy), fontsize=8,
                            color=st["color"])
        if bad:
            ax.plot([p[0] for p in bad], [p[1] for p in bad], marker="X", color=st["color"], ms=10,
                    mew=1.5, mfc="none", ls=":", lw=0.8,
                    label=st["label"] + ": steps not converged, not a valid result")
        for x, y, L in bad:
            ax.annotate(f"L{L}", (x, y), textcoords="offset points", xytext=(7, -11),
                        fontsize=8, color=st["color"])
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axhline(target, color="k", lw=0.8, ls="-.")
    ax.text(0.01, target, f" {target_label}", transform=ax.get_yaxis_transform(), va="bottom",
            fontsize=8)
    ax.set_xlabel(f"wall time of the whole process (s), {threads} threads each unless said, shared 2-core machine")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    ax.legend(fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=1, frameon=False)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)
    print(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("csv")
    ap.add_argument("outdir")
    ap.add_argument("--calculix", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                       "calculix_2026-11-26.csv"))
    ap.add_argument("--threads", default="2")
    ap.add_argument("--extra", help="a second bench CSV (e.g. a 1-thread run): its Hertz rows are "
                                    "drawn as further series, labelled with --extra-label")
    ap.add_argument("--extra-label", default="second run")
    args = ap.parse_args()
    rows = load(args.csv)
    if args.extra:
        for r in load(args.extra):
            if r["case"] == "hertz":
                r["code"] += "+"
                rows.append(r)
        for k in (("stickslip+", "hertz"), ("kratos+", "hertz")):
            STYLE[k]["label"] = STYLE[k]["label"].replace("EXTRA", args.extra_label)
    if args.calculix and os.path.exists(args.calculix):
        rows += load(args.calculix)
    os.makedirs(args.outdir, exist_ok=True)
    chart(rows, "p_err_max", ("hertz", "cm"), 0.01, "1 % of $p_0$",
          r"max $|p - p_H|/p_0$ over $|x| \leq 0.95a$",
          "Contact pressure against Hertz, VM272 (P = 10 N/mm): three codes",
          os.path.join(args.outdir, "speed_accuracy_3codes_pressure.png"), args.threads)
    chart(rows, "q_err_max", ("cm",), 0.02, r"2 % of $\mu p_0$",
          r"max $|q - q_{CM}|/(\mu p_0)$ outside $c \pm w$, $a - w$ ($w = \max(2h, 0.05a)$)",
          "Shear traction against Cattaneo–Mindlin (μ = 0.2, Q = 0.936 N/mm): three codes",
          os.path.join(args.outdir, "speed_accuracy_3codes_shear.png"), args.threads)


if __name__ == "__main__":
    main()
