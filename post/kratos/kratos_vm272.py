#!/usr/bin/env python3
"""Kratos Multiphysics (ContactStructuralMechanicsApplication, mortar ALM) on the VM272 scenes.

For each ladder level L it meshes meshes/vm272.geo with gmsh at h_c = a/(3.2*2^L) in LINEAR
triangles (Kratos has only 2-node mortar conditions in 2-D), writes a Kratos model
(`.mdpa`, `ProjectParameters.json`, `materials.json`) into OUT/CASE/L{k}/, runs it in a child
process (timed around the process, as the CalculiX driver does), and scores the slave nodes'
contact tractions against the closed forms with the same measures as benches/accuracy.rs
(post/kratos/measures.py).

    out/bench/kratos-venv/bin/python post/kratos/kratos_vm272.py --case hertz --levels 0-5
    out/bench/kratos-venv/bin/python post/kratos/kratos_vm272.py --case cm --levels 2 \
        --normal-steps 20 --tangential-steps 20

Cases (the shipped cases/hertz.json and cases/vm272_cm.json):
  hertz  frictionless, P = 10 N/mm on the rigid, non-rotating top (pilot ux = 0);
  cm     Coulomb mu = 0.2: P = 10 N/mm (pilot ux = 0), then Q (default 0.936 N/mm, VM272's)
         on the pilot with P held; `--q` sets Q (0.8 mu P = 1.6 N/mm for the issue's scene).

The top face is rigid and does not rotate, as in our cases and the CalculiX deck: every
`top` node is tied to the pilot (the top node nearest x = 0) by LinearMasterSlaveConstraints
on u_x and u_y, and the loads are point loads on the pilot. Bottom: u = 0.

Prints one JSON object per level on stdout (and appends it to OUT/results.jsonl). A level that
fails (non-converged step, crash, timeout) is reported with "status" saying so, and its
tractions are still scored as they are at the end of the run. Needs the Kratos wheels and gmsh
(benches/kratos.sh installs them into out/bench/kratos-venv).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "post", "calculix"))
sys.path.insert(0, HERE)

A_GEO = 0.6808   # the a of vm272.geo (mesh sizing and arc split only)
R = 8.0
E, NU = 200.0, 0.3
P_LOAD = 10.0
MU = 0.2


# ------------------------------------------------------------------------------------------
# mesh
# ------------------------------------------------------------------------------------------
def make_mesh(level: int, path: str) -> None:
    """meshes/vm272.geo at level `level`, first order, written as MSH 4.1 to `path`."""
    import gmsh

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.onelab.setNumber("h_c", [A_GEO / (3.2 * 2 ** level)])
        gmsh.onelab.setNumber("order", [1.0])
        gmsh.open(os.path.join(REPO, "meshes", "vm272.geo"))
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.option.setNumber("Mesh.RandomSeed", 1)
        gmsh.option.setNumber("Mesh.Binary", 1)
        gmsh.model.mesh.generate(2)
        gmsh.write(path)
    finally:
        gmsh.finalize()


def load_mesh(path: str):
    from msh41 import group_conn, read_msh41

    m = read_msh41(path)
    tri = {b: group_conn(m, b, 2) for b in ("lower_body", "upper_body")}
    lines = {g: group_conn(m, g, 1) for g in ("bottom", "top", "lower_arc", "upper_arc")}
    return m.nodes, tri, lines


# ------------------------------------------------------------------------------------------
# Kratos model files
# ------------------------------------------------------------------------------------------
def write_mdpa(path, xyz, tri, lines, contact_xmax):
    """Nodes, SmallDisplacementElement2D3N, LineCondition2D2N on the arcs (|x| <= contact_xmax
    at both ends; oriented so that the body is on the left, i.e. counter-clockwise), a
    PointLoadCondition2D1N on the pilot, and sub-model parts. Returns facts for the driver."""
    for b, t in tri.items():
        p = xyz[t[:, 0], :2]
        q = xyz[t[:, 1], :2]
        r = xyz[t[:, 2], :2]
        area2 = (q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1]) - (r[:, 0] - p[:, 0]) * (q[:, 1] - p[:, 1])
        if (area2 <= 0).any():
            raise ValueError(f"{b}: {int((area2 <= 0).sum())} clockwise triangles")
    used = np.unique(np.concatenate([tri["lower_body"].ravel(), tri["upper_body"].ravel()]))
    top_nodes = np.unique(lines["top"].ravel())
    pilot = int(top_nodes[np.argmin(np.abs(xyz[top_nodes, 0]))])
    arcs = {}
    for g in ("lower_arc", "upper_arc"):
        e = lines[g]
        keep = (np.abs(xyz[e[:, 0], 0]) <= contact_xmax) & (np.abs(xyz[e[:, 1], 0]) <= contact_xmax)
        arcs[g] = e[keep]
    out = []
    w = out.append
    w("Begin ModelPartData\nEnd ModelPartData\n")
    w("Begin Properties 1\nEnd Properties\nBegin Properties 2\nEnd Properties\n")
    w("Begin Nodes")
    for n in used:
        w(f"{n} {xyz[n, 0]:.17g} {xyz[n, 1]:.17g} 0.0")
    w("End Nodes\n")
    eid = {}
    k = 0
    for prop, b in ((1, "lower_body"), (2, "upper_body")):
        w("Begin Elements SmallDisplacementElement2D3N")
        ids = []
        for t in tri[b]:
            k += 1
            ids.append(k)
            w(f"{k} {prop} {t[0]} {t[1]} {t[2]}")
        w("End Elements\n")
        eid[b] = ids
    cid = {}
    c = 0
    for prop, g in ((1, "lower_arc"), (2, "upper_arc")):
        w("Begin Conditions LineCondition2D2N")
        ids = []
        for e in arcs[g]:
            c += 1
            ids.append(c)
            w(f"{c} {prop} {e[0]} {e[1]}")
        w("End Conditions\n")
        cid[g] = ids
    c += 1
    w("Begin Conditions PointLoadCondition2D1N")
    w(f"{c} 2 {pilot}")
    w("End Conditions\n")
    cid["pilot"] = [c]

    def smp(name, nodes, elems=(), conds=()):
        w(f"Begin SubModelPart {name}")
        w("  Begin SubModelPartNodes")
        w("\n".join(str(int(v)) for v in nodes))
        w("  End SubModelPartNodes")
        w("  Begin SubModelPartElements")
        if len(elems):
            w("\n".join(str(int(v)) for v in elems))
        w("  End SubModelPartElements")
        w("  Begin SubModelPartConditions")
        if len(conds):
            w("\n".join(str(int(v)) for v in conds))
        w("  End SubModelPartConditions")
        w("End SubModelPart\n")

    smp("lower_body", np.unique(tri["lower_body"].ravel()), eid["lower_body"])
    smp("upper_body", np.unique(tri["upper_body"].ravel()), eid["upper_body"])
    smp("bottom", np.unique(lines["bottom"].ravel()))
    smp("top", top_nodes)
    smp("pilot", [pilot], (), cid["pilot"])
    smp("lower_arc", np.unique(arcs["lower_arc"].ravel()), (), cid["lower_arc"])
    smp("upper_arc", np.unique(arcs["upper_arc"].ravel()), (), cid["upper_arc"])
    with open(path, "w") as fh:
        fh.write("\n".join(out) + "\n")
    return {
        "nodes": int(len(used)),
        "elements": int(len(tri["lower_body"]) + len(tri["upper_body"])),
        "slave_faces": int(len(arcs["lower_arc"])),
        "master_faces": int(len(arcs["upper_arc"])),
        "pilot": pilot,
        "top_nodes": [int(v) for v in top_nodes],
        "bottom_nodes": [int(v) for v in np.unique(lines["bottom"].ravel())],
    }


def write_materials(path, mu):
    props = []
    for pid, part in ((1, "lower_body"), (2, "upper_body")):
        props.append({
            "model_part_name": f"Structure.{part}",
            "properties_id": pid,
            "Material": {
                "constitutive_law": {"name": "LinearElasticPlaneStrain2DLaw"},
                "Variables": {"YOUNG_MODULUS": E, "POISSON_RATIO": NU, "DENSITY": 1.0,
                              "THICKNESS": 1.0, "FRICTION_COEFFICIENT": mu},
                "Tables": {},
            },
        })
    with open(path, "w") as fh:
        json.dump({"properties": props}, fh, indent=2)


def _merge(dst, src):
    for k, v in src.items():
        if isinstance(v, dict) and isinstance(dst.get(k), dict):
            _merge(dst[k], v)
        else:
            dst[k] = v


def project_parameters(args, frictional):
    cs = {"mortar_type": "ALMContactFrictional" if frictional else "ALMContactFrictionless"}
    for k, v in (("frictional_stick_contact_displacement_relative_tolerance", args.f_stick_disp_rtol),
                 ("frictional_stick_contact_residual_relative_tolerance", args.f_stick_res_rtol),
                 ("frictional_slip_contact_displacement_relative_tolerance", args.f_slip_disp_rtol),
                 ("frictional_slip_contact_residual_relative_tolerance", args.f_slip_res_rtol)):
        if v is not None:
            cs[k] = v
    if args.echo:
        cs["silent_strategy"] = False
    if args.no_mixed_ulm:
        cs["use_mixed_ulm_solver"] = False
    process = {
        "model_part_name": "Structure",
        "assume_master_slave": {"0": ["lower_arc"]},
        "contact_model_part": {"0": ["lower_arc", "upper_arc"]},
        "contact_type": "Frictional" if frictional else "Frictionless",
    }
    if frictional:
        process["friction_coefficients"] = {"0": args.mu}
        if args.slip_threshold is not None:
            process["slip_threshold"] = args.slip_threshold
        if args.slip_augmentation is not None:
            process["slip_augmentation_coefficient"] = args.slip_augmentation
    if args.penalty_scale is not None:
        process["advance_ALM_parameters"] = {"penalty_scale_factor": args.penalty_scale}
    if args.process_json:
        _merge(process, json.loads(args.process_json))
    if args.contact_json:
        _merge(cs, json.loads(args.contact_json))
    pp = {
        "problem_data": {"problem_name": "vm272", "parallel_type": "OpenMP", "echo_level": args.echo,
                         "start_time": 0.0, "end_time": 2.0 if frictional else 1.0},
        "solver_settings": {
            "solver_type": "Static",
            "model_part_name": "Structure",
            "domain_size": 2,
            "echo_level": args.echo,
            "analysis_type": "non_linear",
            "model_import_settings": {"input_type": "mdpa", "input_filename": "vm272"},
            "material_import_settings": {"materials_filename": "materials.json"},
            "contact_settings": cs,
            "time_stepping": {"time_step": 1.0},
            "convergence_criterion": "contact_residual_criterion",
            "displacement_relative_tolerance": 1e-4,
            "displacement_absolute_tolerance": 1e-9,
            "residual_relative_tolerance": 1e-4,
            "residual_absolute_tolerance": 1e-9,
            "max_iteration": args.max_iterations,
            "linear_solver_settings": {"solver_type": args.linear_solver},
            "builder_and_solver_settings": {"type": args.builder},
        },
        "processes": {"contact_process_list": [{
            "python_module": "alm_contact_process",
            "kratos_module": "KratosMultiphysics.ContactStructuralMechanicsApplication",
            "process_name": "ALMContactProcess",
            "Parameters": process,
        }]},
        "output_processes": {},
    }
    if args.solver_json:
        _merge(pp["solver_settings"], json.loads(args.solver_json))
    return pp


# ------------------------------------------------------------------------------------------
# the child: runs one model directory
# ------------------------------------------------------------------------------------------
def solve(workdir):
    """Runs the model in `workdir` (cwd) and writes result.json and contact.csv there."""
    t0 = time.perf_counter()
    import KratosMultiphysics as KM
    import KratosMultiphysics.ContactStructuralMechanicsApplication as CSMA
    import KratosMultiphysics.LinearSolversApplication  # noqa: F401  (sparse_lu)
    import KratosMultiphysics.StructuralMechanicsApplication as SMA
    from KratosMultiphysics.StructuralMechanicsApplication.structural_mechanics_analysis import (
        StructuralMechanicsAnalysis,
    )

    t_import = time.perf_counter() - t0
    os.chdir(workdir)
    with open("driver.json") as fh:
        d = json.load(fh)
    with open("ProjectParameters.json") as fh:
        params = KM.Parameters(fh.read())
    times = [k / d["normal_steps"] for k in range(1, d["normal_steps"] + 1)]
    if d["frictional"]:
        times += [1.0 + k / d["tangential_steps"] for k in range(1, d["tangential_steps"] + 1)]
    rec = {"import_s": t_import, "steps": []}
    snapshots = {}

    class Run(StructuralMechanicsAnalysis):
        def __init__(self, model, p):
            super().__init__(model, p)
            self.k = 0

        def ModifyInitialGeometry(self):
            super().ModifyInitialGeometry()
            mp = self.model["Structure"]
            for n in mp.GetSubModelPart("bottom").Nodes:
                n.Fix(KM.DISPLACEMENT_X)
                n.Fix(KM.DISPLACEMENT_Y)
            pilot = mp.GetNode(d["pilot"])
            cid = 0
            for nid in d["top_nodes"]:
                if nid == d["pilot"]:
                    continue
                n = mp.GetNode(nid)
                for var in (KM.DISPLACEMENT_X, KM.DISPLACEMENT_Y):
                    cid += 1
                    mp.CreateNewMasterSlaveConstraint("LinearMasterSlaveConstraint", cid,
                                                      pilot, var, n, var, 1.0, 0.0)

        def KeepAdvancingSolutionLoop(self):
            return self.k < len(times)

        def _AdvanceTime(self):
            mp = self.model["Structure"]
            t = times[self.k]
            self.k += 1
            mp.ProcessInfo[KM.STEP] += 1
            mp.CloneTimeStep(t)
            return t

        def ApplyBoundaryConditions(self):
            super().ApplyBoundaryConditions()
            mp = self.model["Structure"]
            t = self.time
            fy = -d["P"] * min(t, 1.0)
            fx = d["Q"] * max(t - 1.0, 0.0) if d["frictional"] else 0.0
            for cnd in mp.GetSubModelPart("pilot").Conditions:
                cnd.SetValue(SMA.POINT_LOAD, KM.Array3([fx, fy, 0.0]))
            if d["frictional"] and d.get("frictionless_normal_stage"):
                # mu = 0 while P is applied (identical materials: no shear in the exact
                # solution), the Coulomb coefficient from the first tangential increment on
                mu = 0.0 if t <= 1.0 + 1e-12 else d["mu"]
                for prop in self._contact_properties(mp):
                    prop[KM.FRICTION_COEFFICIENT] = mu
            pilot = mp.GetNode(d["pilot"])
            if t <= 1.0 + 1e-12:
                pilot.Fix(KM.DISPLACEMENT_X)
                pilot.SetSolutionStepValue(KM.DISPLACEMENT_X, 0.0)
            else:
                pilot.Free(KM.DISPLACEMENT_X)

        def _contact_properties(self, mp):
            found = []

            def walk(part):
                for sub in part.SubModelParts:
                    if sub.Name.startswith("ContactSub"):
                        found.extend(sub.GetProperties())
                    walk(sub)
            walk(mp)
            if not found:
                raise RuntimeError("no ContactSub* model part: cannot set the friction coefficient")
            return found

        def RunSolutionLoop(self):
            mp = self.model["Structure"]
            while self.KeepAdvancingSolutionLoop():
                self.time = self._AdvanceTime()
                ts = time.perf_counter()
                self.InitializeSolutionStep()
                ok = self._GetSolver().SolveSolutionStep()
                self.FinalizeSolutionStep()
                self.OutputSolutionStep()
                its = mp.ProcessInfo[KM.NL_ITERATION_NUMBER]
                rec["steps"].append({"time": self.time, "converged": bool(ok), "iterations": int(its),
                                     "wall_s": time.perf_counter() - ts})
                if self.k == len(times):
                    snapshots["final"] = self.snapshot()
                elif abs(self.time - 1.0) < 1e-12:
                    snapshots["normal"] = self.snapshot()
                with open("progress.json", "w") as fh:
                    json.dump(rec, fh)

        def snapshot(self):
            mp = self.model["Structure"]
            pilot = mp.GetNode(d["pilot"])
            rows = []
            for n in mp.GetSubModelPart("lower_arc").Nodes:
                p = n.GetValue(CSMA.AUGMENTED_NORMAL_CONTACT_PRESSURE)
                q = 0.0
                tv = nv = (0.0, 0.0, 0.0)
                if d["frictional"]:
                    # the tangential traction is a vector: its component along the tangent
                    # t = (n_y, -n_x) of the slave normal n, oriented to have t_x > 0
                    tv = n.GetValue(CSMA.AUGMENTED_TANGENT_CONTACT_PRESSURE)
                    nv = n.GetSolutionStepValue(KM.NORMAL)
                    tx, ty = nv[1], -nv[0]
                    if tx < 0:
                        tx, ty = -tx, -ty
                    q = tv[0] * tx + tv[1] * ty
                rows.append((n.Id, n.X0, n.Y0, p, q, int(n.Is(KM.ACTIVE)), int(n.Is(KM.SLIP)),
                             n.GetSolutionStepValue(KM.DISPLACEMENT_X),
                             n.GetSolutionStepValue(KM.DISPLACEMENT_Y), tv[0], tv[1], nv[0], nv[1]))
            ry = sum(n.GetSolutionStepValue(KM.REACTION_Y) for n in mp.GetSubModelPart("bottom").Nodes)
            rx = sum(n.GetSolutionStepValue(KM.REACTION_X) for n in mp.GetSubModelPart("bottom").Nodes)
            return {"rows": rows, "pilot_u": [pilot.GetSolutionStepValue(KM.DISPLACEMENT_X),
                                              pilot.GetSolutionStepValue(KM.DISPLACEMENT_Y)],
                    "bottom_reaction": [rx, ry], "time": self.time}

    model = KM.Model()
    sim = Run(model, params)
    t1 = time.perf_counter()
    sim.Initialize()
    rec["initialize_s"] = time.perf_counter() - t1
    t2 = time.perf_counter()
    sim.RunSolutionLoop()
    rec["solve_loop_s"] = time.perf_counter() - t2
    sim.Finalize()
    rec["dofs"] = int(sim._GetSolver()._GetBuilderAndSolver().GetEquationSystemSize()) \
        if hasattr(sim._GetSolver()._GetBuilderAndSolver(), "GetEquationSystemSize") else None
    with open("contact.csv", "w") as fh:
        fh.write("step,node,x,y,p,q,active,slip,ux,uy,tx,ty,nx,ny\n")
        for name, s in snapshots.items():
            for r in s["rows"]:
                fh.write(f"{name},{r[0]},{r[1]:.12g},{r[2]:.12g},{r[3]:.12g},{r[4]:.12g},{r[5]},{r[6]},"
                         + ",".join(f"{v:.12g}" for v in r[7:]) + "\n")
    rec["snapshots"] = {k: {kk: vv for kk, vv in s.items() if kk != "rows"} for k, s in snapshots.items()}
    rec["child_total_s"] = time.perf_counter() - t0
    rec["max_rss_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    with open("result.json", "w") as fh:
        json.dump(rec, fh, indent=1)


# ------------------------------------------------------------------------------------------
# the parent: prepare, run, score
# ------------------------------------------------------------------------------------------
def parse_levels(s):
    if "-" in s:
        a, b = s.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(v) for v in s.split(",") if v.strip()]


def prepare(args, level, outdir, frictional):
    os.makedirs(outdir, exist_ok=True)
    meshdir = os.path.join(args.out, "meshes")
    os.makedirs(meshdir, exist_ok=True)
    msh = os.path.join(meshdir, f"vm272_p1_L{level}.msh")
    if not os.path.exists(msh):
        make_mesh(level, msh)
    xyz, tri, lines = load_mesh(msh)
    facts = write_mdpa(os.path.join(outdir, "vm272.mdpa"), xyz, tri, lines,
                       args.contact_xmax * A_GEO)
    write_materials(os.path.join(outdir, "materials.json"), args.mu if frictional else 0.0)
    with open(os.path.join(outdir, "ProjectParameters.json"), "w") as fh:
        json.dump(project_parameters(args, frictional), fh, indent=2)
    drv = {"pilot": facts["pilot"], "top_nodes": facts["top_nodes"], "frictional": frictional,
           "P": args.load, "Q": args.q if frictional else 0.0,
           "normal_steps": args.normal_steps, "tangential_steps": args.tangential_steps,
           "mu": args.mu, "frictionless_normal_stage": args.frictionless_normal_stage}
    with open(os.path.join(outdir, "driver.json"), "w") as fh:
        json.dump(drv, fh)
    return facts


def run_child(outdir, threads, timeout):
    env = dict(os.environ)
    env["OMP_NUM_THREADS"] = str(threads)
    for f in ("result.json", "contact.csv", "progress.json"):
        try:
            os.remove(os.path.join(outdir, f))
        except FileNotFoundError:
            pass
    t = time.perf_counter()
    status = "ok"
    with open(os.path.join(outdir, "kratos.log"), "w") as log:
        try:
            pr = subprocess.run([sys.executable, os.path.abspath(__file__), "--solve", outdir],
                                stdout=log, stderr=subprocess.STDOUT, env=env, timeout=timeout)
            if pr.returncode != 0:
                status = f"kratos exited {pr.returncode}"
        except subprocess.TimeoutExpired:
            status = f"timeout after {timeout:.0f} s"
    return time.perf_counter() - t, status


def log_tail(outdir, n=6):
    try:
        with open(os.path.join(outdir, "kratos.log"), errors="replace") as fh:
            lines = [l.rstrip() for l in fh if l.strip()]
        return lines[-n:]
    except FileNotFoundError:
        return []


def run_level(args, level):
    import measures

    frictional = args.case != "hertz"
    outdir = os.path.abspath(os.path.join(args.out, args.case if args.tag is None else args.tag, f"L{level}"))
    facts = prepare(args, level, outdir, frictional)
    wall, status = run_child(outdir, args.threads, args.timeout)
    rec = {"code": "kratos", "case": args.case, "level": level, "threads": args.threads,
           "wall_time_s": wall, "elements": facts["elements"], "nodes": facts["nodes"],
           "slave_faces": facts["slave_faces"], "normal_steps": args.normal_steps,
           "tangential_steps": args.tangential_steps if frictional else 0,
           "Q": args.q if frictional else 0.0, "dir": os.path.relpath(outdir, REPO)}
    res = None
    for name in ("result.json", "progress.json"):
        try:
            with open(os.path.join(outdir, name)) as fh:
                res = json.load(fh)
            break
        except (FileNotFoundError, json.JSONDecodeError):
            continue
    if res is not None:
        steps = res.get("steps", [])
        rec["iterations"] = sum(s["iterations"] for s in steps)
        rec["steps_run"] = len(steps)
        rec["steps_planned"] = args.normal_steps + (args.tangential_steps if frictional else 0)
        nc = [s["time"] for s in steps if not s["converged"]]
        rec["steps_not_converged"] = len(nc)
        rec["first_not_converged_time"] = nc[0] if nc else None
        for k in ("import_s", "initialize_s", "solve_loop_s", "child_total_s", "max_rss_mib", "dofs"):
            if k in res:
                rec[k] = res[k]
        rec["snapshots"] = res.get("snapshots")
        if status == "ok" and nc:
            status = f"{len(nc)} of {len(steps)} steps not converged (first at t = {nc[0]:.4g})"
        if status == "ok" and len(steps) < rec["steps_planned"]:
            status = f"stopped after {len(steps)} of {rec['steps_planned']} steps"
    elif status == "ok":
        status = "no result.json"
    rec["status"] = status
    if status != "ok":
        rec["log_tail"] = log_tail(outdir)
    csvp = os.path.join(outdir, "contact.csv")
    if os.path.exists(csvp):
        rec.update(measures.score_kratos_csv(csvp, level, frictional, args.q, args.mu,
                                             args.slip_tol))
        # a converged run can still end on a wrong contact set (seen on L4 with 5 normal
        # increments: nodes inside the contact zone inactive, pressures of +-1e4): say so
        x, p = final_xp(csvp)
        inside = [abs(xi) for xi, pi in zip(x, p) if pi > 0]
        if inside:
            a_fe = max(inside)
            holes = sum(1 for xi, pi in zip(x, p) if abs(xi) < a_fe and pi <= 0)
            rec["inactive_inside_contact"] = holes
            if holes and status == "ok":
                rec["status"] = (f"converged to a wrong contact set: {holes} nodes inside "
                                 f"|x| < a_FE inactive")
    return rec


def build_parser():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--solve", help=argparse.SUPPRESS)
    ap.add_argument("--case", choices=("hertz", "cm"), default="hertz")
    ap.add_argument("--levels", default="0-3")
    ap.add_argument("--threads", type=int, default=2, help="OMP_NUM_THREADS of the Kratos process")
    ap.add_argument("--out", default=os.path.join(REPO, "out", "bench", "kratos"))
    ap.add_argument("--tag", help="subdirectory of --out instead of the case name")
    ap.add_argument("--q", type=float, default=0.936, help="tangential load Q, N/mm (cm)")
    ap.add_argument("--mu", type=float, default=MU)
    ap.add_argument("--load", type=float, default=P_LOAD,
                    help="normal load P, N/mm (the scores assume 10; other values for experiments)")
    ap.add_argument("--normal-steps", type=int, default=5)
    ap.add_argument("--tangential-steps", type=int, default=10)
    ap.add_argument("--max-iterations", type=int, default=30)
    ap.add_argument("--linear-solver", default="sparse_lu")
    ap.add_argument("--builder", default="block", choices=("block", "elimination"),
                    help="builder_and_solver_settings.type")
    ap.add_argument("--contact-xmax", type=float, default=1.5, help="contact faces |x| <= this * a")
    ap.add_argument("--slip-tol", type=float, default=0.02,
                    help="stick: |q| < mu p (1 - slip_tol), as in the CalculiX driver")
    ap.add_argument("--timeout", type=float, default=1800.0)
    ap.add_argument("--echo", type=int, default=0, help="solver echo level (timings of the builder)")
    ap.add_argument("--frictionless-normal-stage", action="store_true",
                    help="friction coefficient 0 in the contact pair's properties while P is applied, mu "
                         "from the first tangential increment (tried: no effect in Kratos 10.4.4)")
    ap.add_argument("--no-mixed-ulm", action="store_true", help="use_mixed_ulm_solver = false")
    ap.add_argument("--f-stick-disp-rtol", type=float)
    ap.add_argument("--f-stick-res-rtol", type=float)
    ap.add_argument("--f-slip-disp-rtol", type=float)
    ap.add_argument("--f-slip-res-rtol", type=float)
    ap.add_argument("--slip-threshold", type=float)
    ap.add_argument("--slip-augmentation", type=float)
    ap.add_argument("--penalty-scale", type=float)
    ap.add_argument("--process-json", help="JSON merged into the alm_contact_process Parameters")
    ap.add_argument("--contact-json", help="JSON merged into solver_settings.contact_settings")
    ap.add_argument("--solver-json", help="JSON merged into solver_settings")
    return ap


def default_args():
    return build_parser().parse_args([])


def final_xp(path):
    """x and p (compression positive) of the slave nodes at the last step of contact.csv."""
    import measures

    try:
        rows = measures.read_kratos_csv(path, "final")
    except FileNotFoundError:
        return [], []
    return [float(r["x"]) for r in rows], [-float(r["p"]) for r in rows]


def main():
    args = build_parser().parse_args()
    if args.solve:
        solve(args.solve)
        return
    os.makedirs(args.out, exist_ok=True)
    failed = False
    for level in parse_levels(args.levels):
        rec = run_level(args, level)
        line = json.dumps(rec)
        print(line, flush=True)
        with open(os.path.join(args.out, "results.jsonl"), "a") as fh:
            fh.write(line + "\n")
        failed |= rec["status"] != "ok"
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
