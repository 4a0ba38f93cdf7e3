#!/usr/bin/env python3
"""Parametric contact scene: two cylinders of radii R1 != R2, or a cylinder on a flat, in plane
strain, meshed with gmsh for `stickslip` (MSH 4.1, 6-node triangles, deterministic).

    python3 meshes/scene.py --r1 10 --r2 15 --a 0.2 --out scene.msh
    python3 meshes/scene.py --r1 10 --flat --load 2 --e1 200 --nu1 0.3 --e2 70 --nu2 0.33 --out s.msh
    python3 meshes/scene.py --r1 10 --r2 15 --a 0.2 --lambda 0.02 --out jkr.msh   # h <= s0/2
    python3 meshes/scene.py --r1 10 --r2 15 --h-contact 0.01 --x-fine 0.3 --depth 4 --out s.msh

Geometry (units are the caller's; the contact point is the origin):
  upper_body : body 1, the cylinder of radius R1 pressed by the rigid pilot: the part of the
               disc centred at (0, R1) below y = D1 (a circular segment of depth D1 <= R1; a
               half-disc when D1 = R1). Its straight face y = D1 is `top` (the pilot face), its
               arc is `upper_arc`.
  lower_body : body 2, held on its straight face `bottom` (y = -D2):
               * R2 finite: the part of the disc centred at (0, -R2) above y = -D2, arc
                 `lower_arc`;
               * --flat (R2 = infinity): the rectangle [-W, W] x [-D2, 0]; its top face y = 0 is
                 the contact face, named `lower_arc` like the VM272 meshes (its sides are free and
                 in no group).
  The bodies touch at (0, 0) and share no point, curve or node. Physical groups (names as in
  vm272.geo and pad_flat.geo): "lower_body"=(2,1), "upper_body"=(2,2), "bottom"=(1,3),
  "top"=(1,4), "lower_arc"=(1,5), "upper_arc"=(1,6).

Sizing ("model no more than the scene needs"). The scene's Hertz semi-width a is given by --a,
or computed from --load P and the elastic constants (--e1 --nu1 --e2 --nu2, plane strain:
a = sqrt(4 P R / (pi E*)), 1/R = 1/R1 + 1/R2, 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2).
The slip-weakening transition length s0 (eq. s0 of the paper, at the centre) is given by --s0,
or by --lambda (s0 = 2 Lambda a / pi); without either the law has none (Coulomb friction).
  h_contact : element size along both contact faces for |x| <= x_fine
              (default min(a / PER_A, 0.97 s0 / PER_S0) = min(a/24, 0.97 s0/2): s0 resolved,
              h <= s0/2, with 3 % to spare for gmsh's chord lengths);
  x_fine    : half-width of the fine zone (default FINE_FACTOR a = 1.5 a);
  depth     : D1 = min(R1, depth), D2 = min(R2, depth) (default DEPTH_FACTOR a = 20 a: a and
              p0 within 0.1 % of Hertz for identical bodies; 10 a: 0.3 %, 5 a: 2 %); the flat's
              half-width W = 2 * depth;
  growth    : size h = min(h_far, h_contact + growth * d), d = distance to the fine zone of the
              two faces (default growth 0.15);
  h_far     : cap far from the contact (default depth / 6).
Each contact face is split at |x| = x_fine and at x = 0 (one copy of the contact point per body).

Options: --order 1|2 (default 2), --ascii (default binary MSH 4.1), --json (print a one-line
JSON summary: the sizes used, node and triangle counts, the chord range along the fine zone).
The written file is re-opened and checked (groups, element types, counter-clockwise triangles,
arc nodes on their circles, flat face on y = 0, no node shared by the bodies); the script exits
non-zero if a check fails. Output is deterministic: one thread, Mesh.RandomSeed 1, fixed
options (gmsh 4.15.2 from PyPI: `pip install gmsh`).
"""
import argparse
import json
import math
import os
import sys

import gmsh


def positive(name, v):
    if v is None or not (v > 0.0) or not math.isfinite(v):
        sys.exit(f"scene.py: --{name} must be a positive finite number, got {v}")
    return v


