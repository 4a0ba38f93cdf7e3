#!/usr/bin/env python3
"""Regenerate every mesh in meshes/ from the .geo sources with the gmsh Python API,
verify each written file by re-opening it, and rewrite meshes/README.md.

    python3 meshes/generate.py            # all meshes
    python3 meshes/generate.py vm272_L3   # only outputs whose name starts with one of the args
    python3 meshes/generate.py vm272_L6 vm272_L7   # the two finest levels (on demand only)

The two finest VM272 levels (L6, L7: 10 and 17 MB) are not committed and not made by a plain
run; name them to build them (the convergence tests do, into meshes/, which git ignores).

Requires `pip install gmsh` (developed with gmsh 4.15.2). Output is deterministic:
single thread, fixed random seed, fixed options.
"""
import math
import os
import sys

import gmsh

HERE = os.path.dirname(os.path.abspath(__file__))
A = 0.6808          # Hertz semi-width of VM272 (mm)
R = 8.0             # radius of the half-discs (mm)
XS = 1.5 * A        # arcs are split at |x| = 1.5 a

# ---------------------------------------------------------------------------------------
# job list: (output file, geo file, parser parameters, option overrides, description)
# ---------------------------------------------------------------------------------------
JOBS = []
ON_DEMAND = {"vm272_L6.msh", "vm272_L7.msh", "blocks_h05.msh"}
for L in range(8):
    h_c = A / (3.2 * 2 ** L)
    JOBS.append((f"vm272_L{L}.msh", "vm272.geo", {"h_c": h_c},
                 {"Mesh.Binary": 1}, {"h": h_c, "note": f"h_c = a/{3.2 * 2 ** L:g}"}))
JOBS.append(("vm272_L1_ascii.msh", "vm272.geo", {"h_c": A / 6.4},
             {"Mesh.Binary": 0}, {"h": A / 6.4, "note": "level 1, ASCII MSH 4.1"}))
JOBS.append(("vm272_first_order.msh", "vm272.geo", {"h_c": A / 3.2, "order": 1},
             {"Mesh.Binary": 0}, {"h": A / 3.2, "note": "level 0, FIRST order (3-node), error-path test"}))
JOBS.append(("vm272_L0_msh22.msh", "vm272.geo", {"h_c": A / 3.2},
             {"Mesh.Binary": 0, "Mesh.MshFileVersion": 2.2},
             {"h": A / 3.2, "note": "level 0, MSH 2.2 ASCII, error-path test"}))
for L in range(5):
    h = 0.4 / 2 ** L
    JOBS.append((f"lame_L{L}.msh", "lame.geo", {"h": h, "linear": 0},
                 {"Mesh.Binary": 0}, {"h": h, "note": "curved (mid-edge nodes on arcs)"}))
for L in range(5):
    h = 0.4 / 2 ** L
    JOBS.append((f"lame_straight_L{L}.msh", "lame.geo", {"h": h, "linear": 1},
                 {"Mesh.Binary": 0}, {"h": h, "note": "straight-edged (SecondOrderLinear = 1)"}))
JOBS.append(("block_hertz.msh", "block_hertz.geo", {}, {"Mesh.Binary": 1},
             {"h": A / 40, "note": "a/40 on top for abs(x) <= 1.2a, ~a/20 on x = 0 to depth 3.5a; nodes at x = -a, 0, a on top"}))
JOBS.append(("patch_curved.msh", "patch_curved.geo", {}, {"Mesh.Binary": 0},
             {"h": 0.34, "note": "unit square, unstructured"}))
# Rupture on a long planar interface (docs/dynamics.md): two blocks 1200 x 600 mm, h_i along
# the interface over |x| <= 220 mm; h_i = 0.5 is made on demand (tests/rupture.rs).
for tag, h_i in (("h2", 2.0), ("h1", 1.0), ("h05", 0.5)):
    JOBS.append((f"blocks_{tag}.msh", "blocks.geo",
                 {"L": 1200.0, "H": 600.0, "h_i": h_i, "x_f": 220.0, "k_grow": 0.2, "h_far": 50.0},
                 {"Mesh.Binary": 1},
                 {"h": h_i, "note": f"two blocks 1200 x 600 mm; h = {h_i:g} mm along the interface for abs(x) <= 220 mm"}))
