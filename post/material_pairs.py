#!/usr/bin/env python3
"""Rabinowicz's metal pairs (the paper's Table 1) on a laboratory line contact: a cylindrical
pad of radius R = 25 mm (first material of the pair) pressed on a flat specimen (second
material), loaded by a normal force P and then a force-controlled tangential ramp past Q_max.
See docs/material_pairs.md.

    cargo build --release
    python3 post/material_pairs.py [OUT]          # default OUT = out/material_pairs
        [--bin PATH] [--threads N] [--reuse] [--only NAME ...] [--no-beta0] [--write-cases]

Runs every `cases/pair_*.json` (exit status 5, "equilibrium lost", is the expected end), calls
`stickslip analytic` for the closed forms, reads the von Mises stress of the last written
step for the yield check, prints the tables of docs/material_pairs.md and writes them to
OUT/material_pairs_tables.md (numbers in OUT/material_pairs.json).

The JKR check is repeated with β = 0 (both bodies with the pair's E*, ν = 0.3; case written to
OUT/pair_jkr_beta0.json) unless --no-beta0.

`--write-cases` rewrites the case files from the tables below (materials, loads) and exits;
without it the script checks that the case files agree with the tables.
"""
import argparse
import glob
import json
import math
import os
import re
import subprocess
import sys
import time
import zlib

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, HERE)
from fe_common import analytic_json, die, find_bin  # noqa: E402

R_PAD = 25.0  # mm; the flat is 50 mm x 10 mm (meshes/pad_flat.geo)

# Typical handbook values for commercially pure / low-carbon metals, plane strain (E, Y in MPa).
# Y: 0.2 % proof stress of a common temper (see docs/material_pairs.md for the sources).
MATERIALS = {
    "mild steel": {"E": 207000.0, "nu": 0.30, "Y": 250.0},
    "copper": {"E": 110000.0, "nu": 0.34, "Y": 250.0},
    "lead": {"E": 16000.0, "nu": 0.44, "Y": 5.0},
    "titanium": {"E": 107000.0, "nu": 0.34, "Y": 275.0},
    "zinc": {"E": 108000.0, "nu": 0.25, "Y": 75.0},
}

# (preset, pad material, flat material, P in N/mm, mesh). P gives p0 ~ Y_soft / 2.
PAIRS = [
    ("copper-mild-steel", "copper", "mild steel", 15.0, "pad_flat.msh"),
    ("lead-mild-steel", "lead", "mild steel", 0.027, "pad_flat_lead.msh"),
    ("mild-steel-copper", "mild steel", "copper", 15.0, "pad_flat.msh"),
    ("mild-steel-titanium", "mild steel", "titanium", 15.0, "pad_flat.msh"),
    ("mild-steel-zinc", "mild steel", "zinc", 1.5, "pad_flat.msh"),
]
PRESETS = {  # the paper's Table 1 (also `stickslip analytic presets`): f_s, f_d, Δ (mm)
    "copper-mild-steel": (0.46, 0.31, 1.0e-3),
    "lead-mild-steel": (0.72, 0.47, 3.0e-3),
    "mild-steel-copper": (0.54, 0.39, 0.9e-3),
    "mild-steel-titanium": (0.63, 0.45, 6.0e-3),
    "mild-steel-zinc": (0.65, 0.47, 2.0e-3),
}
# The JKR check: copper pad on mild steel with the copper/mild-steel f_s, f_d but a slip length
# Δ chosen for Λ = 0.025 (a few nm: hypothetical), at a load whose a the mesh resolves.
JKR = {"name": "pair_jkr_copper_mild_steel", "pad": "copper", "flat": "mild steel",
       "preset": "copper-mild-steel", "P": 45.0, "lambda": 0.025, "mesh": "pad_flat.msh",
       "steps": 46, "q_end_over_fdP": 1.15}
STEPS = 50            # tangential steps up to Q_END_OVER_FS * f_s P
Q_END_OVER_FS = 1.05


def case_name(preset):
    return "pair_" + preset.replace("-", "_")


