#!/usr/bin/env python3
"""CalculiX 2.20 reference solution of the VM272 frictional Hertz problem on the project's meshes.

For every requested mesh level k this script
  1. converts meshes/vm272_L{k}.msh (MSH 4.1, 6-node triangles) into a CalculiX deck
     (CPE6 plane strain, E = 200, nu = 0.3, thickness 1; bottom fixed; the top face tied by
     *EQUATION to one of its nodes, the "pilot", so that it translates rigidly without
     rotating; penalty face-to-face contact with Coulomb friction mu = 0.2 between the arcs
     within |x| <= 1.5a, slave = lower arc);
  2. runs `ccx` (OMP_NUM_THREADS = CCX_NPROC_EQUATION_SOLVER = --threads) and times it;
  3. reads the contact pressure and shear at the slave nodes from the .frd file
     (*CONTACT FILE, CSTR/CDIS) at the end of the normal-load step and of the tangential step;
  4. scores them against the half-space closed forms (Hertz, Cattaneo-Mindlin) of
     docs/reference.md;
  5. writes <out>/L{k}/contact_L{k}.csv (x, p, q, status, ... per slave node and step) and
     appends one JSON object per run to <out>/results.jsonl (also printed on stdout).

Load steps (see docs/calculix.md):
  step 1: pilot uy = -delta0 (prescribed, tiny) with ux = 0: closes the point contact so the
          upper body is held before any force is applied;
  step 2: uy released, Fy = -P = -10 N/mm ramped on the pilot (force control), ux = 0 held;
  step 3: ux released, Fx = +Q = 0.936 N/mm ramped, Fy = -P held.
"Step 1 / step 2" of the problem statement are this script's ccx steps 2 and 3.

If `ccx` is not on PATH, prints a message and the JSON {"skipped": "ccx not found"}, exits 0.

Usage:
    python3 post/calculix/ccx_vm272.py --levels 0,1,2,3 --threads 2 --out out/calculix
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import re
import shutil
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from msh41 import group_conn, read_msh41  # noqa: E402

# ---------------------------------------------------------------- problem data (vm272.md)
R = 8.0
E_MOD = 200.0
NU = 0.3
P_LOAD = 10.0
Q_LOAD = 0.936
MU = 0.2
E_STAR = E_MOD / (2.0 * (1.0 - NU**2))
R_EFF = R / 2.0
A_HZ = np.sqrt(4.0 * P_LOAD * R_EFF / (np.pi * E_STAR))  # 0.6808 mm
P0 = 2.0 * P_LOAD / (np.pi * A_HZ)  # 9.351 N/mm^2
C_CM = A_HZ * np.sqrt(1.0 - Q_LOAD / (MU * P_LOAD))  # 0.4965 mm
A_GEO = 0.6808  # the a used by meshes/vm272.geo to split the arcs at |x| = 1.5 a

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))


# ---------------------------------------------------------------- closed forms
def p_hertz(x):
    x = np.asarray(x, dtype=float)
    return P0 * np.sqrt(np.clip(1.0 - (x / A_HZ) ** 2, 0.0, None))


def q_cm(x):
    """Cattaneo-Mindlin shear (positive, along +x, the direction of Q on the upper body)."""
    x = np.asarray(x, dtype=float)
    q = MU * p_hertz(x)
    inner = np.abs(x) < C_CM
    q[inner] = MU * P0 / A_HZ * (np.sqrt(A_HZ**2 - x[inner] ** 2) - np.sqrt(C_CM**2 - x[inner] ** 2))
    return q


# ---------------------------------------------------------------- deck
def _face_lookup(tris):
    """Map a sorted corner pair to (element index, CalculiX face id S1..S3)."""
    look = {}
    for e, t in enumerate(tris):
        for fid, (i, j) in enumerate(((0, 1), (1, 2), (2, 0)), start=1):
            key = (min(t[i], t[j]), max(t[i], t[j]))
            look[key] = (e, fid, t[[i, j]], t[3 + fid - 1])
    return look


def _arc_faces(nodes, arc, tris, elem_offset, xmax):
    """Element faces (elem id, S#) of `tris` lying on the arc line elements with |x| <= xmax."""
    look = _face_lookup(tris)
    faces = []
    for ln in arc:
        if np.max(np.abs(nodes[ln, 0])) > xmax + 1e-9:
            continue
        key = (min(ln[0], ln[1]), max(ln[0], ln[1]))
        if key not in look:
            raise ValueError(f"arc edge {ln} is not an edge of any triangle of its body")
        e, fid, _, mid = look[key]
        if mid != ln[2]:
            raise ValueError(f"arc edge {ln}: mid node differs from the triangle's ({mid})")
        faces.append((e + 1 + elem_offset, fid))
    return faces


def _fmt_ids(ids, per_line=16):
    ids = list(ids)
    return "\n".join(", ".join(str(i) for i in ids[k:k + per_line])
                     for k in range(0, len(ids), per_line))


def build_deck(mesh_path, deck_path, penalty, stick_slope, delta0, inc1, inc2, contact_xmax):
    """Write the CalculiX deck; return a dict of facts about it."""
    mesh = read_msh41(mesh_path)
    nodes = mesh.nodes
    lower = group_conn(mesh, "lower_body", 9)
    upper = group_conn(mesh, "upper_body", 9)
    bottom = np.unique(group_conn(mesh, "bottom", 8))
    top = np.unique(group_conn(mesh, "top", 8))
    lower_arc = group_conn(mesh, "lower_arc", 8)
    upper_arc = group_conn(mesh, "upper_arc", 8)

    # gmsh 6-node triangle: corners (CCW), mid 0-1, 1-2, 2-0 -- the same order as CalculiX
    # CPE6 (corners 1-3, mid-nodes 4 = 1-2, 5 = 2-3, 6 = 3-1). Check the orientation anyway.
    for name, t in (("lower_body", lower), ("upper_body", upper)):
        p = nodes[t[:, :3], :2]
        area2 = ((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1])
                 - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1]))
        if (area2 <= 0).any():
            raise ValueError(f"{name}: {int((area2 <= 0).sum())} triangles not counter-clockwise")
    if not (np.allclose(nodes[bottom, 1], 0.0) and np.allclose(nodes[top, 1], 2 * R)):
        raise ValueError("bottom/top groups are not on y = 0 / y = 2R")

    n_low = len(lower)
    slave = _arc_faces(nodes, lower_arc, lower, 0, contact_xmax)
    master = _arc_faces(nodes, upper_arc, upper, n_low, contact_xmax)
    slave_nodes = np.unique(lower_arc[np.max(np.abs(nodes[lower_arc, 0]), axis=1)
                                      <= contact_xmax + 1e-9])
    master_edges = upper_arc[np.max(np.abs(nodes[upper_arc, 0]), axis=1) <= contact_xmax + 1e-9]
    arc_nodes = np.unique(np.concatenate([slave_nodes, master_edges.ravel()]))

    # pilot: the top node nearest to (0, 2R); every other top node's ux, uy equal the pilot's
    pilot = int(top[np.argmin(np.abs(nodes[top, 0]))])
    tied = [int(n) for n in top if n != pilot]

    used = np.unique(np.concatenate([lower.ravel(), upper.ravel()]))
    out = []
    w = out.append

    def end_step_with_output():
        # The same requests close both loaded steps: pilot displacement, bottom reaction
        # total, arc displacements, contact stresses and displacements.
        for line in ("*NODE PRINT, NSET=PILOT, FREQUENCY=100000", "U",
                     "*NODE PRINT, NSET=BOTTOM, TOTALS=ONLY", "RF",
                     "*NODE PRINT, NSET=ARCN", "U",
                     "*CONTACT FILE", "CSTR, CDIS",
                     "*CONTACT PRINT", "CSTR",
                     "*END STEP"):
            w(line)
    w("** VM272 frictional Hertz contact, generated by post/calculix/ccx_vm272.py")
    w(f"** mesh: {os.path.relpath(mesh_path, REPO)}")
    w("*NODE, NSET=NALL")
    for n in used:
        w(f"{n}, {nodes[n, 0]:.15g}, {nodes[n, 1]:.15g}, 0")
    for name, conn, off in (("LOWER", lower, 0), ("UPPER", upper, n_low)):
        w(f"*ELEMENT, TYPE=CPE6, ELSET={name}")
        for e, c in enumerate(conn):
            w(f"{e + 1 + off}, " + ", ".join(str(int(v)) for v in c))
    w("*NSET, NSET=BOTTOM")
    w(_fmt_ids(bottom))
    w("*NSET, NSET=PILOT")
    w(str(pilot))
    w("*NSET, NSET=ARCN")
    w(_fmt_ids(arc_nodes))
    w("*SURFACE, NAME=SLAVE, TYPE=ELEMENT")
    for e, f in slave:
        w(f"{e}, S{f}")
    w("*SURFACE, NAME=MASTER, TYPE=ELEMENT")
    for e, f in master:
        w(f"{e}, S{f}")
    w("*MATERIAL, NAME=ELAST")
    w("*ELASTIC")
    w(f"{E_MOD}, {NU}")
    w("*SOLID SECTION, ELSET=LOWER, MATERIAL=ELAST")
    w("1.")
    w("*SOLID SECTION, ELSET=UPPER, MATERIAL=ELAST")
    w("1.")
    # rigid, non-rotating top face: u_i - u_pilot = 0 for dofs 1, 2 of every other top node
    w("*EQUATION")
    for n in tied:
        for dof in (1, 2):
            w("2")
            w(f"{n}, {dof}, 1., {pilot}, {dof}, -1.")
    w("*SURFACE INTERACTION, NAME=FRIC")
    w("*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR")
    w(f"{penalty:.6g}")
    w("*FRICTION")
    w(f"{MU}, {stick_slope:.6g}")
    w("*CONTACT PAIR, INTERACTION=FRIC, TYPE=SURFACE TO SURFACE")
    w("SLAVE, MASTER")

    # ccx step 1: close the point contact by a tiny prescribed approach of the pilot
    w("** ---- step 1: prescribed approach delta0 of the pilot (closes the point contact)")
    w("*STEP, INC=1000")
    w("*STATIC")
    w("1., 1.")
    w("*BOUNDARY")
    w("BOTTOM, 1, 2")
    w("PILOT, 1, 1, 0.")
    w(f"PILOT, 2, 2, {-delta0:.6g}")
    w("*END STEP")
    # ccx step 2: force control, normal load
    w("** ---- step 2: normal load P on the pilot (force control), ux of the pilot held")
    w("*STEP, INC=1000")
    w("*STATIC")
    w(f"{inc1[0]:.6g}, 1., {inc1[1]:.6g}, {inc1[2]:.6g}")
    w("*BOUNDARY, OP=NEW")
    w("BOTTOM, 1, 2")
    w("PILOT, 1, 1, 0.")
    w("*CLOAD")
    w(f"PILOT, 2, {-P_LOAD}")
    end_step_with_output()
    # ccx step 3: tangential load
    w("** ---- step 3: tangential load Q on the pilot, normal load held")
    w("*STEP, INC=1000")
    w("*STATIC")
    w(f"{inc2[0]:.6g}, 1., {inc2[1]:.6g}, {inc2[2]:.6g}")
    w("*BOUNDARY, OP=NEW")
    w("BOTTOM, 1, 2")
    w("*CLOAD")
    w(f"PILOT, 1, {Q_LOAD}")
    w(f"PILOT, 2, {-P_LOAD}")
    end_step_with_output()
    with open(deck_path, "w") as fh:
        fh.write("\n".join(out) + "\n")
    return {
        "elements": int(len(lower) + len(upper)),
        "nodes": int(len(used)),
        "slave_faces": len(slave),
        "master_faces": len(master),
        "slave_nodes": slave_nodes,
        "master_edges": master_edges,
        "pilot": pilot,
        "tied_top_nodes": len(tied),
        "node_xy": nodes[:, :2],
    }