# Material-pair cases (docs/material_pairs.md): cylindrical pad R = 25 mm on a flat.
JOBS.append(("pad_flat.msh", "pad_flat.geo", {"h_c": 0.001, "x_f": 0.16}, {"Mesh.Binary": 1},
             {"h": 0.001, "xs": 0.16, "note": "pad R = 25 mm on a flat; h_c = 1 um for abs(x) <= 0.16 mm"}))
JOBS.append(("pad_flat_lead.msh", "pad_flat.geo", {"h_c": 0.00025, "x_f": 0.016}, {"Mesh.Binary": 1},
             {"h": 0.00025, "xs": 0.016, "note": "as pad_flat, h_c = 0.25 um for abs(x) <= 0.016 mm (lead pair)"}))


def make(out, geo, params, opts):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    for k, v in params.items():
        # equivalent of `gmsh -setnumber k v`: overrides the DefineConstant default
        gmsh.onelab.setNumber(k, [float(v)])
    gmsh.open(os.path.join(HERE, geo))
    for k, v in opts.items():
        gmsh.option.setNumber(k, v)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.option.setNumber("Mesh.RandomSeed", 1)
    gmsh.model.mesh.generate(2)
    gmsh.write(os.path.join(HERE, out))
    gmsh.finalize()


# ---------------------------------------------------------------------------------------
# verification of a written file
# ---------------------------------------------------------------------------------------
EXPECTED_GROUPS = {
    "vm272": {(2, "lower_body"), (2, "upper_body"), (1, "bottom"), (1, "top"),
              (1, "lower_arc"), (1, "upper_arc")},
    "lame": {(2, "body"), (1, "inner"), (1, "outer"), (1, "sym_x"), (1, "sym_y")},
    "block_hertz": {(2, "block"), (1, "top"), (1, "bottom"), (1, "left"), (1, "right")},
    "patch_curved": {(2, "body"), (1, "left"), (1, "right"), (1, "bottom"), (1, "top")},
    "pad_flat": {(2, "lower_body"), (2, "upper_body"), (1, "bottom"), (1, "top"),
                 (1, "lower_arc"), (1, "upper_arc")},
    "blocks": {(2, "lower_block"), (2, "upper_block"), (1, "bottom"), (1, "top"),
               (1, "lower_face"), (1, "upper_face"), (1, "lower_left"), (1, "lower_right"),
               (1, "upper_left"), (1, "upper_right")},
}
# circles whose boundary-line nodes must lie on the circle: group -> (cx, cy, r)
CIRCLES = {
    "vm272": {"lower_arc": (0.0, 0.0, R), "upper_arc": (0.0, 2 * R, R)},
    "lame": {"inner": (0.0, 0.0, 1.0), "outer": (0.0, 0.0, 2.0)},
    "pad_flat": {"upper_arc": (0.0, 35.0, 25.0)},
}
# straight contact faces whose nodes must lie on a line y = const: group -> y
FLATS = {"pad_flat": {"lower_arc": 10.0}, "blocks": {"lower_face": 0.0, "upper_face": 0.0}}


def family(out):
    for f in ("vm272", "lame", "block_hertz", "patch_curved", "pad_flat", "blocks"):
        if out.startswith(f):
            return f
    raise ValueError(out)


