"""The error measures of benches/accuracy.rs, in Python, for the Kratos side-by-side bench.

Closed forms (half-space, identical materials): a = sqrt(4 P R'/(pi E*)), p0 = 2P/(pi a),
c = a sqrt(1 - Q/(mu P)); R' = R/2 = 4 mm, E* = E/(2(1 - nu^2)). These equal
`stickslip analytic hertz` and `stickslip analytic cm --mu MU --q Q` (bench.py checks that).

* p err: max and RMS of |p - p_H|/p0 over the slave nodes with |x| <= 0.95a;
* q err: max and RMS of |q - q_CM|/(mu p0) over the nodes with |x| <= a - w and
  ||x| - c| > w, w = max(2h, 0.05a), h = a/(3.2*2^L) (the element length along the arcs);
* c err = c_FE/c - 1.
"""
from __future__ import annotations

import csv
import math

R_EFF = 4.0
E_STAR = 200.0 / (2.0 * (1.0 - 0.3 ** 2))
P_LOAD = 10.0


def closed_forms(q=0.0, mu=0.2):
    a = math.sqrt(4.0 * P_LOAD * R_EFF / (math.pi * E_STAR))
    p0 = 2.0 * P_LOAD / (math.pi * a)
    c = a * math.sqrt(1.0 - q / (mu * P_LOAD)) if q > 0 else a
    return a, p0, c


def p_hertz(x, a, p0):
    return p0 * math.sqrt(max(0.0, 1.0 - (x / a) ** 2))


def q_cm(x, a, p0, c, mu):
    x = abs(x)
    if x >= a:
        return 0.0
    if x >= c:
        return mu * p_hertz(x, a, p0)
    return mu * p0 / a * (math.sqrt(a * a - x * x) - math.sqrt(c * c - x * x))


def max_rms(e):
    if not e:
        return float("nan"), float("nan")
    return max(e), math.sqrt(sum(v * v for v in e) / len(e))


def h_arc(level, a):
    return a / (3.2 * 2 ** level)


def pressure_errors(x, p, a, p0):
    return max_rms([abs(pi - p_hertz(xi, a, p0)) / p0 for xi, pi in zip(x, p) if abs(xi) <= 0.95 * a])


def shear_errors(x, q, level, q_ratio_mu, mu=0.2):
    """|q - q_CM|/(mu p0) outside a - w and c +- w; q_ratio_mu = Q (N/mm)."""
    a, p0, c = closed_forms(q_ratio_mu, mu)
    w = max(2.0 * h_arc(level, a), 0.05 * a)
    e = [abs(qi - q_cm(xi, a, p0, c, mu)) / (mu * p0) for xi, qi in zip(x, q)
         if abs(xi) <= a - w and abs(abs(xi) - c) > w]
    return max_rms(e)


def score(x, p, q, level, frictional, Q, mu, stick=None):
    """The bench's measures for nodal (x, p, q); `stick` (bools) gives c_FE where known."""
    a, p0, c = closed_forms(Q if frictional else 0.0, mu)
    out = {}
    out["p_err_max"], out["p_err_rms"] = pressure_errors(x, p, a, p0)
    inside = [abs(xi) for xi, pi in zip(x, p) if pi > 0]
    out["a_fe_over_a"] = max(inside) / a if inside else None
    if frictional:
        out["q_err_max"], out["q_err_rms"] = shear_errors(x, q, level, Q, mu)
        if stick is not None:
            st = [abs(xi) for xi, s in zip(x, stick) if s]
            out["c_fe"] = max(st) if st else 0.0
            out["c_err_rel"] = out["c_fe"] / c - 1.0
    return out


def read_kratos_csv(path, step):
    rows = []
    with open(path, newline="") as fh:
        for r in csv.DictReader(fh):
            if r["step"] == step:
                rows.append(r)
    rows.sort(key=lambda r: float(r["x"]))
    return rows


def score_kratos_csv(path, level, frictional, Q, mu, slip_tol):
    """Scores post/kratos/kratos_vm272.py's contact.csv (slave = lower arc).

    Kratos' AUGMENTED_NORMAL_CONTACT_PRESSURE is negative in compression, so p = -value;
    q = AUGMENTED_TANGENT_CONTACT_PRESSURE with its sign chosen so that q > 0 along +x (the
    direction of Q on the upper body) where the traction is largest in magnitude. Stick as in
    the CalculiX driver: p > 0 and |q| < mu p (1 - slip_tol); Kratos' own SLIP flag gives
    `c_fe_flag`."""
    out = {}
    for step in (("final", "normal") if frictional else ("final",)):
        rows = read_kratos_csv(path, step)
        if not rows:
            continue
        x = [float(r["x"]) for r in rows]
        p = [-float(r["p"]) for r in rows]
        q = [float(r["q"]) for r in rows]
        if frictional and q:
            big = max(range(len(q)), key=lambda i: abs(q[i]))
            if q[big] < 0:
                q = [-v for v in q]
        stick = [pi > 0 and abs(qi) < mu * pi * (1.0 - slip_tol) for pi, qi in zip(p, q)]
        s = score(x, p, q, level, frictional and step == "final", Q, mu, stick)
        if frictional:
            a, _, c = closed_forms(Q, mu)
            st = [abs(float(r["x"])) for r in rows if r["active"] == "1" and r["slip"] == "0"]
            s["c_fe_flag"] = max(st) if st else 0.0
            s["active_nodes"] = sum(r["active"] == "1" for r in rows)
            s["slip_nodes"] = sum(r["active"] == "1" and r["slip"] == "1" for r in rows)
        if step == "final":
            out.update(s)
        else:
            out["normal"] = s
    return out