def parse(argv):
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--r1", type=float, required=True, help="radius of the upper cylinder (body 1)")
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument("--r2", type=float, help="radius of the lower cylinder (body 2)")
    g.add_argument("--flat", action="store_true", help="the lower body is a flat (R2 = infinity)")
    p.add_argument("--out", required=True, help="output .msh")
    p.add_argument("--a", type=float, help="Hertz contact semi-width of the scene")
    p.add_argument("--load", type=float, help="normal load P per unit thickness (computes a)")
    for k, what in (("e1", "Young's modulus of body 1 (upper)"), ("nu1", "Poisson's ratio of body 1"),
                    ("e2", "Young's modulus of body 2 (lower)"), ("nu2", "Poisson's ratio of body 2")):
        p.add_argument(f"--{k}", type=float, help=f"{what} (with --load)")
    p.add_argument("--s0", type=float, help="slip-weakening transition length s0")
    p.add_argument("--lambda", dest="lam", type=float, help="Lambda of the law (s0 = 2 Lambda a/pi)")
    p.add_argument("--h-contact", type=float, help="element size along the fine zone")
    p.add_argument("--x-fine", type=float, help="half-width of the fine zone (default FINE_FACTOR a)")
    p.add_argument("--fine-factor", type=float, default=1.5, help="default x_fine = FINE_FACTOR * a (1.5)")
    p.add_argument("--per-a", type=float, default=24.0, help="default h_contact = a / PER_A (24)")
    p.add_argument("--per-s0", type=float, default=2.0, help="and h_contact <= s0 / PER_S0 (2)")
    p.add_argument("--depth", type=float, help="depth of each body (default 20 a, capped at R)")
    p.add_argument("--depth-factor", type=float, default=20.0, help="default depth = FACTOR * a")
    p.add_argument("--growth", type=float, default=0.15, help="size growth rate (0.15)")
    p.add_argument("--h-far", type=float, help="size cap far away (default depth / 6)")
    p.add_argument("--order", type=int, default=2, choices=(1, 2))
    p.add_argument("--ascii", action="store_true", help="ASCII instead of binary MSH 4.1")
    p.add_argument("--json", action="store_true", help="print a one-line JSON summary")
    return p.parse_args(argv)


def sizes(o):
    """The scene's sizes from the options (see the module docstring)."""
    r1 = positive("r1", o.r1)
    r2 = math.inf if o.flat else positive("r2", o.r2)
    r_eff = 1.0 / (1.0 / r1 + (0.0 if math.isinf(r2) else 1.0 / r2))
    if o.a is not None:
        a = positive("a", o.a)
    elif o.load is not None:
        for k in ("e1", "nu1", "e2", "nu2"):
            if getattr(o, k) is None:
                sys.exit(f"scene.py: --load needs --{k}")
        e_star = 1.0 / ((1 - o.nu1 ** 2) / positive("e1", o.e1) + (1 - o.nu2 ** 2) / positive("e2", o.e2))
        a = math.sqrt(4.0 * positive("load", o.load) * r_eff / (math.pi * e_star))
    elif o.h_contact is not None and o.x_fine is not None and o.depth is not None:
        a = None
    else:
        sys.exit("scene.py: give --a, or --load with --e1 --nu1 --e2 --nu2, "
                 "or all of --h-contact --x-fine --depth")
    s0 = o.s0
    if s0 is None and o.lam is not None:
        if a is None:
            sys.exit("scene.py: --lambda needs a (--a or --load)")
        s0 = 2.0 * positive("lambda", o.lam) * a / math.pi
    h = o.h_contact
    if h is None:
        h = a / o.per_a
        if s0 is not None:
            h = min(h, 0.97 * positive("s0", s0) / o.per_s0)
    x_fine = o.x_fine if o.x_fine is not None else o.fine_factor * a
    depth = o.depth if o.depth is not None else o.depth_factor * a
    d1 = min(r1, positive("depth", depth))
    d2 = min(r2, depth)
    h_far = o.h_far if o.h_far is not None else depth / 6.0
    h_far = max(h_far, h)
    positive("h-contact", h)
    positive("x-fine", x_fine)
    positive("growth", o.growth)
    if x_fine >= 0.5 * min(r1, r2) or x_fine >= 0.9 * math.sqrt(d1 * (2 * r1 - d1)):
        sys.exit(f"scene.py: the fine zone |x| <= {x_fine:g} does not fit on the bodies "
                 f"(R1 = {r1:g}, R2 = {r2:g}, depth {depth:g})")
    if not math.isinf(r2) and x_fine >= 0.9 * math.sqrt(d2 * (2 * r2 - d2)):
        sys.exit(f"scene.py: the fine zone |x| <= {x_fine:g} does not fit on the lower body")
    return dict(r1=r1, r2=r2, r_eff=r_eff, a=a, s0=s0, h_contact=h, x_fine=x_fine,
                depth=depth, d1=d1, d2=d2, w_flat=2.0 * depth, growth=o.growth, h_far=h_far)