# ---------------------------------------------------------------- frd reading
def read_frd_contact(path):
    """Return a list of (step, increment, time, {node: (copen, cslip1, cslip2, cpress, cshear1,
    cshear2)}) for every CONTACT block of an ASCII .frd file."""
    blocks = []
    cur = None
    step = inc = 0
    t = 0.0
    with open(path) as fh:
        for line in fh:
            if line.startswith("    1PSTEP"):
                parts = line.split()
                inc, step = int(parts[2]), int(parts[3])
            elif line.startswith("  100C"):
                t = float(line[12:24])
            elif line.startswith(" -4  CONTACT"):
                cur = {}
                blocks.append((step, inc, t, cur))
            elif line.startswith(" -4"):
                cur = None
            elif cur is not None and line.startswith(" -1"):
                nid = int(line[3:13])
                vals = [float(line[13 + 12 * k:25 + 12 * k]) for k in range(6)]
                cur[nid] = vals
            elif line.startswith(" -3"):
                cur = None
    return blocks


def read_dat_blocks(path):
    """Blocks of the .dat file: list of (title, time, {node: [values]}) for node-wise blocks."""
    blocks = []
    cur = None
    with open(path) as fh:
        for line in fh:
            s = line.strip()
            if not s:
                continue
            m = re.match(r"(.+?) for set (\S+) and time\s+(\S+)", s)
            if m:
                cur = {}
                blocks.append((f"{m.group(1)} {m.group(2)}", float(m.group(3)), cur))
                continue
            if re.match(r"[a-z]", s):
                cur = None
                continue
            if cur is not None:
                v = s.split()
                try:
                    cur[int(v[0])] = [float(t) for t in v[1:]]
                except ValueError:
                    cur = None
    return blocks


