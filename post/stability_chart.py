#!/usr/bin/env python3
"""Chart of the stability study written by `cargo bench --bench stability`.

Usage: python3 post/stability_chart.py out/bench/stability.csv OUT.png

One panel per contact method: Newton iterations per load step against the number of steps
(log scale), one line per friction-law shape and mesh level (h/s0 in the legend); runs that
did not converge are marked with a red cross at the top of the panel.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main() -> int:
    if len(sys.argv) != 3:
        print(__doc__)
        return 2
    rows = list(csv.DictReader(open(sys.argv[1])))
    methods = ["newton", "penalty", "augmented_lagrangian"]
    shapes = {"step": "-", "ramp": "--", "exponential": ":"}
    colors = {"2": "tab:blue", "3": "tab:orange", "4": "tab:green"}
    fig, axes = plt.subplots(1, 3, figsize=(13, 4), sharey=True)
    ymax = max(float(r["iterations_per_step"]) for r in rows) * 1.15
    for ax, m in zip(axes, methods):
        for shape, ls in shapes.items():
            for level, col in colors.items():
                pts = sorted(
                    (int(r["steps"]), float(r["iterations_per_step"]), r["converged"] == "true", float(r["h_over_s0"]))
                    for r in rows
                    if r["method"] == m and r["shape"] == shape and r["level"] == level
                )
                if not pts:
                    continue
                ok = [(s, it) for s, it, c, _ in pts if c]
                if ok:
                    ax.plot([p[0] for p in ok], [p[1] for p in ok], ls, color=col, marker="o", ms=3,
                            label=f"{shape}, h/s0 = {pts[0][3]:.2f}")
                for s, _, c, _ in pts:
                    if not c:
                        ax.plot([s], [ymax * 0.97], "x", color="red", ms=9, mew=2)
        ax.set_xscale("log")
        ax.set_xticks([5, 20, 80])
        ax.set_xticklabels(["5", "20", "80"])
        ax.minorticks_off()
        ax.set_title(m.replace("_", " "))
        ax.set_xlabel("tangential load steps")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("Newton iterations per step")
    axes[0].set_ylim(0, ymax)
    axes[2].legend(fontsize=7, loc="upper right")
    fig.suptitle("Stability study, Fig. 2 problem (red ×: did not converge)")
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=130)
    print(f"chart written to {sys.argv[2]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