def build(s):
    """The geometry with the built-in kernel; returns the fine curves for the size field."""
    geo = gmsh.model.geo
    r1, r2, d1, d2, xf = s["r1"], s["r2"], s["d1"], s["d2"], s["x_fine"]
    fine = []

    # ---------------- lower body (body 2, fixed on `bottom`) ----------------
    if math.isinf(r2):
        w = s["w_flat"]
        p = [geo.addPoint(x, y, 0) for x, y in
             ((-w, -d2), (w, -d2), (w, 0), (xf, 0), (0, 0), (-xf, 0), (-w, 0))]
        c = [geo.addLine(p[i], p[(i + 1) % 7]) for i in range(7)]
        bottom, face = [c[0]], c[2:6]
        fine += c[3:5]
    else:
        yc = -r2
        wb = math.sqrt(max(r2 * r2 - (r2 - d2) ** 2, 0.0))
        yf = yc + math.sqrt(r2 * r2 - xf * xf)
        pc = geo.addPoint(0, yc, 0)
        p = [geo.addPoint(x, y, 0) for x, y in
             ((-wb, -d2), (wb, -d2), (xf, yf), (0, 0), (-xf, yf))]
        c = [geo.addLine(p[0], p[1])]
        c += [geo.addCircleArc(p[i], pc, p[(i + 1) % 5]) for i in range(1, 5)]
        bottom, face = [c[0]], c[1:5]
        fine += c[2:4]
    lower = geo.addPlaneSurface([geo.addCurveLoop(c)])

    # ---------------- upper body (body 1, the pilot on `top`) ----------------
    yc = r1
    wt = math.sqrt(max(r1 * r1 - (r1 - d1) ** 2, 0.0))
    yf = yc - math.sqrt(r1 * r1 - xf * xf)
    pc = geo.addPoint(0, yc, 0)
    q = [geo.addPoint(x, y, 0) for x, y in
         ((-wt, d1), (-xf, yf), (0, 0), (xf, yf), (wt, d1))]
    cu = [geo.addCircleArc(q[i], pc, q[i + 1]) for i in range(4)]
    cu.append(geo.addLine(q[4], q[0]))
    upper = geo.addPlaneSurface([geo.addCurveLoop(cu)])
    fine += cu[1:3]
    geo.synchronize()

    m = gmsh.model
    m.addPhysicalGroup(2, [lower], 1, "lower_body")
    m.addPhysicalGroup(2, [upper], 2, "upper_body")
    m.addPhysicalGroup(1, bottom, 3, "bottom")
    m.addPhysicalGroup(1, [cu[4]], 4, "top")
    m.addPhysicalGroup(1, face, 5, "lower_arc")
    m.addPhysicalGroup(1, cu[0:4], 6, "upper_arc")
    return fine


def mesh(s, o):
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("Geometry.AutoCoherence", 0)   # never merge the contact points
    gmsh.model.add("scene")
    fine = build(s)
    f = gmsh.model.mesh.field
    dist = f.add("Distance")
    f.setNumbers(dist, "CurvesList", fine)
    f.setNumber(dist, "Sampling", 2000)
    thr = f.add("Threshold")
    f.setNumber(thr, "InField", dist)
    f.setNumber(thr, "SizeMin", s["h_contact"])
    f.setNumber(thr, "SizeMax", s["h_far"])
    f.setNumber(thr, "DistMin", 0.0)
    f.setNumber(thr, "DistMax", (s["h_far"] - s["h_contact"]) / s["growth"])
    f.setAsBackgroundMesh(thr)
    for k, v in (("Mesh.MeshSizeExtendFromBoundary", 0), ("Mesh.MeshSizeFromPoints", 0),
                 ("Mesh.MeshSizeFromCurvature", 0), ("Mesh.MeshSizeMax", s["h_far"]),
                 ("Mesh.Algorithm", 6), ("Mesh.RandomSeed", 1), ("General.NumThreads", 1),
                 ("Mesh.ElementOrder", o.order), ("Mesh.SecondOrderLinear", 0),
                 ("Mesh.HighOrderOptimize", 0), ("Mesh.MshFileVersion", 4.1),
                 ("Mesh.Binary", 0 if o.ascii else 1), ("Mesh.SaveAll", 0)):
        gmsh.option.setNumber(k, v)
    gmsh.model.mesh.generate(2)
    gmsh.write(o.out)