def _quad_edge(xi, X):
    """Point and tangent of a 3-node edge (end, end, mid) at xi in [-1, 1]."""
    n = np.array([0.5 * xi * (xi - 1.0), 0.5 * xi * (xi + 1.0), 1.0 - xi * xi])
    dn = np.array([xi - 0.5, xi + 0.5, -2.0 * xi])
    return n @ X, dn @ X


def overlap_at_slave_nodes(xy, disp, slave_nodes, master_edges):
    """Normal overlap (> 0: penetration) of every slave node into the deformed master arc,
    measured along the master's outward normal at the closest-point projection."""
    pos = {int(n): xy[n] + np.asarray(disp[int(n)][:2]) for n in
           np.unique(np.concatenate([slave_nodes, master_edges.ravel()]))}
    edges = [np.array([pos[int(a)], pos[int(b)], pos[int(c)]]) for a, b, c in master_edges]
    centres = np.array([e.mean(axis=0) for e in edges])
    out = np.zeros(len(slave_nodes))
    for k, sn in enumerate(slave_nodes):
        xs = pos[int(sn)]
        best = None
        for j in np.argsort(np.linalg.norm(centres - xs, axis=1))[:4]:
            X = edges[j]
            xi = 0.0
            for _ in range(30):
                p, t = _quad_edge(xi, X)
                dd = np.array([1.0, 1.0, -2.0]) @ X  # second derivative of the edge
                f = (p - xs) @ t
                df = t @ t + (p - xs) @ dd
                step = f / df
                xi -= step
                if abs(step) < 1e-14:
                    break
            xi = min(1.0, max(-1.0, xi))
            p, t = _quad_edge(xi, X)
            d = np.linalg.norm(p - xs)
            if best is None or d < best[0]:
                nrm = np.array([t[1], -t[0]]) / np.linalg.norm(t)
                if nrm[1] > 0:  # outward normal of the upper body points down
                    nrm = -nrm
                best = (d, -(xs - p) @ nrm)
        out[k] = best[1]
    return out