def check(out, desc):
    fam = family(out)
    first_order = out == "vm272_first_order.msh"
    straight = out.startswith("lame_straight")
    tri_t, lin_t = (2, 1) if first_order else (9, 8)
    nv_tri, nv_lin = (3, 2) if first_order else (6, 3)
    errors = []

    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.open(os.path.join(HERE, out))

    ntags, coords, _ = gmsh.model.mesh.getNodes()
    xy = {int(t): (coords[3 * i], coords[3 * i + 1]) for i, t in enumerate(ntags)}
    if any(abs(coords[3 * i + 2]) > 0 for i in range(len(ntags))):
        errors.append("non-zero z coordinate")

    groups = {}
    for dim, ptag in gmsh.model.getPhysicalGroups():
        name = gmsh.model.getPhysicalName(dim, ptag)
        groups[name] = (dim, ptag)
    if {(d, n) for n, (d, _) in groups.items()} != EXPECTED_GROUPS[fam]:
        errors.append(f"physical groups {sorted(groups)}")

    # elements per group
    conn = {}
    types = set()
    for name, (dim, ptag) in groups.items():
        rows = []
        for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, ptag):
            ets, _, enodes = gmsh.model.mesh.getElements(dim, ent)
            for et, en in zip(ets, enodes):
                types.add(int(et))
                nv = nv_tri if dim == 2 else nv_lin
                en = [int(v) for v in en]
                rows += [en[i:i + nv] for i in range(0, len(en), nv)]
        conn[name] = rows
    if types != {tri_t, lin_t}:
        errors.append(f"element types {sorted(types)}")

    used = set()
    for rows in conn.values():
        for r in rows:
            used.update(r)
    if used != set(xy):
        errors.append(f"{len(set(xy) - used)} orphan nodes / {len(used - set(xy))} missing nodes")

    surf = [n for n, (d, _) in groups.items() if d == 2]
    ntri = sum(len(conn[n]) for n in surf)

    # orientation (corner signed area) and mid-edge node placement
    neg = 0
    curved_edges = 0
    for n in surf:
        for r in conn[n]:
            (x0, y0), (x1, y1), (x2, y2) = xy[r[0]], xy[r[1]], xy[r[2]]
            if (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0) <= 0:
                neg += 1
            if not first_order:
                for m, (i, j) in zip(r[3:], ((0, 1), (1, 2), (2, 0))):
                    mx = 0.5 * (xy[r[i]][0] + xy[r[j]][0])
                    my = 0.5 * (xy[r[i]][1] + xy[r[j]][1])
                    d = math.hypot(xy[m][0] - mx, xy[m][1] - my)
                    L = math.hypot(xy[r[i]][0] - xy[r[j]][0], xy[r[i]][1] - xy[r[j]][1])
                    if d > 1e-12 * max(1.0, L):
                        curved_edges += 1
                        if d > 0.25 * L:
                            errors.append("mid-edge node far from its edge (ordering?)")
    if neg:
        errors.append(f"{neg} clockwise triangles")

    # bodies share no node (vm272, pad_flat, blocks)
    if fam in ("vm272", "pad_flat", "blocks"):
        lo_name, up_name = ("lower_block", "upper_block") if fam == "blocks" else ("lower_body", "upper_body")
        lo = {v for r in conn[lo_name] for v in r}
        up = {v for r in conn[up_name] for v in r}
        if lo & up:
            errors.append(f"bodies share {len(lo & up)} nodes")

    # boundary nodes on circles
    circ_dev = 0.0
    for gname, (cx, cy, rad) in CIRCLES.get(fam, {}).items():
        for r in conn[gname]:
            for k, v in enumerate(r):
                dev = abs(math.hypot(xy[v][0] - cx, xy[v][1] - cy) - rad)
                if k < 2 or not straight:
                    circ_dev = max(circ_dev, dev)
    for gname, y in FLATS.get(fam, {}).items():
        for r in conn[gname]:
            for v in r:
                circ_dev = max(circ_dev, abs(xy[v][1] - y))
    if circ_dev > 1e-9:
        errors.append(f"arc node off circle (or flat face off its line) by {circ_dev:.3e}")
    if straight and curved_edges:
        errors.append(f"{curved_edges} curved edges in straight-edged mesh")

    # boundary line elements: mid node should be the 3rd node
    if not first_order:
        for gname, rows in conn.items():
            if groups[gname][0] != 1:
                continue
            for r in rows:
                (x0, y0), (x1, y1), (xm, ym) = xy[r[0]], xy[r[1]], xy[r[2]]
                L = math.hypot(x1 - x0, y1 - y0)
                if math.hypot(xm - 0.5 * (x0 + x1), ym - 0.5 * (y0 + y1)) > 0.25 * L:
                    errors.append(f"line element node order in {gname}")
                    break

    # edge lengths along the arcs for |x| <= 1.5 a
    arc_h = {}
    if fam in ("vm272", "pad_flat"):
        xs = desc.get("xs", XS)
        for gname in ("lower_arc", "upper_arc"):
            ls = [math.hypot(xy[r[0]][0] - xy[r[1]][0], xy[r[0]][1] - xy[r[1]][1])
                  for r in conn[gname]
                  if abs(xy[r[0]][0]) <= xs + 1e-9 and abs(xy[r[1]][0]) <= xs + 1e-9]
            arc_h[gname] = (min(ls), max(ls), len(ls))
    gmsh.finalize()

    with open(os.path.join(HERE, out), "rb") as f:
        f.readline()
        hdr = f.readline().split()
    fmt = f"MSH {hdr[0].decode()} {'binary' if hdr[1] == b'1' else 'ASCII'}"
    return {
        "fmt": fmt, "file": out, "nodes": len(xy), "tri": ntri, "groups": groups,
        "bytes": os.path.getsize(os.path.join(HERE, out)), "errors": errors,
        "arc_h": arc_h, "circ_dev": circ_dev, "curved_edges": curved_edges,
        "h": desc["h"], "note": desc["note"],
    }