def candidate_gap(a):
    """Initial gap g0 = x²/2R at |x| = 1.25 a: the candidate zone covers the contact plus a margin
    (the run widens it by itself if the contact reaches its edge)."""
    return float(f"{(1.25 * a) ** 2 / (2 * R_PAD):.3g}")


def e_star(m1, m2):
    return 1.0 / ((1 - m1["nu"] ** 2) / m1["E"] + (1 - m2["nu"] ** 2) / m2["E"])


def make_case(title, mesh, pad, flat, P, friction, steps, q_end, every):
    a = math.sqrt(4 * P * R_PAD / (math.pi * e_star(MATERIALS[pad], MATERIALS[flat])))
    return {
        "title": title,
        "mesh": f"../meshes/{mesh}",
        "bodies": [
            {"group": "lower_body", "E": MATERIALS[flat]["E"], "nu": MATERIALS[flat]["nu"]},
            {"group": "upper_body", "E": MATERIALS[pad]["E"], "nu": MATERIALS[pad]["nu"]},
        ],
        "supports": [{"group": "bottom", "ux": 0.0, "uy": 0.0}],
        "pilot": {"group": "top"},
        "contact": {
            "slave": "lower_arc", "master": "upper_arc", "method": "newton",
            "max_iterations": 30, "candidate_gap": candidate_gap(a),
            "friction": friction,
        },
        "stages": [
            {"name": "normal", "steps": 1, "pilot_x": {"force": 0.0}, "pilot_y": {"force": -P}},
            {"name": "tangential", "steps": steps, "pilot_x": {"force": q_end}},
        ],
        "output": {"every": every},
    }


def all_cases():
    out = {}
    for preset, pad, flat, P, mesh in PAIRS:
        fs = PRESETS[preset][0]
        q_end = float(f"{Q_END_OVER_FS * fs * P:.4g}")
        out[case_name(preset)] = make_case(
            f"Table 1 pair {preset}: {pad} pad (R = 25 mm) on a {flat} flat, P = {P} N/mm, "
            f"then a tangential force ramp to {q_end} N/mm = {Q_END_OVER_FS} f_s P (past Q_max)",
            mesh, pad, flat, P, {"preset": preset, "shape": "ramp"}, STEPS, q_end, 10)
    fs, fd, _ = PRESETS[JKR["preset"]]
    q_end = float(f"{JKR['q_end_over_fdP'] * fd * JKR['P']:.4g}")
    out[JKR["name"]] = make_case(
        f"JKR check: copper pad on mild steel, f_s = {fs}, f_d = {fd} with Λ = {JKR['lambda']} "
        f"(Δ of a few nm, hypothetical), P = {JKR['P']} N/mm, tangential ramp to "
        f"{q_end} N/mm = {JKR['q_end_over_fdP']} f_d P",
        JKR["mesh"], JKR["pad"], JKR["flat"], JKR["P"],
        {"shape": "ramp", "fs": fs, "fd": fd, "lambda": JKR["lambda"], "radius": R_PAD,
         "load": JKR["P"]},
        JKR["steps"], q_end, 100)
    return out


# ---------------------------------------------------------------------------------------------
# reading the output
# ---------------------------------------------------------------------------------------------
def vtu_arrays(path, names):
    """DataArrays of a .vtu by name: appended raw data (UInt64 headers), each array raw or in
    zlib blocks (`compressor="vtkZLibDataCompressor"`, `output.compress`)."""
    data = open(path, "rb").read()
    app = data.index(b"<AppendedData")
    start = data.index(b"_", app) + 1
    head = data[:app].decode()
    compressed = 'compressor="vtkZLibDataCompressor"' in head
    dtypes = {"Float64": "<f8", "UInt64": "<u8", "UInt8": "u1", "Int64": "<i8"}
    out = {}
    for m in re.finditer(r'<DataArray type="(\w+)" Name="(\w+)"[^>]*offset="(\d+)"', head):
        typ, name, offset = m.groups()
        if name not in names:
            continue
        p = start + int(offset)
        if compressed:
            nblocks = int(np.frombuffer(data[p:p + 8], "<u8")[0])
            sizes = np.frombuffer(data[p + 24:p + 24 + 8 * nblocks], "<u8")
            q, raw = p + 24 + 8 * nblocks, b""
            for c in sizes:
                raw += zlib.decompress(data[q:q + int(c)])
                q += int(c)
        else:
            n = int(np.frombuffer(data[p:p + 8], "<u8")[0])
            raw = data[p + 8:p + 8 + n]
        out[name] = np.frombuffer(raw, dtypes[typ])
    missing = set(names) - set(out)
    if missing:
        die(f"{path}: arrays {sorted(missing)} not found")
    return out


