"""Shared helpers for the FE post-processing scripts (hertz_pressure.py, cattaneo.py, fig23.py).

Reads the output of `stickslip run CASE --out DIR`:
  DIR/contact_NNNN.csv  x,y,pressure,shear,gap,slip,slip_increment,status,mu,q_over_p
  DIR/history.csv       step,stage,time,...,a,x_centre,c,b,contact_fx,contact_fy,wall_s,mean_slip
and calls `stickslip analytic ...` for the closed forms.
"""
import csv
import glob
import io
import json
import os
import re
import subprocess
import sys

import numpy as np

OPEN, STICK, SLIP = 0, 1, 2


def die(msg):
    sys.exit(f"error: {msg}")


def find_bin(cli_value=None):
    """Binary path: --bin, else $STICKSLIP_BIN, else target/release/stickslip (relative to the
    current directory, then to the repository holding this script)."""
    if cli_value:
        cands = [cli_value]
    elif os.environ.get("STICKSLIP_BIN"):
        cands = [os.environ["STICKSLIP_BIN"]]
    else:
        here = os.path.dirname(os.path.abspath(__file__))
        cands = ["target/release/stickslip",
                 os.path.join(here, "..", "target", "release", "stickslip")]
    for c in cands:
        if os.path.isfile(c) and os.access(c, os.X_OK):
            return c
    die(f"stickslip binary not found (tried {', '.join(cands)}); build it with "
        "`cargo build --release` or pass --bin PATH / set STICKSLIP_BIN")


def _run(binary, args):
    cmd = [binary, "analytic", *map(str, args)]
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        die(f"command failed: {' '.join(cmd)}\n{res.stderr.strip()}")
    return res.stdout


def analytic_json(binary, *args):
    """`stickslip analytic ARGS` printing JSON -> dict."""
    return json.loads(_run(binary, args))


def analytic_csv(binary, *args):
    """`stickslip analytic ARGS` printing CSV -> dict of float arrays (empty cells -> NaN)."""
    rows = list(csv.DictReader(io.StringIO(_run(binary, args))))
    if not rows:
        die(f"`stickslip analytic {' '.join(map(str, args))}` printed no rows")
    return {k: np.array([float(r[k]) if r[k] != "" else np.nan for r in rows]) for k in rows[0]}


def contact_files(run_dir):
    if not os.path.isdir(run_dir):
        die(f"run directory {run_dir!r} does not exist")
    files = glob.glob(os.path.join(run_dir, "contact_*.csv"))
    files = [f for f in files if re.search(r"contact_(\d+)\.csv$", f)]
    if not files:
        die(f"no contact_NNNN.csv in {run_dir!r} (was the case run with contact output?)")
    return sorted(files, key=lambda f: int(re.search(r"contact_(\d+)\.csv$", f).group(1)))


def read_contact(run_dir, step=None):
    """Contact CSV of the given step (default: the last one written), sorted by x.

    Returns (dict of column arrays, path, step). Adds `vertex` (bool): the contact arc is a chain
    of 3-node edges, so along x the nodes alternate vertex, mid-edge, vertex, ...; the parity is
    anchored on the node at x = 0 (the arcs are split at the contact point, which is a vertex),
    else on the ends of the chain (odd node count: both ends are vertices)."""
    files = contact_files(run_dir)
    if step is None:
        path = files[-1]
    else:
        path = os.path.join(run_dir, f"contact_{step:04d}.csv")
        if not os.path.isfile(path):
            die(f"{path} not found")
    step_no = int(re.search(r"contact_(\d+)\.csv$", path).group(1))
    data = np.genfromtxt(path, delimiter=",", names=True)
    if data.size == 0:
        die(f"{path} has no rows")
    need = ("x", "y", "pressure", "shear", "status", "mu")
    missing = [k for k in need if k not in data.dtype.names]
    if missing:
        die(f"{path}: missing columns {missing}")
    order = np.argsort(data["x"], kind="stable")
    cols = {k: np.asarray(data[k][order], dtype=float) for k in data.dtype.names}
    n = len(cols["x"])
    idx = np.arange(n)
    i0 = int(np.argmin(np.abs(cols["x"])))
    if abs(cols["x"][i0]) < 1e-9:
        cols["vertex"] = (idx - i0) % 2 == 0
    else:
        cols["vertex"] = idx % 2 == 0
    cols["status"] = np.rint(cols["status"]).astype(int)
    return cols, path, step_no


def read_history(run_dir):
    path = os.path.join(run_dir, "history.csv")
    if not os.path.isfile(path):
        die(f"{path} not found")
    h = np.genfromtxt(path, delimiter=",", names=True)
    return np.atleast_1d(h)


def history_row(run_dir, step):
    """history.csv row of the given step (a, c, b, forces, ...) as a dict."""
    h = read_history(run_dir)
    rows = h[np.rint(h["step"]).astype(int) == step]
    if len(rows) == 0:
        die(f"step {step} not in {run_dir}/history.csv")
    r = rows[-1]
    return {k: float(r[k]) for k in h.dtype.names}


def arc_edge_length(x, vertex, a):
    """Median edge length (distance between consecutive vertex nodes) within |x| <= a."""
    xv = x[vertex & (np.abs(x) <= a)]
    if len(xv) < 2:
        xv = x[vertex]
    return float(np.median(np.diff(xv)))


def style():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    plt.rcParams.update({
        "font.size": 10,
        "axes.labelsize": 11,
        "legend.fontsize": 8.5,
        "legend.framealpha": 0.9,
        "axes.grid": True,
        "grid.alpha": 0.25,
        "savefig.dpi": 150,
        "figure.dpi": 100,
    })
    return plt