# ---------------------------------------------------------------- scoring
def score(x, p, q, x_all_contact):
    """Error measures of one step; x, p, q at slave nodes (q along +x on the upper body)."""
    res = {}
    sel = np.abs(x) <= 0.95 * A_HZ
    ep = np.abs(p[sel] - p_hertz(x[sel])) / P0
    res["p_err_max"] = float(ep.max())
    res["p_err_rms"] = float(np.sqrt(np.mean(ep**2)))
    res["n_scored"] = int(sel.sum())
    inc = p > 0.0
    res["a_fe"] = float(np.max(np.abs(x[inc]))) if inc.any() else 0.0
    res["a_fe_over_a"] = res["a_fe"] / A_HZ
    res["p_max"] = float(p.max())
    res["p_max_over_p0"] = float(p.max() / P0)
    res["x_all_contact"] = x_all_contact
    return res


def score_shear(x, p, q, h_arc, slip_tol):
    res = {}
    sel = np.abs(x) <= 0.95 * A_HZ
    eq = np.abs(q[sel] - q_cm(x[sel])) / (MU * P0)
    res["q_err_max"] = float(eq.max())
    res["q_err_rms"] = float(np.sqrt(np.mean(eq**2)))
    far = sel & (np.abs(np.abs(x) - C_CM) > 2.0 * h_arc)
    eqf = np.abs(q[far] - q_cm(x[far])) / (MU * P0)
    res["q_err_max_excl_c"] = float(eqf.max())
    res["q_err_rms_excl_c"] = float(np.sqrt(np.mean(eqf**2)))
    res["n_scored_excl_c"] = int(far.sum())
    # stick: in contact and |q| < mu p (1 - slip_tol)
    stick = (p > 0.0) & (np.abs(q) < MU * p * (1.0 - slip_tol))
    res["c_fe"] = float(np.max(np.abs(x[stick]))) if stick.any() else 0.0
    res["c_fe_over_a"] = res["c_fe"] / A_HZ
    res["c_err_rel"] = (res["c_fe"] - C_CM) / C_CM
    return res