def verify(s, o):
    """Re-opens the file; returns (errors, facts)."""
    gmsh.open(o.out)
    errors = []
    tags, coords, _ = gmsh.model.mesh.getNodes()
    xy = {int(t): (coords[3 * i], coords[3 * i + 1]) for i, t in enumerate(tags)}
    groups = {gmsh.model.getPhysicalName(d, t): (d, t) for d, t in gmsh.model.getPhysicalGroups()}
    want = {"lower_body": (2, 1), "upper_body": (2, 2), "bottom": (1, 3), "top": (1, 4),
            "lower_arc": (1, 5), "upper_arc": (1, 6)}
    if groups != want:
        errors.append(f"physical groups {groups}")
    nv = {2: 3 if o.order == 1 else 6, 1: 2 if o.order == 1 else 3}
    want_type = {2: 2 if o.order == 1 else 9, 1: 1 if o.order == 1 else 8}
    conn = {}
    for name, (d, t) in groups.items():
        rows = []
        for ent in gmsh.model.getEntitiesForPhysicalGroup(d, t):
            ets, _, ens = gmsh.model.mesh.getElements(d, ent)
            for et, en in zip(ets, ens):
                if int(et) != want_type[d]:
                    errors.append(f"element type {et} in {name}")
                en = [int(v) for v in en]
                rows += [en[i:i + nv[d]] for i in range(0, len(en), nv[d])]
        conn[name] = rows
    neg = sum(1 for b in ("lower_body", "upper_body") for r in conn.get(b, [])
              if (xy[r[1]][0] - xy[r[0]][0]) * (xy[r[2]][1] - xy[r[0]][1])
              - (xy[r[2]][0] - xy[r[0]][0]) * (xy[r[1]][1] - xy[r[0]][1]) <= 0)
    if neg:
        errors.append(f"{neg} clockwise triangles")
    lo = {v for r in conn.get("lower_body", []) for v in r}
    up = {v for r in conn.get("upper_body", []) for v in r}
    if lo & up:
        errors.append(f"bodies share {len(lo & up)} nodes")
    dev = 0.0
    for r in conn.get("upper_arc", []):
        for v in r:
            dev = max(dev, abs(math.hypot(xy[v][0], xy[v][1] - s["r1"]) - s["r1"]))
    for r in conn.get("lower_arc", []):
        for v in r:
            if math.isinf(s["r2"]):
                dev = max(dev, abs(xy[v][1]))
            else:
                dev = max(dev, abs(math.hypot(xy[v][0], xy[v][1] + s["r2"]) - s["r2"]))
    if dev > 1e-9 * max(1.0, s["r1"]):
        errors.append(f"contact-face node off its circle/line by {dev:.3e}")
    chords = {}
    for g in ("lower_arc", "upper_arc"):
        ls = [math.hypot(xy[r[0]][0] - xy[r[1]][0], xy[r[0]][1] - xy[r[1]][1])
              for r in conn.get(g, [])
              if max(abs(xy[r[0]][0]), abs(xy[r[1]][0])) <= s["x_fine"] * (1 + 1e-9)]
        chords[g] = (min(ls), max(ls), len(ls)) if ls else (0.0, 0.0, 0)
        if not ls:
            errors.append(f"no element of {g} in the fine zone")
    ntri = len(conn.get("lower_body", [])) + len(conn.get("upper_body", []))
    facts = {"nodes": len(xy), "triangles": ntri,
             "fine_edges": chords["lower_arc"][2],
             "fine_chord": [min(c[0] for c in chords.values()), max(c[1] for c in chords.values())]}
    return errors, facts


def main(argv=None):
    o = parse(sys.argv[1:] if argv is None else argv)
    s = sizes(o)
    os.makedirs(os.path.dirname(os.path.abspath(o.out)), exist_ok=True)
    gmsh.initialize(["scene.py"], readConfigFiles=False)
    try:
        mesh(s, o)
        gmsh.clear()
        errors, facts = verify(s, o)
    finally:
        gmsh.finalize()
    if errors:
        for e in errors:
            print(f"scene.py: ERROR: {e}", file=sys.stderr)
        sys.exit(1)
    out = dict(s, **facts, out=o.out, gmsh=gmsh.__version__)
    out["r2"] = None if math.isinf(s["r2"]) else s["r2"]
    if o.json:
        print(json.dumps(out))
    else:
        print(f"{o.out}: R1 = {s['r1']:g}, R2 = {'inf' if out['r2'] is None else s['r2']:}, "
              f"h = {s['h_contact']:.4g} on |x| <= {s['x_fine']:.4g}, depth {s['depth']:.4g}, "
              f"{facts['nodes']} nodes, {facts['triangles']} triangles, "
              f"{facts['fine_edges']} fine edges of {facts['fine_chord'][0]:.4g}..{facts['fine_chord'][1]:.4g}")


if __name__ == "__main__":
    main()
