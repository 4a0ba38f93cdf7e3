//! Helpers shared by the integration tests: small meshes written as MSH 4.1 text, a plain
//! linear solve with per-node Dirichlet values, error norms, and runs of the `stickslip`
//! binary on a case with its outputs read back.
#![allow(dead_code)]

pub mod rupture;
pub mod vtu;

use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use stickslip::assembly::{self, UpperCsc};
use stickslip::condense::Condensed;
use stickslip::dofs::{DofMap, SupportSpec};
use stickslip::elasticity::{self, Material};
use stickslip::la::PartialSymbolic;
use stickslip::mesh::{Group, GroupDim, Mesh, Tri6};
use stickslip::quadrature::TRI_7;
use stickslip::shapes::tri6;

pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A fresh, empty temporary directory for one test. The first call of a test process also
/// deletes the directories that earlier test processes, no longer running, left over an hour
/// ago (some tests write hundreds of MB of output, which would otherwise pile up run after
/// run).
pub fn tempdir(name: &str) -> PathBuf {
    static STALE: std::sync::Once = std::sync::Once::new();
    STALE.call_once(remove_stale_tempdirs);
    let d = std::env::temp_dir().join(format!("stickslip-test-{}-{}", name, std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Deletes `stickslip-test-*-PID` directories whose process is gone (Linux: no `/proc/PID`)
/// and that are more than an hour old (a process of another PID namespace sharing the
/// temporary directory is not in `/proc`). The fuzz reproducers of `tests/hostile.rs`
/// (`stickslip-hostile-PID`) are kept.
fn remove_stale_tempdirs() {
    let proc = std::path::Path::new("/proc");
    if !proc.join("self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(std::env::temp_dir()) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        let Some(rest) = name.strip_prefix("stickslip-test-") else {
            continue;
        };
        let Some(pid) = rest.rsplit('-').next().filter(|p| p.parse::<u32>().is_ok()) else {
            continue;
        };
        let old = e
            .metadata()
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age.as_secs() > 3600);
        if old && !proc.join(pid).exists() {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// Runs the `stickslip` binary with `args`; returns (exit status, -1 without one; stdout;
/// stderr).
pub fn stickslip(args: &[&str]) -> (i32, String, String) {
    stickslip_env(args, &[])
}

/// `stickslip sweep DIR/case.json DIR/TABLE --out OUT` followed by `extra`; returns what
/// [`stickslip`] returns.
pub fn sweep_in(dir: &Path, table: &str, out: &Path, extra: &[&str]) -> (i32, String, String) {
    let (case, table) = (dir.join("case.json"), dir.join(table));
    let mut args = vec![
        "sweep",
        case.to_str().unwrap(),
        table.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    stickslip(&args)
}

/// [`stickslip`] with the environment variables `envs` set for the process.
pub fn stickslip_env(args: &[&str], envs: &[(&str, &str)]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"))
        // No model cache: tests leave the user's cache directory alone.
        .env("STICKSLIP_NO_CACHE", "1")
        .envs(envs.iter().copied())
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// Whether `VALIDATION_WRITE_DOC` asks the tests to write their rows of the README's
/// validation table (set, and neither empty nor `0`).
pub fn validation_write_doc() -> bool {
    std::env::var_os("VALIDATION_WRITE_DOC").is_some_and(|v| !v.is_empty() && v != "0")
}

/// `v` to one significant digit in scientific notation (`4e-12`), or `0` when it is zero: for
/// round-off-level differences in the validation table.
pub fn sci(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v:.0e}")
    }
}

/// One row of the README's validation table (`| check | reference | result | test |`), written
/// to `docs/validation/<key>.md` when `VALIDATION_WRITE_DOC` is set, and nothing otherwise.
///
/// `key` starts with a three-digit order prefix (`010-patch`): sorting the file names gives
/// the row order of the table, which `post/validation_table.py` assembles into README.md and
/// docs/validation.md. `test` is the name of the test binary (`tests/<test>.rs`) that calls this
/// right after the assertions the row reports; `result` is formatted from the same variables
/// and bounds those assertions use. Cells are plain text: `|` is escaped here, line breaks
/// become spaces. The file is written to a temporary name and renamed, so it is whole or absent.
pub fn validation_row(key: &str, check: &str, reference: &str, result: &str, test: &str) {
    if !validation_write_doc() {
        return;
    }
    let (prefix, name) = key.split_at(key.find('-').unwrap_or(0));
    assert!(
        prefix.len() == 3
            && prefix.bytes().all(|b| b.is_ascii_digit())
            && name.len() > 1
            && name[1..]
                .bytes()
                .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-'),
        "validation row key `{key}`: expected NNN-name (lower case, digits, dashes)"
    );
    assert!(
        repo().join("tests").join(format!("{test}.rs")).is_file(),
        "validation row {key}: no test binary tests/{test}.rs"
    );
    let cell = |s: &str| {
        s.split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
            .replace('|', "\\|")
    };
    let line = format!(
        "| {} | {} | {} | `{test}` |\n",
        cell(check),
        cell(reference),
        cell(result)
    );
    let dir = repo().join("docs/validation");
    std::fs::create_dir_all(&dir).unwrap();
    let tmp = dir.join(format!(".{key}.md.tmp{}", std::process::id()));
    std::fs::write(&tmp, line).unwrap();
    std::fs::rename(&tmp, dir.join(format!("{key}.md"))).unwrap();
}

/// The path of `meshes/NAME` as a JSON string, for a case's `"mesh"`.
/// Makes sure `meshes/<stem>.msh` exists, building it with `meshes/generate.py <stem>` (gmsh
/// from PyPI) when it does not. Panics, never skips, when gmsh is missing: CI installs it.
pub fn ensure_mesh(stem: &str) -> PathBuf {
    // Tests of one binary run in parallel: one builds, the others wait for the whole file.
    static BUILD: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _guard = BUILD.lock().unwrap_or_else(|e| e.into_inner());
    let path = repo().join("meshes").join(format!("{stem}.msh"));
    if path.exists() {
        return path;
    }
    let out = std::process::Command::new("python3")
        .arg(repo().join("meshes/generate.py"))
        .arg(stem)
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success() && path.exists(),
        "cannot build {}: `python3 meshes/generate.py {stem}` failed (install gmsh: pip install gmsh==4.15.2): {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    path
}

pub fn mesh_path(name: &str) -> Value {
    json!(repo().join("meshes").join(name).to_str().unwrap())
}

/// `cases/FILE` as JSON, its mesh path (relative to `cases/`) made absolute.
pub fn shipped_case(file: &str) -> Value {
    let mut v: Value =
        serde_json::from_str(&std::fs::read_to_string(repo().join("cases").join(file)).unwrap())
            .unwrap();
    let mesh = v["mesh"].as_str().unwrap().trim_start_matches("../");
    v["mesh"] = json!(repo().join(mesh).to_str().unwrap());
    v
}

/// `cases/FILE` as JSON with the mesh `meshes/MESH` (absolute path).
pub fn shipped_case_on(file: &str, mesh: &str) -> Value {
    let mut v = shipped_case(file);
    v["mesh"] = mesh_path(mesh);
    v
}

/// One `stickslip run`: exit status (-1 without one), stderr and the output directory.
pub struct CaseRun {
    pub code: i32,
    pub stderr: String,
    pub out: PathBuf,
}

/// Writes `text` as `dir/file` and runs `stickslip run dir/file --out dir/out` followed by
/// `extra` arguments.
pub fn run_case_in(dir: &Path, file: &str, text: &str, extra: &[&str]) -> CaseRun {
    let path = dir.join(file);
    std::fs::write(&path, text).unwrap();
    let out = dir.join("out");
    let mut args = vec![
        "run",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let (code, _, stderr) = stickslip(&args);
    CaseRun { code, stderr, out }
}

/// Runs the case `v` (written as compact JSON to `case.json` in a fresh temporary directory
/// `name`) with `extra` arguments.
pub fn run_case(name: &str, v: &Value, extra: &[&str]) -> CaseRun {
    run_case_in(
        &tempdir(name),
        "case.json",
        &serde_json::to_string(v).unwrap(),
        extra,
    )
}

/// A numeric CSV file: its header and rows.
pub struct Table {
    pub header: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    pub fn read(path: &Path) -> Table {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        let header = lines
            .next()
            .unwrap()
            .split(',')
            .map(str::to_string)
            .collect();
        let rows = lines
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect();
        Table { header, rows }
    }

    /// The index of the column `name`.
    pub fn col(&self, name: &str) -> usize {
        self.header.iter().position(|h| h == name).unwrap()
    }

    /// The value of column `name` in the last row.
    pub fn last(&self, name: &str) -> f64 {
        self.rows.last().unwrap()[self.col(name)]
    }
}

impl CaseRun {
    /// Asserts exit status 0, naming `what` and the stderr otherwise.
    pub fn assert_ok(&self, what: &str) -> &Self {
        assert_eq!(self.code, 0, "{what} failed: {}", self.stderr);
        self
    }

    /// `history.csv`.
    pub fn history(&self) -> Table {
        Table::read(&self.out.join("history.csv"))
    }

    /// `summary.json`.
    pub fn summary(&self) -> Value {
        serde_json::from_str(&std::fs::read_to_string(self.out.join("summary.json")).unwrap())
            .unwrap()
    }

    /// `contact_NNNN.csv` of step `step`.
    pub fn contact(&self, step: usize) -> Table {
        Table::read(&self.out.join(format!("contact_{step:04}.csv")))
    }

    /// The contact CSV of the last step in `history.csv`.
    pub fn last_contact(&self) -> Table {
        self.contact(self.history().rows.last().unwrap()[0] as usize)
    }

    /// Whether the output directory exists.
    pub fn wrote_output(&self) -> bool {
        self.out.exists()
    }
}

/// MSH 4.1 text of the bodies `surfaces` with the four sides of [`structured`] as the curve
/// groups bottom, right, top, left.
pub fn msh41_sides(
    nodes: &[[f64; 2]],
    surfaces: &[(&str, Vec<[usize; 6]>)],
    sides: [Vec<[usize; 3]>; 4],
) -> String {
    let [b, r, t, l] = sides;
    msh41(
        nodes,
        surfaces,
        &[("bottom", b), ("right", r), ("top", t), ("left", l)],
    )
}

/// Two flat blocks with non-matching meshes: lower [0,2]×[0,1] with `lower` = (nx, ny) cells,
/// upper [0,2]×[y0, y0+1] with `upper` cells, interior vertices moved by `distort`; groups
/// lower, upper, bottom, lower_top, lower_left, upper_bottom, top, upper_left.
pub fn two_blocks(lower: [usize; 2], upper: [usize; 2], y0: f64, distort: f64) -> String {
    let (n1, t1, s1) = structured(lower[0], lower[1], 0.0, 2.0, 0.0, 1.0, distort);
    let (n2, t2, s2) = structured(upper[0], upper[1], 0.0, 2.0, y0, y0 + 1.0, distort);
    let off = n1.len();
    let mut nodes = n1;
    nodes.extend(n2);
    let shift = |v: &Vec<[usize; 3]>| v.iter().map(|e| e.map(|k| k + off)).collect::<Vec<_>>();
    let t2: Vec<[usize; 6]> = t2.iter().map(|t| t.map(|k| k + off)).collect();
    let [b1, _, top1, l1] = s1;
    let [b2, _, top2, l2] = &s2;
    msh41(
        &nodes,
        &[("lower", t1), ("upper", t2)],
        &[
            ("bottom", b1),
            ("lower_top", top1),
            ("lower_left", l1),
            ("upper_bottom", shift(b2)),
            ("top", shift(top2)),
            ("upper_left", shift(l2)),
        ],
    )
}

/// Writes an ASCII MSH 4.1 file: `surfaces` are (name, 6-node triangles), `curves` are
/// (name, 3-node lines); node indices are 0-based into `nodes` (written as tags 1..).
pub fn msh41(
    nodes: &[[f64; 2]],
    surfaces: &[(&str, Vec<[usize; 6]>)],
    curves: &[(&str, Vec<[usize; 3]>)],
) -> String {
    let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n");
    s += &format!("{}\n", surfaces.len() + curves.len());
    for (i, (n, _)) in curves.iter().enumerate() {
        s += &format!("1 {} \"{}\"\n", i + 1, n);
    }
    for (i, (n, _)) in surfaces.iter().enumerate() {
        s += &format!("2 {} \"{}\"\n", 100 + i, n);
    }
    s += "$EndPhysicalNames\n$Entities\n";
    s += &format!("0 {} {} 0\n", curves.len(), surfaces.len());
    for i in 0..curves.len() {
        s += &format!("{} 0 0 0 1 1 0 1 {} 0\n", i + 1, i + 1);
    }
    for i in 0..surfaces.len() {
        s += &format!("{} 0 0 0 1 1 0 1 {} 0\n", i + 1, 100 + i);
    }
    s += "$EndEntities\n$Nodes\n";
    s += &format!(
        "1 {} 1 {}\n2 1 0 {}\n",
        nodes.len(),
        nodes.len(),
        nodes.len()
    );
    for i in 0..nodes.len() {
        s += &format!("{}\n", i + 1);
    }
    for p in nodes {
        s += &format!("{:.17e} {:.17e} 0\n", p[0], p[1]);
    }
    s += "$EndNodes\n$Elements\n";
    let ne: usize = surfaces.iter().map(|x| x.1.len()).sum::<usize>()
        + curves.iter().map(|x| x.1.len()).sum::<usize>();
    s += &format!("{} {} 1 {}\n", curves.len() + surfaces.len(), ne, ne);
    let mut tag = 1;
    for (i, (_, ls)) in curves.iter().enumerate() {
        s += &format!("1 {} 8 {}\n", i + 1, ls.len());
        for l in ls {
            s += &format!("{} {} {} {}\n", tag, l[0] + 1, l[1] + 1, l[2] + 1);
            tag += 1;
        }
    }
    for (i, (_, ts)) in surfaces.iter().enumerate() {
        s += &format!("2 {} 9 {}\n", i + 1, ts.len());
        for t in ts {
            s += &format!("{}", tag);
            for n in t {
                s += &format!(" {}", n + 1);
            }
            s += "\n";
            tag += 1;
        }
    }
    s += "$EndElements\n";
    s
}

/// Nodes, 6-node triangles and the 3-node edges of the four sides of a structured mesh.
pub type Structured = (Vec<[f64; 2]>, Vec<[usize; 6]>, [Vec<[usize; 3]>; 4]);

/// A structured mesh of the rectangle [x0,x1]×[y0,y1] with `nx × ny` cells split into 6-node
/// triangles; interior vertices moved by `distort` (fraction of the cell size, deterministic
/// pseudo-random). Returns nodes, triangles and the boundary lines of the four sides
/// (bottom, right, top, left).
pub fn structured(
    nx: usize,
    ny: usize,
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    distort: f64,
) -> Structured {
    // Grid of (2nx+1) × (2ny+1) points; even indices are vertices.
    let (mx, my) = (2 * nx + 1, 2 * ny + 1);
    let id = |i: usize, j: usize| j * mx + i;
    let mut nodes = vec![[0.0; 2]; mx * my];
    let (hx, hy) = ((x1 - x0) / nx as f64, (y1 - y0) / ny as f64);
    for j in 0..my {
        for i in 0..mx {
            nodes[id(i, j)] = [x0 + 0.5 * hx * i as f64, y0 + 0.5 * hy * j as f64];
        }
    }
    // Move interior vertices, then put mid-edge nodes back at straight midpoints.
    let mut seed = 12345u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 33) as f64 / (1u64 << 31) as f64) - 0.5
    };
    for j in (2..my - 1).step_by(2) {
        for i in (2..mx - 1).step_by(2) {
            nodes[id(i, j)][0] += distort * hx * rnd();
            nodes[id(i, j)][1] += distort * hy * rnd();
        }
    }
    let mid = |a: [f64; 2], b: [f64; 2]| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    let mut tris = Vec::new();
    for cj in 0..ny {
        for ci in 0..nx {
            let (i, j) = (2 * ci, 2 * cj);
            let (a, b, c, d) = (id(i, j), id(i + 2, j), id(i + 2, j + 2), id(i, j + 2));
            tris.push([a, b, c, id(i + 1, j), id(i + 2, j + 1), id(i + 1, j + 1)]);
            tris.push([a, c, d, id(i + 1, j + 1), id(i + 1, j + 2), id(i, j + 1)]);
        }
    }
    for t in &tris {
        for ed in tri6::EDGE_NODE_IDS {
            nodes[t[ed[2]]] = mid(nodes[t[ed[0]]], nodes[t[ed[1]]]);
        }
    }
    let bottom = (0..nx)
        .map(|c| [id(2 * c, 0), id(2 * c + 2, 0), id(2 * c + 1, 0)])
        .collect();
    let right = (0..ny)
        .map(|c| {
            [
                id(mx - 1, 2 * c),
                id(mx - 1, 2 * c + 2),
                id(mx - 1, 2 * c + 1),
            ]
        })
        .collect();
    let top = (0..nx)
        .map(|c| {
            [
                id(2 * c + 2, my - 1),
                id(2 * c, my - 1),
                id(2 * c + 1, my - 1),
            ]
        })
        .collect();
    let left = (0..ny)
        .map(|c| [id(0, 2 * c + 2), id(0, 2 * c), id(0, 2 * c + 1)])
        .collect();
    (nodes, tris, [bottom, right, top, left])
}

/// A `Mesh` with one body group `body` from nodes and triangles.
pub fn mesh_from(nodes: Vec<[f64; 2]>, tris: Vec<[usize; 6]>) -> Mesh {
    let n = tris.len();
    Mesh {
        source: "generated".into(),
        node_tags: (1..=nodes.len() as u64).collect(),
        nodes,
        triangles: tris
            .into_iter()
            .enumerate()
            .map(|(i, t)| Tri6 {
                nodes: t,
                tag: i as u64 + 1,
            })
            .collect(),
        lines: vec![],
        groups: vec![Group {
            name: "body".into(),
            dim: GroupDim::Surface,
            tag: 1,
            elements: (0..n).collect(),
        }],
        reoriented: vec![],
    }
}

/// Solves linear elasticity on all triangles of `mesh` with per-node prescribed displacements
/// per component (`dirichlet(node) = [Some(ux), None]` …), a body force and extra free-vector forces from `extra`.
/// Returns the DOF map and the free solution.
pub fn solve_linear(
    mesh: &Mesh,
    mat: Material,
    dirichlet: &dyn Fn(usize) -> [Option<f64>; 2],
    body: Option<&dyn Fn([f64; 2]) -> [f64; 2]>,
) -> (DofMap, Vec<f64>) {
    solve_linear_with(mesh, mat, dirichlet, body, &|_, _| {})
}

/// As [`solve_linear`], with `extra(dofs, f)` adding further forces to the free vector.
pub fn solve_linear_with(
    mesh: &Mesh,
    mat: Material,
    dirichlet: &dyn Fn(usize) -> [Option<f64>; 2],
    body: Option<&dyn Fn([f64; 2]) -> [f64; 2]>,
    extra: &dyn Fn(&DofMap, &mut [f64]),
) -> (DofMap, Vec<f64>) {
    let elems: Vec<(usize, Material)> = (0..mesh.triangles.len()).map(|e| (e, mat)).collect();
    let active = vec![true; mesh.nodes.len()];
    let fixed: Vec<(usize, [Option<f64>; 2])> = (0..mesh.nodes.len())
        .map(|n| (n, dirichlet(n)))
        .filter(|(_, v)| v[0].is_some() || v[1].is_some())
        .collect();
    let single: Vec<[usize; 1]> = fixed.iter().map(|(n, _)| [*n]).collect();
    let supports: Vec<SupportSpec> = fixed
        .iter()
        .zip(&single)
        .map(|((_, u), nodes)| SupportSpec {
            group: "dirichlet",
            nodes,
            value: *u,
        })
        .collect();
    let dofs = DofMap::build(&mesh.node_tags, &active, &supports, None, &[]).unwrap();
    let mut k = UpperCsc::pattern(mesh, &elems, &dofs);
    let mut f = assembly::assemble_stiffness(mesh, &elems, &dofs, &mut k);
    if let Some(b) = body {
        for (e, _) in &elems {
            let fe = elasticity::element_body_force(&mesh.tri_coords(*e), b);
            assembly::add_element_vector(&dofs, &mesh.triangles[*e].nodes, &fe, &mut f);
        }
    }
    extra(&dofs, &mut f);
    let sym = PartialSymbolic::analyse(dofs.n_free(), 0, &k.col_ptr, &k.row_idx).unwrap();
    let cond = Condensed::build(&k, dofs.n_interior, &[], &sym).unwrap();
    let u = cond.recover(&f, &[], &[]);
    (dofs, u)
}

/// L2 norm of the displacement error and energy norm of the error,
/// `sqrt(∫ (ε_h − ε):D:(ε_h − ε))`, with the 7-point rule.
pub fn error_norms(
    mesh: &Mesh,
    mat: &Material,
    dofs: &DofMap,
    u: &[f64],
    exact: &dyn Fn([f64; 2]) -> [f64; 2],
    exact_strain: &dyn Fn([f64; 2]) -> [f64; 3],
) -> (f64, f64) {
    let (mut l2, mut en) = (0.0, 0.0);
    for (e, t) in mesh.triangles.iter().enumerate() {
        let xe = mesh.tri_coords(e);
        let ue: [f64; 12] = std::array::from_fn(|i| dofs.displacement(t.nodes[i / 2], u)[i % 2]);
        for (p, w) in TRI_7.iter() {
            let mp = tri6::map_point(&xe, p[0], p[1]);
            let mut uh = [0.0; 2];
            for a in 0..6 {
                uh[0] += mp.n[a] * ue[2 * a];
                uh[1] += mp.n[a] * ue[2 * a + 1];
            }
            let ux = exact(mp.x);
            l2 += w * mp.det_j * ((uh[0] - ux[0]).powi(2) + (uh[1] - ux[1]).powi(2));
            let eh = elasticity::strain(&mp, &ue);
            let ex = exact_strain(mp.x);
            let d = [eh[0] - ex[0], eh[1] - ex[1], eh[2] - ex[2]];
            let s = mat.stress(d);
            en += w * mp.det_j * (s[0] * d[0] + s[1] * d[1] + s[2] * d[2]);
        }
    }
    (l2.sqrt(), en.sqrt())
}

/// Least-squares slope of log(err) against log(h).
pub fn fitted_rate(h: &[f64], err: &[f64]) -> f64 {
    let n = h.len() as f64;
    let x: Vec<f64> = h.iter().map(|v| v.ln()).collect();
    let y: Vec<f64> = err.iter().map(|v| v.ln()).collect();
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    sxy / sxx
}

/// Adds the consistent nodal forces of a traction field `t(x, n)` (n: outward unit normal) on
/// the lines of a curve group, 5-point Gauss per edge.
pub fn add_edge_traction(
    mesh: &Mesh,
    group: &str,
    dofs: &DofMap,
    f: &mut [f64],
    t: &dyn Fn([f64; 2], [f64; 2]) -> [f64; 2],
) {
    use stickslip::shapes::lin3;
    let tris: Vec<usize> = (0..mesh.triangles.len()).collect();
    let orient = stickslip::loads::EdgeOrientation::new(mesh, &tris);
    for &l in &mesh.group(group).unwrap().elements {
        let nodes = orient.oriented_nodes(mesh, l).unwrap();
        let xe = nodes.map(|n| mesh.nodes[n]);
        for &(s, w) in stickslip::quadrature::gauss_legendre(5) {
            let tg = lin3::tangent(&xe, s);
            let j = tg[0].hypot(tg[1]);
            let tv = t(lin3::point(&xe, s), [tg[1] / j, -tg[0] / j]);
            let n = lin3::n(s);
            for a in 0..3 {
                for c in 0..2 {
                    if let stickslip::dofs::Dof::Free(i) = dofs.node[nodes[a]][c] {
                        f[i] += w * j * n[a] * tv[c];
                    }
                }
            }
        }
    }
}

/// The names of the entries of `dir`, sorted.
pub fn file_names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    names.sort();
    names
}

/// Starts `stickslip ARGS` (with `envs` set; `STICKSLIP_NO_CACHE=1` unless `envs` clears it by
/// giving it empty), polls `until` every 200 µs for at most `secs` seconds, then kills the
/// process (SIGKILL) if it is still running. Returns whether `until` held before the kill.
pub fn kill_when(
    args: &[&str],
    envs: &[(&str, &str)],
    secs: u64,
    until: &dyn Fn() -> bool,
) -> bool {
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_stickslip"));
    cmd.env("STICKSLIP_NO_CACHE", "1");
    for (k, v) in envs {
        if v.is_empty() {
            cmd.env_remove(k);
        } else {
            cmd.env(k, v);
        }
    }
    let mut child = cmd
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    let mut held = false;
    while t0.elapsed().as_secs() < secs {
        if until() {
            held = true;
            break;
        }
        if child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_micros(200));
    }
    let _ = child.kill();
    child.wait().unwrap();
    held
}