def von_mises_per_body(run_dir, stem):
    files = [f for f in glob.glob(os.path.join(run_dir, f"{stem}_*.vtu"))
             if re.search(rf"{re.escape(stem)}_(\d+)\.vtu$", f)]
    if not files:
        return None, None
    last = max(files, key=lambda f: int(re.search(r"_(\d+)\.vtu$", f).group(1)))
    d = vtu_arrays(last, {"von_mises", "body_id", "connectivity"})
    conn = d["connectivity"].reshape(-1, 6)
    body_of_node = np.full(d["von_mises"].shape[0], -1)
    for b in (0, 1):
        body_of_node[conn[d["body_id"] == b].ravel()] = b
    return [float(d["von_mises"][body_of_node == b].max()) for b in (0, 1)], last


def history(run_dir):
    with open(os.path.join(run_dir, "history.csv")) as f:
        head = f.readline().strip().split(",")
        rows = [[float(x) for x in line.split(",")] for line in f if line.strip()]
    return head, rows


def contact_at_step(run_dir, vtu_path):
    """Max accumulated slip and min μ along the contact of the step written in vtu_path."""
    n = int(re.search(r"_(\d+)\.vtu$", vtu_path).group(1))
    path = os.path.join(run_dir, f"contact_{n:04d}.csv")
    data = np.genfromtxt(path, delimiter=",", names=True)
    inside = data["pressure"] > 0
    return float(data["slip"][inside].max()), float(data["mu"][inside].min()), n


def run_case(binary, name, out_dir, threads, reuse, case=None):
    case = case or os.path.join(REPO, "cases", f"{name}.json")
    run_dir = os.path.join(out_dir, name)
    summ = os.path.join(run_dir, "summary.json")
    stamp = os.path.join(run_dir, ".case.json")
    if reuse and os.path.isfile(summ) and os.path.isfile(stamp) and \
            open(stamp).read() == open(case).read():
        print(f"  {name}: reusing {run_dir}", flush=True)
        return json.load(open(summ)), None
    t0 = time.time()
    res = subprocess.run([binary, "run", case, "--out", run_dir, "--threads", str(threads),
                          "--quiet"], capture_output=True, text=True)
    wall = time.time() - t0
    if res.returncode not in (0, 5):
        die(f"{name}: stickslip exited with {res.returncode}\n{res.stderr.strip()}")
    if res.returncode != 5:
        print(f"  WARNING {name}: exit status {res.returncode}, expected 5 (equilibrium lost)")
    with open(stamp, "w") as f:
        f.write(open(case).read())
    print(f"  {name}: exit {res.returncode}, {wall:.1f} s", flush=True)
    s = json.load(open(summ))
    s["_process_wall_s"] = wall
    json.dump(s, open(summ, "w"), indent=1)
    return s, wall


def fmt(x, nd=4):
    if x is None:
        return "—"
    if x == 0:
        return "0"
    if abs(x) >= 1e4 or abs(x) < 1e-3:
        return f"{x:.{nd - 1}e}"
    return f"{x:.{nd}g}"


