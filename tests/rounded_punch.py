#!/usr/bin/env python3
"""A flat punch with rounded corners on a block, meshed with gmsh for tests/profile_reference.rs.

    python3 tests/rounded_punch.py OUT.msh [--flat 0.5] [--radius 10] [--h 0.05]

The punch (upper_body) is flat on y = 0 for |x| <= FLAT and rises in arcs of radius RADIUS
beyond, up to |x| = FLAT + 2 (then straight sides to its top face `top` at y = 4). The block
(lower_body) is [-8, 8] x [-8, 0], held on `bottom`; its top face is `lower_arc`, the punch's
lower face `upper_arc` (groups as in meshes/scene.py). 6-node triangles, MSH 4.1.
The profile is not a parabola: no Hertzian closed form applies to it.
"""
import argparse
import math

import gmsh


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--flat", type=float, default=0.5)
    p.add_argument("--radius", type=float, default=10.0)
    p.add_argument("--h", type=float, default=0.05)
    o = p.parse_args()
    f, r, h = o.flat, o.radius, o.h
    xe = f + 2.0
    ye = r - math.sqrt(r * r - (xe - f) ** 2)
    top, w, d = 4.0, 8.0, 8.0
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.option.setNumber("Mesh.RandomSeed", 1)
    gmsh.model.add("rounded_punch")
    g = gmsh.model.geo
    # The block.
    b = [g.addPoint(-w, -d, 0), g.addPoint(w, -d, 0), g.addPoint(w, 0, 0), g.addPoint(-w, 0, 0)]
    bm = [g.addPoint(-xe - 1.0, 0, 0), g.addPoint(xe + 1.0, 0, 0)]
    l_bottom = g.addLine(b[0], b[1])
    l_right = g.addLine(b[1], b[2])
    l_top_r = g.addLine(b[2], bm[1])
    l_top = g.addLine(bm[1], bm[0])
    l_top_l = g.addLine(bm[0], b[3])
    l_left = g.addLine(b[3], b[0])
    s_block = g.addPlaneSurface([g.addCurveLoop([l_bottom, l_right, l_top_r, l_top, l_top_l, l_left])])
    # The punch: flat, two arcs, sides, top.
    pl, pr = g.addPoint(-f, 0, 0), g.addPoint(f, 0, 0)
    cl, cr = g.addPoint(-f, r, 0), g.addPoint(f, r, 0)
    el, er = g.addPoint(-xe, ye, 0), g.addPoint(xe, ye, 0)
    tl, tr = g.addPoint(-xe, top, 0), g.addPoint(xe, top, 0)
    flat = g.addLine(pl, pr)
    arc_r = g.addCircleArc(pr, cr, er)
    side_r = g.addLine(er, tr)
    top_l = g.addLine(tr, tl)
    side_l = g.addLine(tl, el)
    arc_l = g.addCircleArc(el, cl, pl)
    s_punch = g.addPlaneSurface([g.addCurveLoop([flat, arc_r, side_r, top_l, side_l, arc_l])])
    g.synchronize()
    gmsh.model.addPhysicalGroup(2, [s_block], 1, "lower_body")
    gmsh.model.addPhysicalGroup(2, [s_punch], 2, "upper_body")
    gmsh.model.addPhysicalGroup(1, [l_bottom], 3, "bottom")
    gmsh.model.addPhysicalGroup(1, [top_l], 4, "top")
    gmsh.model.addPhysicalGroup(1, [l_top], 5, "lower_arc")
    gmsh.model.addPhysicalGroup(1, [arc_l, flat, arc_r], 6, "upper_arc")
    # Fine along the contact faces, coarser away from them.
    fd = gmsh.model.mesh.field
    dist = fd.add("Distance")
    fd.setNumbers(dist, "CurvesList", [l_top, flat, arc_l, arc_r])
    fd.setNumber(dist, "Sampling", 400)
    th = fd.add("Threshold")
    fd.setNumber(th, "InField", dist)
    fd.setNumber(th, "SizeMin", h)
    fd.setNumber(th, "SizeMax", 1.0)
    fd.setNumber(th, "DistMin", 0.1)
    fd.setNumber(th, "DistMax", 5.0)
    fd.setAsBackgroundMesh(th)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.ElementOrder", 2)
    gmsh.option.setNumber("Mesh.SecondOrderLinear", 0)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.model.mesh.generate(2)
    gmsh.write(o.out)
    gmsh.finalize()


if __name__ == "__main__":
    main()
