#!/usr/bin/env python3
"""Two elastic half-cylinders of different radii, meshed with gmsh for stickslip: the worked
example of "Bring your own mesh" in the README, run as shipped by tests/own_mesh.rs.

    python3 meshes/two_cylinders.py                 # writes meshes/two_cylinders.msh
    python3 meshes/two_cylinders.py --r-lower 12 --r-upper 5 --a 0.3197 --per-a 20 --out my.msh
    stickslip run cases/own_mesh.json               # the case written for the default mesh

Geometry (units are the case's; the shipped case uses mm):

  lower body  upper half of the disc of radius R_lower centred at (0, 0): flat face `bottom`
              (y = 0), arc `lower_arc`;
  upper body  lower half of the disc of radius R_upper centred at (0, R_lower + R_upper): arc
              `upper_arc`, flat face `top` (y = R_lower + R_upper), which the case drives as the
              rigid pilot.

The bodies touch at (0, R_lower). What stickslip needs from a mesh, and how this script does it:

  * one Physical Surface per body and one Physical Curve per face the case names (supports,
    pilot, tractions, contact slave and master); names are what the case refers to;
  * second order: 6-node triangles and 3-node lines (Mesh.ElementOrder = 2), mid-edge nodes on
    the true arcs (Mesh.SecondOrderLinear = 0);
  * the two bodies share no node: each has its own copy of the contact point (built here as two
    separate surfaces; in a .geo file also set Geometry.AutoCoherence = 0, and with the OCC
    kernel do not fragment the bodies);
  * MSH 4.1, only the elements of physical groups saved (Mesh.SaveAll = 0);
  * elements small along both contact faces where contact will be: h = a / PER_A over
    |x| <= 1.5 a (a = the Hertz semi-width you expect, `stickslip analytic hertz --r1 R1 --r2 R2
    --load P`), growing away from it. The run warns below 10 elements across the contact width
    2a, and, for a slip-weakening law, when h > s0/2. (`stickslip analytic hertz --r1 12 --r2 5
    --load 2.5` gives a = 0.3197 mm for the defaults.)

Output is deterministic for one gmsh version (one thread, fixed seed): gmsh 4.15.2 from PyPI,
which `bash scripts/test.sh` installs.
"""
import argparse
import os
import sys

import gmsh

HERE = os.path.dirname(os.path.abspath(__file__))


def parse(argv):
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--r-lower", type=float, default=12.0, help="radius of the lower cylinder (12)")
    p.add_argument("--r-upper", type=float, default=5.0, help="radius of the upper cylinder (5)")
    p.add_argument("--a", type=float, default=0.3197,
                   help="Hertz semi-width the mesh is sized for (0.3197: P = 2.5 N/mm, "
                        "E = 200 N/mm^2, nu = 0.3 on both bodies)")
    p.add_argument("--per-a", type=float, default=20.0,
                   help="elements per semi-width a along the contact faces (20)")
    p.add_argument("--growth", type=float, default=0.05,
                   help="element size growth per unit distance from the contact zone (0.05)")
    p.add_argument("--out", default=os.path.join(HERE, "two_cylinders.msh"),
                   help="output file (meshes/two_cylinders.msh)")
    o = p.parse_args(argv)
    for k in ("r_lower", "r_upper", "a", "per_a", "growth"):
        if not getattr(o, k) > 0.0:
            p.error(f"--{k.replace('_', '-')} must be positive")
    if 1.5 * o.a >= 0.5 * min(o.r_lower, o.r_upper):
        p.error("the fine zone |x| <= 1.5a does not fit on the arcs: a is too large for R1, R2")
    return o


def half_disc(cx, cy, r, xs, upper_half):
    """A half-disc centred at (cx, cy): its flat side on y = cy, its arc through (0, cy -+ r),
    split at |x| = xs and at x = 0. Returns (surface, flat side, arc pieces, central pieces)."""
    geo = gmsh.model.geo
    s = 1.0 if upper_half else -1.0
    ys = cy + s * (r * r - xs * xs) ** 0.5
    centre = geo.addPoint(cx, cy, 0)
    # Counter-clockwise: along the flat side, then back over the arc.
    ends = [(-r, cy), (r, cy)] if upper_half else [(r, cy), (-r, cy)]
    arc_pts = [(xs, ys), (0.0, cy + s * r), (-xs, ys)] if upper_half else \
              [(-xs, ys), (0.0, cy + s * r), (xs, ys)]
    p = [geo.addPoint(x, y, 0) for x, y in ends + arc_pts]
    flat = geo.addLine(p[0], p[1])
    arcs = [geo.addCircleArc(p[1], centre, p[2]), geo.addCircleArc(p[2], centre, p[3]),
            geo.addCircleArc(p[3], centre, p[4]), geo.addCircleArc(p[4], centre, p[0])]
    surface = geo.addPlaneSurface([geo.addCurveLoop([flat] + arcs)])
    return surface, flat, arcs, arcs[1:3]