def md_table(head, rows):
    return "\n".join(["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
                     + ["| " + " | ".join(r) + " |" for r in rows])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", nargs="?", default="out/material_pairs")
    ap.add_argument("--bin")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--reuse", action="store_true", help="keep runs whose case file is unchanged")
    ap.add_argument("--only", nargs="*", help="case names (pair_...) to run")
    ap.add_argument("--write-cases", action="store_true")
    ap.add_argument("--no-beta0", action="store_true", help="skip the β = 0 control run")
    args = ap.parse_args()

    cases = all_cases()
    if args.write_cases:
        for name, c in cases.items():
            with open(os.path.join(REPO, "cases", f"{name}.json"), "w") as f:
                json.dump(c, f, indent=2, ensure_ascii=False)
                f.write("\n")
            print(f"wrote cases/{name}.json")
        return
    for name, c in cases.items():
        path = os.path.join(REPO, "cases", f"{name}.json")
        if not os.path.isfile(path) or json.load(open(path)) != c:
            die(f"cases/{name}.json differs from the tables in {__file__}; "
                "rerun with --write-cases (or fix the tables)")

    binary = find_bin(args.bin)
    os.makedirs(args.out, exist_ok=True)
    names = [case_name(p[0]) for p in PAIRS] + [JKR["name"]]
    if args.only:
        names = [n for n in names if n in args.only]

    results = {}
    for name in names:
        c = cases[name]
        pad_m = {"E": c["bodies"][1]["E"], "nu": c["bodies"][1]["nu"]}
        flat_m = {"E": c["bodies"][0]["E"], "nu": c["bodies"][0]["nu"]}
        if name == JKR["name"]:
            preset, pad, flat, P = JKR["preset"], JKR["pad"], JKR["flat"], JKR["P"]
        else:
            preset, pad, flat, P, _ = next(p for p in PAIRS if case_name(p[0]) == name)
        fs, fd, delta = PRESETS[preset]
        geo = ["--r1", R_PAD, "--r2", "inf", "--e1", pad_m["E"], "--nu1", pad_m["nu"],
               "--e2", flat_m["E"], "--nu2", flat_m["nu"], "--load", P]
        hz = analytic_json(binary, "hertz", *geo)
        law = ["--delta", delta] if name != JKR["name"] else ["--lambda", JKR["lambda"]]
        sc = analytic_json(binary, "scales", "--fs", fs, "--fd", fd, *law, *geo)
        app = analytic_json(binary, "apparent", "--chi", sc["chi"], "--fs-over-fd", fs / fd)
        s, wall = run_case(binary, name, args.out, args.threads, args.reuse)
        fr = s["friction"]
        run_dir = os.path.join(args.out, name)
        vm, vtu = von_mises_per_body(run_dir, name)
        head, rows = history(run_dir)
        slip_max, mu_min, vstep = contact_at_step(run_dir, vtu) if vtu else (None, None, None)
        q_at_vtu = next((r[head.index("pilot_fx")] for r in rows if int(r[0]) == vstep), None)
        results[name] = {
            "preset": preset, "pad": pad, "flat": flat, "P": P, "fs": fs, "fd": fd,
            "delta": sc["delta"], "beta": hz["dundurs_beta"], "e_star": hz["e_star"],
            "a": hz["a"], "p0": hz["p0"], "lambda": sc["lambda"], "chi": sc["chi"],
            "psi": sc["psi"], "s0_over_a": sc["s0_centre_over_a"],
            "a_fe": fr["a_hertz"], "lambda_fe": fr["lambda"], "h_contact": fr["h_contact"],
            "h_over_s0": fr["h_contact"] / (fr["s0_over_a"] * fr["a_hertz"]),
            "resolved": fr["resolved"], "q_max": fr["q_max"], "load_fe": fr["load"],
            "apparent_fe": fr["apparent_friction"],
            "apparent_jkr": app["q_max_jkr"] * fd, "apparent_dcm": app["q_max_dcm"] * fd,
            "dcm_truncated": app["dcm_max_truncated"], "small_scale_ok": app["small_scale_ok"],
            "apparent_jkr_summary": fr["apparent_friction_jkr"],
            "steps": len(s["steps"]), "newton_iterations": s["newton_iterations"],
            "contact_nodes": s["contact_nodes"], "triangles": s["triangles"],
            "wall_s": s.get("_process_wall_s", wall), "status": s["status"],
            "von_mises_max": {"flat": vm[0], "pad": vm[1]} if vm else None,
            "yield_ratio": {"flat": vm[0] / MATERIALS[flat]["Y"],
                            "pad": vm[1] / MATERIALS[pad]["Y"]} if vm else None,
            "vtu": os.path.basename(vtu) if vtu else None, "q_at_vtu": q_at_vtu,
            "slip_max_at_vtu": slip_max, "mu_min_at_vtu": mu_min,
        }
    # β = 0 control of the JKR check: both bodies with the same E* (ν = 0.3), same law and load.
    beta0 = None
    if JKR["name"] in names and not args.no_beta0:
        c = json.loads(json.dumps(cases[JKR["name"]]))
        es = e_star(MATERIALS[JKR["pad"]], MATERIALS[JKR["flat"]])
        for b in c["bodies"]:
            b["E"], b["nu"] = 2 * (1 - 0.3 ** 2) * es, 0.3
        c["mesh"] = os.path.join(REPO, "meshes", JKR["mesh"])
        c["title"] += "; β = 0 control (both bodies E = 2(1 − 0.3²)E*, ν = 0.3)"
        path = os.path.join(args.out, "pair_jkr_beta0.json")
        with open(path, "w") as f:
            json.dump(c, f, indent=2, ensure_ascii=False)
        s, wall = run_case(binary, "pair_jkr_beta0", args.out, args.threads, args.reuse, path)
        fr = s["friction"]
        beta0 = {"E": c["bodies"][0]["E"], "q_max_over_fdP": fr["q_max"] / (fr["f_d"] * fr["load"]),
                 "jkr": fr["apparent_friction_jkr"] / fr["f_d"],
                 "h_over_s0": fr["h_contact"] / (fr["s0_over_a"] * fr["a_hertz"]),
                 "resolved": fr["resolved"], "lambda": fr["lambda"], "a": fr["a_hertz"],
                 "wall_s": s.get("_process_wall_s", wall)}
        results["pair_jkr_beta0"] = beta0
    json.dump(results, open(os.path.join(args.out, "material_pairs.json"), "w"), indent=1)

    # ------------------------------------------------------------------ tables
    pairs = [results[n] for n in names if n != JKR["name"]]
    t_mat = md_table(
        ["material", "E (GPa)", "ν", "Y (MPa)"],
        [[m, f"{v['E'] / 1000:g}", f"{v['nu']:g}", f"{v['Y']:g}"] for m, v in MATERIALS.items()])
    t_par = md_table(
        ["pair (pad / flat)", "f_s", "f_d", "Δ (µm)", "E* (GPa)", "β", "P (N/mm)", "a (mm)",
         "p0 (MPa)", "Λ", "χ", "Ψ", "s0/a", "h (µm)", "h/s0"],
        [[r["preset"], fmt(r["fs"], 2), fmt(r["fd"], 2), fmt(r["delta"] * 1e3, 2),
          f"{r['e_star'] / 1000:.1f}", f"{r['beta']:+.3f}", fmt(r["P"], 3), fmt(r["a"], 3),
          fmt(r["p0"], 3), fmt(r["lambda"], 3), fmt(r["chi"], 3), fmt(r["psi"], 3),
          fmt(r["s0_over_a"], 3), fmt(r["h_contact"] * 1e3, 3), fmt(r["h_over_s0"], 2)]
         for r in pairs])
    t_res = md_table(
        ["pair", "Q_max/P FE", "JKR (eq. QJKR)", "double C–M", "f_s", "FE / f_s",
         "Q_max/(f_d P) FE", "max slip / Δ at Q ≈ Q_max", "min μ there", "steps", "Newton its",
         "wall s"],
        [[r["preset"], f"{r['apparent_fe']:.5f}",
          f"{r['apparent_jkr']:.4f}" + ("" if r["small_scale_ok"] else " ✗"),
          f"{r['apparent_dcm']:.4f}" + (" (b = a)" if r["dcm_truncated"] else ""),
          f"{r['fs']:.2f}", f"{r['apparent_fe'] / r['fs']:.4f}",
          f"{r['apparent_fe'] / r['fd']:.4f}",
          fmt(r["slip_max_at_vtu"] / r["delta"], 3) if r["slip_max_at_vtu"] is not None else "—",
          fmt(r["mu_min_at_vtu"], 4), str(r["steps"]), str(r["newton_iterations"]),
          f"{r['wall_s']:.1f}" if r["wall_s"] else "—"]
         for r in pairs])
    t_yld = md_table(
        ["pair", "σ_vM max pad (MPa)", "/ Y pad", "σ_vM max flat (MPa)", "/ Y flat",
         "at Q/Q_max"],
        [[r["preset"], fmt(r["von_mises_max"]["pad"], 3), f"{r['yield_ratio']['pad']:.2f}",
          fmt(r["von_mises_max"]["flat"], 3), f"{r['yield_ratio']['flat']:.2f}",
          f"{r['q_at_vtu'] / r['q_max']:.5f}"] for r in pairs if r["von_mises_max"]])
    text = ("### Materials\n\n" + t_mat + "\n\n### Parameters\n\n" + t_par
            + "\n\n### Apparent static friction\n\n" + t_res + "\n\n### Yield check\n\n" + t_yld
            + "\n")
    if JKR["name"] in results:
        r = results[JKR["name"]]
        fe = r["q_max"] / (r["fd"] * r["load_fe"])
        jkr = r["apparent_jkr"] / r["fd"]
        text += "\n### JKR check (Λ = 0.025, s0 resolved)\n\n" + md_table(
            ["case", "f_s/f_d", "Λ", "χ", "Ψ", "Δ (nm)", "P", "a (mm)", "h/s0",
             "Q_max/(f_d P) FE", "JKR", "double C–M", "FE − JKR", "Q_max/P FE", "f_s", "wall s"],
            [[r["preset"] + " (Λ = 0.025)", f"{r['fs'] / r['fd']:.4f}", fmt(r["lambda_fe"], 3),
              fmt(r["chi"], 3), fmt(r["psi"], 3), f"{r['delta'] * 1e6:.2f}", fmt(r["P"], 3),
              fmt(r["a_fe"], 4), f"{r['h_over_s0']:.3f}" + ("" if r["resolved"] else " ✗"),
              f"{fe:.5f}", f"{jkr:.5f}", f"{r['apparent_dcm'] / r['fd']:.5f}",
              f"{100 * (fe / jkr - 1):+.2f} %", f"{r['apparent_fe']:.5f}", f"{r['fs']:.2f}",
              f"{r['wall_s']:.1f}" if r["wall_s"] else "—"]]
            + ([["same, β = 0 control (E = " + f"{beta0['E'] / 1000:.1f}" + " GPa, ν = 0.3 both)",
                 f"{r['fs'] / r['fd']:.4f}", fmt(beta0["lambda"], 3), fmt(r["chi"], 3),
                 fmt(r["psi"], 3), f"{r['delta'] * 1e6:.2f}", fmt(r["P"], 3),
                 fmt(beta0["a"], 4),
                 f"{beta0['h_over_s0']:.3f}" + ("" if beta0["resolved"] else " ✗"),
                 f"{beta0['q_max_over_fdP']:.5f}", f"{beta0['jkr']:.5f}", "",
                 f"{100 * (beta0['q_max_over_fdP'] / beta0['jkr'] - 1):+.2f} %",
                 f"{beta0['q_max_over_fdP'] * r['fd']:.5f}", f"{r['fs']:.2f}",
                 f"{beta0['wall_s']:.1f}" if beta0["wall_s"] else "—"]] if beta0 else [])
        ) + "\n"
    print()
    print(text)
    with open(os.path.join(args.out, "material_pairs_tables.md"), "w") as f:
        f.write(text)
    print(f"wrote {args.out}/material_pairs_tables.md and material_pairs.json")


if __name__ == "__main__":
    main()