def fmt_groups(groups):
    return ", ".join(f'"{n}"=({d},{t})' for n, (d, t) in sorted(groups.items(), key=lambda x: (x[1][0], x[1][1])))


def main():
    sel = sys.argv[1:]
    version = gmsh.__version__
    print(f"gmsh {version}")
    results = []
    for out, geo, params, opts, desc in JOBS:
        if sel and not any(out.startswith(s) for s in sel):
            continue
        if not sel and out in ON_DEMAND:
            continue
        if sel and out in ON_DEMAND and not any(out.startswith(s) and len(s) >= len("vm272_L6") for s in sel):
            continue
        make(out, geo, params, opts)
        res = check(out, desc)
        results.append(res)
        line = (f"{out:26s} {res['fmt']:16s} h={res['h']:.6g} nodes={res['nodes']:7d} tri={res['tri']:6d} "
                f"size={res['bytes'] / 1e6:7.3f}MB")
        if res["arc_h"]:
            line += "  " + "  ".join(
                f"{g}: n={n} h=[{lo:.6g},{hi:.6g}]" for g, (lo, hi, n) in res["arc_h"].items())
        if res["circ_dev"]:
            line += f"  circle_dev={res['circ_dev']:.1e}"
        print(line)
        print(f"    groups (dim,tag): {fmt_groups(res['groups'])}")
        for e in res["errors"]:
            print(f"    ERROR: {e}")
    if any(r["errors"] for r in results):
        print("VERIFICATION FAILED")
        sys.exit(1)
    if not sel:
        write_readme(results, version)
    total = sum(r["bytes"] for r in results)
    print(f"all checks passed; total size {total / 1e6:.2f} MB")