def build(o):
    xs = 1.5 * o.a                      # half-width of the fine zone on each arc
    h_c = o.a / o.per_a                 # element size there
    h_far = min(o.r_lower, o.r_upper) / 8.0   # size cap far from the contact
    gmsh.model.add("two_cylinders")
    lower, bottom, lower_arc, fine_lo = half_disc(0.0, 0.0, o.r_lower, xs, upper_half=True)
    upper, top, upper_arc, fine_up = half_disc(0.0, o.r_lower + o.r_upper, o.r_upper, xs,
                                               upper_half=False)
    gmsh.model.geo.synchronize()

    # Physical groups: the names are the contract with the case file (tags as in vm272.geo).
    m = gmsh.model
    m.addPhysicalGroup(2, [lower], 1, "lower_body")
    m.addPhysicalGroup(2, [upper], 2, "upper_body")
    m.addPhysicalGroup(1, [bottom], 3, "bottom")
    m.addPhysicalGroup(1, [top], 4, "top")
    m.addPhysicalGroup(1, lower_arc, 5, "lower_arc")
    m.addPhysicalGroup(1, upper_arc, 6, "upper_arc")

    # Size: h_c on the central arcs (|x| <= 1.5a), growing linearly with the distance from them.
    f = m.mesh.field
    dist = f.add("Distance")
    f.setNumbers(dist, "CurvesList", fine_lo + fine_up)
    f.setNumber(dist, "Sampling", 2000)
    thr = f.add("Threshold")
    f.setNumber(thr, "InField", dist)
    f.setNumber(thr, "SizeMin", h_c)
    f.setNumber(thr, "SizeMax", h_far)
    f.setNumber(thr, "DistMin", 0.0)
    f.setNumber(thr, "DistMax", (h_far - h_c) / o.growth)
    f.setAsBackgroundMesh(thr)

    for key, value in (
        ("Mesh.MeshSizeExtendFromBoundary", 0), ("Mesh.MeshSizeFromPoints", 0),
        ("Mesh.MeshSizeFromCurvature", 0), ("Mesh.MeshSizeMax", h_far),
        ("Mesh.Algorithm", 6),                  # Frontal-Delaunay
        ("Mesh.RandomSeed", 1), ("General.NumThreads", 1),   # deterministic
        ("Mesh.ElementOrder", 2),               # 6-node triangles, 3-node lines
        ("Mesh.SecondOrderLinear", 0),          # mid-edge nodes on the true arcs
        ("Mesh.HighOrderOptimize", 0),
        ("Mesh.MshFileVersion", 4.1), ("Mesh.Binary", 1),
        ("Mesh.SaveAll", 0),                    # only the elements of physical groups
    ):
        gmsh.option.setNumber(key, value)
    m.mesh.generate(2)
    return h_c


def main(argv=None):
    o = parse(sys.argv[1:] if argv is None else argv)
    out = os.path.abspath(o.out)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    tmp = f"{out}.tmp{os.getpid()}.msh"
    gmsh.initialize(["two_cylinders.py"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("Geometry.AutoCoherence", 0)   # never merge the contact points
        h_c = build(o)
        gmsh.write(tmp)
        triangles = len(gmsh.model.mesh.getElementsByType(9)[0])
    finally:
        gmsh.finalize()
    os.replace(tmp, out)   # a file is either whole or absent
    print(f"{os.path.relpath(out)}: R_lower = {o.r_lower:g}, R_upper = {o.r_upper:g}, h = {h_c:.4g} on "
          f"|x| <= {1.5 * o.a:.4g} "
          f"(a/h = {o.per_a:g}), {triangles} triangles, gmsh {gmsh.__version__}")


if __name__ == "__main__":
    main()