def status_of(p, q, slip_tol):
    st = np.where(p > 0.0, np.where(np.abs(q) < MU * p * (1.0 - slip_tol), "stick", "slip"),
                  "open")
    return st


# ---------------------------------------------------------------- ccx output parsing
def parse_ccx_log(text):
    info = {}
    m = re.findall(r"Total CalculiX Time:\s*([0-9.Ee+-]+)", text)
    if m:
        info["ccx_total_time_reported_s"] = float(m[-1])
    # ccx 2.20 prints no per-phase timing; the .sta file gives increments and iterations
    # size of the linear system ccx solves (the expanded plane-strain model, after its MPCs)
    eqs = re.findall(r"number of equations\s+(\d+)", text)
    if eqs:
        info["equations"] = max(int(v) for v in eqs)
    info["iterations"] = len(re.findall(r"iteration\s+\d+", text))
    info["increments"] = len(re.findall(r"increment\s+\d+\s+attempt", text))
    info["cutbacks"] = len(re.findall(r"attempt\s+[2-9]", text))
    return info


def parse_sta(path):
    """Per-step counts of increments and iterations from the .sta file."""
    out = {}
    if not os.path.exists(path):
        return out
    with open(path) as fh:
        for line in fh:
            v = line.split()
            if len(v) >= 6 and v[0].isdigit() and v[1].isdigit():
                s = int(v[0])
                d = out.setdefault(s, {"increments": 0, "attempts": 0, "iterations": 0})
                d["increments"] += 1
                d["attempts"] += int(re.sub(r"\D", "", v[2]) or 1)
                d["iterations"] += int(v[3])
    return out