SCENE_SECTION = """
## Scene generator (`scene.py`)

`scene.py` makes a contact scene on demand instead of a fixed file (it is not run by
`generate.py`, and its meshes are not committed): two cylinders of radii R1 != R2, or a
cylinder on a flat (`--flat`, R2 = infinity), sized from the scene. `tests/scenes.rs` meshes
every scene it draws with it.

    python3 meshes/scene.py --r1 10 --r2 15 --a 0.2 --lambda 0.04 --out scene.msh

* Bodies: `upper_body` = body 1, the cylinder R1 under the pilot (the part of the disc centred
  at (0, R1) below y = D1; `top` at y = D1); `lower_body` = body 2, the cylinder R2 (the part of
  the disc centred at (0, -R2) above y = -D2) or the flat [-2D2, 2D2] x [-D2, 0], held on
  `bottom` at y = -D2. Contact faces `upper_arc` and `lower_arc` (the flat's top face); the
  bodies touch at the origin and share no node. Group names and tags as in `vm272.geo`.
* Sizing: the Hertz semi-width a is `--a`, or follows from `--load` and `--e1 --nu1 --e2 --nu2`
  (plane strain, 1/R = 1/R1 + 1/R2); s0 is `--s0`, or 2 Lambda a/pi from `--lambda`. Along both
  faces h = min(a/24, 0.97 s0/2) for |x| <= 1.5a (`--fine-factor`), growing as h + 0.15 d up to
  depth/6 away from it. Each body is a circular segment of depth D = min(R, 20a) (a half-disc when
  R <= 20a). Measured (identical bodies, h = a/24): depth 20a puts a within 0.04 % and p0 within
  0.1 % of Hertz (5a: -1.9 %, +1.4 %; 10a: -0.2 %, +0.3 %; 80a: +0.07 %, +0.01 %). With
  h = a/24 a node sits at x = +-a (to 1e-4 a), which makes the FE's a unusually exact; with
  other h its edge extrapolation is off by up to 0.35 % (tests/scenes.rs).
* Every size can be set directly: `--h-contact`, `--x-fine`, `--depth`, `--growth`, `--h-far`;
  also `--per-a`, `--per-s0`, `--depth-factor`, `--order 1|2`, `--ascii`, and `--json` (prints
  the sizes used, node and triangle counts and the chord range along the fine zone).
* The written file is re-opened and checked as above (groups, element types, orientation,
  face nodes on their circle or line, no shared node); output is deterministic.

## Two cylinders (`two_cylinders.py`)

The worked example of "Bring your own mesh" in the top-level README: two half-cylinders of
radii 12 mm (`lower_body`) and 5 mm (`upper_body`), sized for the Hertz semi-width of
`cases/own_mesh.json` (a = 0.3197 mm, h = a/20 over |x| <= 1.5a), with the groups of the VM272
meshes. Its docstring lists what stickslip needs from a mesh. It is not run by `generate.py`
and its mesh is not committed: `python3 meshes/two_cylinders.py` writes
`meshes/two_cylinders.msh` (options `--r-lower --r-upper --a --per-a --growth --out`), and
`tests/own_mesh.rs` builds it and runs the case.
"""


def write_readme(results, version):
    rows = []
    for r in results:
        arc = ""
        if r["arc_h"]:
            lo = min(v[0] for v in r["arc_h"].values())
            hi = max(v[1] for v in r["arc_h"].values())
            n = r["arc_h"]["lower_arc"][2]
            arc = f"{n} / [{lo:.4g}, {hi:.4g}]"
        rows.append(f"| `{r['file']}` | {r['h']:.6g} | {r['nodes']} | {r['tri']} | {arc} | "
                    f"{r['bytes'] / 1e6:.2f} MB | {r['fmt']} | {r['note']} |")
    groups = {}
    for r in results:
        groups.setdefault(family(r["file"]), fmt_groups(r["groups"]))
    text = f"""# Meshes

All meshes are generated from the `.geo` sources in this directory by

    python3 meshes/generate.py

(gmsh Python API, `pip install gmsh`; these files were produced with **gmsh {version}**).
The script re-opens every written file and checks: physical names, element types
(9 = 6-node triangle, 8 = 3-node line; 2/1 for the first-order file), no orphan nodes,
counter-clockwise corner ordering of every triangle, mid-edge nodes of the arcs on the
circle (|r - R| < 1e-9), the straight contact faces on their line, the two bodies of
the two-body meshes share no node, and for `lame_straight_*`
all mid-edge nodes at chord midpoints. Output is deterministic (1 thread, fixed seed).

Format: MSH 4.1 (binary where stated, little-endian, 8-byte size_t tags), except
`vm272_L0_msh22.msh` (MSH 2.2 ASCII). Only elements of physical groups are saved.
Binary MSH 4.1 layout (as written by gmsh {version}): header line `4.1 1 8`, then a binary
int 1 (endianness check) and a newline; `$PhysicalNames` stays ASCII; `$Entities` counts are
size_t (u64), entity tags/physical tags/bounding tags are i32, boxes/coords f64; `$Nodes`
starts with 4 u64 (numBlocks, numNodes, minTag, maxTag), and each block has i32 dim, i32 tag,
i32 parametric (always 0 here), u64 n, then n u64 tags followed by n*(x,y,z) f64;
`$Elements` starts with 4 u64, and each block has i32 dim, i32 tag, i32 type, u64 n, then
per element u64 tag + u64 node tags. Each binary section ends with a newline before `$End...`. `$Entities`
also lists the (unmeshed, untagged) circle-centre points; nodes of corner points appear in
dim-0 node blocks although the points carry no physical tag. Node and element tags are
contiguous from 1.
Node order (gmsh convention): 6-node triangle = 3 corners (counter-clockwise), then
mid-nodes of edges 0-1, 1-2, 2-0; 3-node line = 2 end nodes, then the mid node.

Physical groups, `"name"=(dim,tag)`:

""" + "\n".join(f"- {fam}: {g}" for fam, g in groups.items()) + f"""

VM272 (`vm272.geo`): R = 8 mm, a = {A} mm; each arc split at |x| = 1.5a and at the contact
point (0, 8) (one copy per body). Size h = min(1, h_c + 0.05 d), d = distance to the
central arcs (|x| <= 1.5a), capped at R/8. Ladder h_c = a/(3.2*2^L), so L5 has h_c <= a/100. "arc edges" = number of 3-node line
elements of `lower_arc` with |x| <= 1.5a and min/max chord length there (both arcs).

Pad on flat (`pad_flat.geo`, the material-pair cases of docs/material_pairs.md): a cylindrical
pad of radius R = 25 mm (`upper_body`, lower half of the disc centred at (0, 35), flat face
`top` at y = 35) on a flat specimen 50 mm x 10 mm (`lower_body`, `bottom` at y = 0); the
contact faces are `upper_arc` and the straight top face of the flat, named `lower_arc` like
the VM272 meshes so the cases look alike. Size h = min(2.5, h_c + 0.1 d), d = distance to the
central pieces |x| <= x_f of the two contact faces. For these files "arc edges" counts the
edges with |x| <= x_f (0.16 mm for `pad_flat.msh`, 0.016 mm for `pad_flat_lead.msh`).

Two blocks (`blocks.geo`, the rupture case `cases/rupture_pmma.json`): identical rectangles
1200 mm x 600 mm, `lower_block` below y = 0 (held on `bottom`) and `upper_block` above it
(`top` at y = 600, the pilot), each with its own interface line (`lower_face`, `upper_face`)
and lateral sides (`lower_left`, `lower_right`, `upper_left`, `upper_right`) for side
tractions. Size h_i within a band of height h_i along the interface over |x| <= 220 mm,
growing at 0.2 per unit distance to 50 mm. `blocks_h05.msh` (h_i = 0.5 mm, 8 MB) is made on
demand only (`python3 meshes/generate.py blocks_h05`, as tests/rupture.rs does).

| file | h_c or h (mm) | nodes | triangles | arc edges / chord range | size | format | notes |
|---|---|---|---|---|---|---|---|
""" + "\n".join(rows) + "\n" + SCENE_SECTION
    with open(os.path.join(HERE, "README.md"), "w") as f:
        f.write(text)


if __name__ == "__main__":
    main()