# ---------------------------------------------------------------- one run
def run_level(level, args):
    mesh_path = os.path.join(args.meshdir, f"vm272_L{level}.msh")
    wdir = os.path.join(args.out, f"L{level}")
    os.makedirs(wdir, exist_ok=True)
    job = f"vm272_L{level}"
    deck = os.path.join(wdir, job + ".inp")
    facts = build_deck(mesh_path, deck, args.penalty, args.stick_slope, args.delta0,
                       (args.inc1[0], args.inc1[1], args.inc1[2]),
                       (args.inc2[0], args.inc2[1], args.inc2[2]), args.contact_xmax * A_GEO + 1e-6)
    for ext in (".frd", ".dat", ".sta", ".cvg"):
        if os.path.exists(os.path.join(wdir, job + ext)):
            os.remove(os.path.join(wdir, job + ext))
    env = dict(os.environ)
    env["OMP_NUM_THREADS"] = str(args.threads)
    env["CCX_NPROC_EQUATION_SOLVER"] = str(args.threads)
    cmd = [args.ccx, "-i", job]
    stdbuf = shutil.which("stdbuf") if args.profile else None
    if stdbuf:  # unbuffered stdout so that each log line can be time-stamped
        cmd = [stdbuf, "-o0"] + cmd
    phases = {}
    t0 = time.perf_counter()
    with open(os.path.join(wdir, job + ".log"), "w") as log:
        proc = subprocess.Popen(cmd, cwd=wdir, env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True, bufsize=1)
        last_t, last_phase = 0.0, "other"
        for line in proc.stdout:
            t = time.perf_counter() - t0
            log.write(line)
            if time.perf_counter() - t0 > args.timeout:
                proc.kill()
                raise subprocess.TimeoutExpired(cmd, args.timeout)
            s = line.strip()
            if not s:
                continue
            phases[last_phase] = phases.get(last_phase, 0.0) + (t - last_t)
            last_t = t
            low = s.lower()
            if "for spooles" in low or "for pardiso" in low or "for pastix" in low:
                last_phase = "linear_solver_factor_solve"
            elif "symmetric stiffness" in low and "asymmetric" not in low:
                last_phase = "stiffness_assembly_symmetric"
            elif "asymmetric stiffness" in low:
                last_phase = "stiffness_assembly_asymmetric"
            elif "stress calculation" in low:
                last_phase = "stress_and_contact_forces"
            elif "structure of the matrix" in low:
                last_phase = "matrix_structure"
            else:
                last_phase = "other"
        # wait4 rather than wait: the child's own resource usage gives ccx's peak memory
        # (stdbuf execs ccx, so the child is ccx itself)
        _, wstatus, rusage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(wstatus)
    wall = time.perf_counter() - t0
    phases[last_phase] = phases.get(last_phase, 0.0) + (wall - last_t)
    with open(os.path.join(wdir, job + ".log")) as fh:
        logtext = fh.read()
    rec = {
        "code": "calculix",
        "ccx_version": args.ccx_version,
        "mesh": os.path.relpath(mesh_path, REPO),
        "level": level,
        "elements": facts["elements"],
        "nodes": facts["nodes"],
        "slave_faces": facts["slave_faces"],
        "master_faces": facts["master_faces"],
        "threads": args.threads,
        "wall_time_s": round(wall, 3),
        "peak_memory_mib": round(rusage.ru_maxrss / 1024.0, 1),  # ru_maxrss is in KiB on Linux
        "ccx_returncode": proc.returncode,
        "penalty": args.penalty,
        "stick_slope": args.stick_slope,
        "delta0": args.delta0,
        "inc_normal": args.inc1,
        "inc_tangential": args.inc2,
        "slip_tol": args.slip_tol,
        "deck": os.path.relpath(deck, REPO) if deck.startswith(REPO) else deck,
    }
    rec.update(parse_ccx_log(logtext))
    if stdbuf:
        rec["time_breakdown_s"] = {k: round(v, 2) for k, v in
                                   sorted(phases.items(), key=lambda kv: -kv[1])}
    rec["sta"] = parse_sta(os.path.join(wdir, job + ".sta"))
    if rec.get("iterations"):
        rec["wall_per_iteration_s"] = round(wall / rec["iterations"], 4)
    frd = os.path.join(wdir, job + ".frd")
    ok = proc.returncode == 0 and "Job finished" in logtext and os.path.exists(frd)
    if not ok:
        rec["status"] = "ccx failed"
        rec["log_tail"] = logtext[-2000:]
        return rec
    blocks = read_frd_contact(frd)
    last = {}
    for step, inc, t, data in blocks:
        last[step] = data  # the last block of each step = end of the step
    if 2 not in last or 3 not in last:
        rec["status"] = f"missing contact output (steps with output: {sorted(last)})"
        return rec

    dat = read_dat_blocks(os.path.join(wdir, job + ".dat"))
    disp = {}
    for title, t, d in dat:
        if title.startswith("displacements") and title.endswith("ARCN"):
            disp[2 if t <= 2.0 + 1e-9 else 3] = d
        if title.startswith("displacements") and title.endswith("PILOT"):
            rec[f"pilot_u_step{2 if t <= 2.0 + 1e-9 else 3}"] = list(d.values())[0][:2]
    xy = facts["node_xy"]
    sn = facts["slave_nodes"]
    x = xy[sn, 0]
    order = np.argsort(x)
    sn, x = sn[order], x[order]
    # arc edge length in the refined zone (chord of two adjacent corner-to-corner nodes)
    h_arc = float(np.median(np.diff(x)) * 2.0)
    rec["h_arc"] = h_arc
    csv_path = os.path.join(wdir, f"contact_L{level}.csv")
    rows = []
    for stepname, step in (("normal", 2), ("tangential", 3)):
        d = last[step]
        vals = np.array([d.get(int(n), [0.0] * 6) for n in sn])
        p = vals[:, 3]
        # CSHEAR1 = shear exerted by the slave (lower) on the master (upper) surface along the
        # master's first tangent, the projection of +x on the master arc. It resists Q, i.e. it
        # points along -x; the shear exerted on the lower body, along +x, is q = -CSHEAR1.
        q = -vals[:, 4]
        st = status_of(p, q, args.slip_tol)
        res = score(x, p, q, bool(facts["slave_faces"] > 0))
        res.pop("x_all_contact")
        # pressure recovered at the nodes from the displacements: K * overlap
        ov = overlap_at_slave_nodes(xy, disp[step], sn, facts["master_edges"])
        p_rec = args.penalty * np.clip(ov, 0.0, None)
        rec_res = score(x, p_rec, q, True)
        for key in ("p_err_max", "p_err_rms", "a_fe", "a_fe_over_a", "p_max_over_p0"):
            res[key + "_from_u"] = rec_res[key]
        if stepname == "tangential":
            res.update(score_shear(x, p, q, h_arc, args.slip_tol))
        res["missing_nodes"] = int(sum(int(n) not in d for n in sn))
        rec[stepname] = res
        for n, xi, pi, qi, si, v, pr in zip(sn, x, p, q, st, vals, p_rec):
            rows.append((stepname, int(n), xi, pi, qi, si, v[0], v[1], pr))
    with open(csv_path, "w", newline="") as fh:
        wr = csv.writer(fh)
        wr.writerow(["step", "node", "x", "p", "q", "status", "copen", "cslip1", "p_from_u"])
        for r in rows:
            wr.writerow([r[0], r[1], f"{r[2]:.9g}", f"{r[3]:.9g}", f"{r[4]:.9g}", r[5],
                         f"{r[6]:.6g}", f"{r[7]:.6g}", f"{r[8]:.9g}"])
    rec["csv"] = os.path.relpath(csv_path, REPO) if csv_path.startswith(REPO) else csv_path
    rec["status"] = "ok"
    if not args.keep:
        for name in (job + ".frd", job + ".12d", "spooles.out"):
            if os.path.exists(os.path.join(wdir, name)):
                os.remove(os.path.join(wdir, name))
    return rec


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--levels", default="0,1,2,3", help="comma-separated mesh levels")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=os.path.join(REPO, "out", "calculix"))
    ap.add_argument("--meshdir", default=os.path.join(REPO, "meshes"))
    ap.add_argument("--ccx", default="ccx", help="ccx executable")
    ap.add_argument("--penalty", type=float, default=1.0e5,
                    help="normal penalty slope K (N/mm^3) of PRESSURE-OVERCLOSURE=LINEAR")
    ap.add_argument("--stick-slope", type=float, default=1.0e4,
                    help="stick slope lambda (N/mm^3) of *FRICTION")
    ap.add_argument("--delta0", type=float, default=1.0e-3,
                    help="prescribed pilot approach (mm) of ccx step 1 that closes the contact")
    ap.add_argument("--inc1", default="0.1,1e-5,0.1",
                    help="normal step: initial, minimum, maximum increment (fractions of P)")
    ap.add_argument("--inc2", default="0.05,1e-5,0.05",
                    help="tangential step: initial, minimum, maximum increment (fractions of Q)")
    ap.add_argument("--contact-xmax", type=float, default=1.5,
                    help="contact surfaces cover arc edges with |x| <= this * a")
    ap.add_argument("--slip-tol", type=float, default=0.02,
                    help="a slave node sticks if p > 0 and |q| < mu p (1 - slip_tol)")
    ap.add_argument("--timeout", type=float, default=1200.0, help="seconds per ccx run")
    ap.add_argument("--no-profile", dest="profile", action="store_false",
                    help="do not time-stamp ccx's output lines (needs stdbuf) for a breakdown")
    ap.add_argument("--keep", action="store_true",
                    help="keep the .frd, .12d and spooles.out files (removed after reading)")
    args = ap.parse_args()
    args.inc1 = [float(v) for v in args.inc1.split(",")]
    args.inc2 = [float(v) for v in args.inc2.split(",")]
    args.out = os.path.abspath(args.out)

    exe = shutil.which(args.ccx)
    if exe is None:
        print(f"ccx_vm272: '{args.ccx}' not found on PATH: the CalculiX side is skipped",
              file=sys.stderr)
        print(json.dumps({"skipped": "ccx not found"}))
        return 0
    args.ccx = exe
    try:
        v = subprocess.run([exe, "-v"], capture_output=True, text=True, timeout=30).stdout
        m = re.search(r"Version\s+(\S+)", v)
        args.ccx_version = m.group(1) if m else v.strip()
    except (OSError, subprocess.SubprocessError):
        args.ccx_version = "unknown"
    os.makedirs(args.out, exist_ok=True)
    jsonl = os.path.join(args.out, "results.jsonl")
    failed = 0
    for lev in [int(v) for v in args.levels.split(",") if v.strip()]:
        try:
            rec = run_level(lev, args)
        except subprocess.TimeoutExpired:
            rec = {"code": "calculix", "level": lev, "status": f"timeout after {args.timeout} s"}
        if rec.get("status") != "ok":
            failed += 1
        line = json.dumps(rec)
        print(line, flush=True)
        with open(jsonl, "a") as fh:
            fh.write(line + "\n")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
