//! Hostile input: random mutations and truncations of real mesh files fed to the mesh reader
//! and the mesh checks, random mutations of the shipped case files fed to the case parser and
//! its validation, and a list of hand-made bad inputs fed to the `stickslip` binary.
//!
//! Nothing may panic or hang. The fuzz loops are deterministic (a fixed seed; set
//! `HOSTILE_SEED` to explore others) and bounded by a time budget per input file
//! (`HOSTILE_FUZZ_SECS`, default 4 s). A panic writes its input to the temporary directory and
//! names it. The CLI cases run the binary with a timeout; each one must end with a clear message
//! and a non-zero exit status (or complete, where that is legitimate), never with a panic (exit
//! status 101) or a hang. `HOSTILE_WRITE_DOC=1` rewrites `docs/hostile_inputs.md` from these
//! runs.

mod common;
use common::*;
use serde_json::{Value, json};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex, mpsc};
use std::time::{Duration, Instant};
use stickslip::case::Case;
use stickslip::mesh::{GroupDim, check, gmsh, info};

// ---------------------------------------------------------------------------------------------
// Deterministic randomness and mutations
// ---------------------------------------------------------------------------------------------

/// splitmix64.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e3779b97f4a7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
    fn pick<'a, T>(&mut self, v: &'a [T]) -> &'a T {
        &v[self.below(v.len())]
    }
}

fn base_seed() -> u64 {
    std::env::var("HOSTILE_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0x5717_c45e_1f00_d5ee)
}

/// With `HOSTILE_FUZZ_SECS` set, the time budget alone bounds the fuzz loops (no iteration cap).
fn iteration_cap(default: usize) -> usize {
    if std::env::var("HOSTILE_FUZZ_SECS").is_ok() {
        usize::MAX
    } else {
        default
    }
}

fn fuzz_budget() -> Duration {
    let s = std::env::var("HOSTILE_FUZZ_SECS")
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
        .unwrap_or(4.0);
    Duration::from_secs_f64(s)
}

/// Number tokens that break parsers: zero, negative, huge, overflowing, non-finite.
const NASTY_TOKENS: &[&str] = &[
    "0",
    "-1",
    "1",
    "2",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "1e400",
    "-1e308",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "18446744073709551616",
    "9223372036854775807",
    "-9223372036854775808",
    "99999999999999999999999",
    "0.5",
    "",
    "x",
];

/// Integers written into binary data (counts, tags, sizes).
const NASTY_INTS: &[u64] = &[
    0,
    1,
    2,
    3,
    8,
    9,
    15,
    0x7f,
    0xff,
    0xffff,
    0x7fff_ffff,
    0xffff_ffff,
    0x1_0000_0000,
    1 << 40,
    u64::MAX / 24,
    u64::MAX,
    u64::MAX - 1,
    i64::MAX as u64,
];

const SECTION_MARKERS: &[&[u8]] = &[
    b"$MeshFormat",
    b"$PhysicalNames",
    b"$Entities",
    b"$Nodes",
    b"$Elements",
    b"$EndNodes",
    b"$EndElements",
];

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// A position in `b`: anywhere, or (half the time) within 300 bytes after a section marker,
/// where the counts and sizes live.
fn position(rng: &mut Rng, b: &[u8]) -> usize {
    if b.is_empty() {
        return 0;
    }
    if rng.below(2) == 0 {
        let m = rng.pick(SECTION_MARKERS);
        if let Some(p) = find(b, m) {
            return (p + rng.below(300)).min(b.len() - 1);
        }
    }
    rng.below(b.len())
}

/// One random mutation of a byte string.
fn mutate_bytes(rng: &mut Rng, b: &mut Vec<u8>) -> String {
    let n = b.len();
    match rng.below(9) {
        0 => {
            let at = position(rng, b);
            b.truncate(at);
            format!("truncate at {at}")
        }
        1 => {
            let at = position(rng, b);
            if at < n {
                let bit = rng.below(8);
                b[at] ^= 1 << bit;
            }
            format!("flip a bit at {at}")
        }
        2 => {
            let at = position(rng, b);
            let c = *rng.pick(b"0123456789 -.\n\t$eE+\0\"");
            if at < n {
                b[at] = c;
            }
            format!("byte {at} := {c:?}")
        }
        3 => {
            let at = position(rng, b);
            let len = 1 + rng.below(64);
            let end = (at + len).min(n);
            b.drain(at..end);
            format!("delete {at}..{end}")
        }
        4 => {
            let at = position(rng, b);
            let len = 1 + rng.below(256);
            let end = (at + len).min(n);
            let chunk = b[at..end].to_vec();
            let to = position(rng, b);
            b.splice(to..to, chunk);
            format!("copy {at}..{end} to {to}")
        }
        5 => {
            // Replace the ASCII number token around a position by a nasty one.
            let at = position(rng, b);
            let is_num =
                |c: u8| c.is_ascii_digit() || c == b'-' || c == b'.' || c == b'e' || c == b'+';
            let (mut s, mut e) = (at, at);
            while s > 0 && is_num(b[s - 1]) {
                s -= 1;
            }
            while e < n && is_num(b[e]) {
                e += 1;
            }
            let tok = *rng.pick(NASTY_TOKENS);
            b.splice(s..e, tok.bytes());
            format!("token {s}..{e} := {tok:?}")
        }
        6 | 7 => {
            // Overwrite 4 or 8 bytes with a nasty little-endian integer (binary counts, tags).
            let at = position(rng, b);
            let v = *rng.pick(NASTY_INTS);
            let w = if rng.below(2) == 0 { 4 } else { 8 };
            let bytes = v.to_le_bytes();
            for k in 0..w {
                if at + k < b.len() {
                    b[at + k] = bytes[k];
                }
            }
            format!("{w} bytes at {at} := {v:#x}")
        }
        _ => {
            // Remove or duplicate a whole line.
            let at = position(rng, b);
            let s = b[..at.min(n)]
                .iter()
                .rposition(|&c| c == b'\n')
                .map_or(0, |p| p + 1);
            let e = b[at.min(n)..]
                .iter()
                .position(|&c| c == b'\n')
                .map_or(n, |p| at + p + 1);
            if rng.below(2) == 0 {
                b.drain(s..e);
                format!("delete line {s}..{e}")
            } else {
                let line = b[s..e].to_vec();
                b.splice(e..e, line);
                format!("duplicate line {s}..{e}")
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Fuzz driver: runs the target on a worker thread so that a hang is reported, not waited for
// ---------------------------------------------------------------------------------------------

struct Finding {
    what: String,
    saved: PathBuf,
}

/// Mutates `original` repeatedly for `budget` and feeds each mutant to `target` inside
/// `catch_unwind`. Returns the number of inputs tried, how many the target accepted, the
/// slowest call, and the panics found (each input saved to a file).
fn fuzz(
    label: &str,
    original: Vec<u8>,
    budget: Duration,
    max_iters: usize,
    target: fn(&[u8]) -> bool,
) -> (usize, usize, Duration, Vec<Finding>) {
    let current: Arc<Mutex<(u64, Vec<u8>, String)>> =
        Arc::new(Mutex::new((0, vec![], String::new())));
    let cur = current.clone();
    let (tx, rx) = mpsc::channel();
    let seed = base_seed() ^ fxhash(label.as_bytes());
    let label_s = label.to_string();
    let saved_dir = std::env::temp_dir().join(format!("stickslip-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&saved_dir).unwrap();
    let sd = saved_dir.clone();
    std::thread::spawn(move || {
        let start = Instant::now();
        let (mut tried, mut accepted) = (0usize, 0usize);
        let mut slowest = Duration::ZERO;
        let mut findings = Vec::new();
        while start.elapsed() < budget && tried < max_iters {
            let iseed = seed.wrapping_add(tried as u64);
            let mut rng = Rng(iseed);
            let mut b = original.clone();
            let mut how = Vec::new();
            for _ in 0..1 + rng.below(3) {
                how.push(mutate_bytes(&mut rng, &mut b));
            }
            let how = how.join("; ");
            *cur.lock().unwrap() = (iseed, b.clone(), how.clone());
            let t0 = Instant::now();
            let r = catch_unwind(AssertUnwindSafe(|| target(&b)));
            slowest = slowest.max(t0.elapsed());
            tried += 1;
            match r {
                Ok(true) => accepted += 1,
                Ok(false) => {}
                Err(e) => {
                    let msg = e
                        .downcast_ref::<String>()
                        .cloned()
                        .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
                        .unwrap_or_default();
                    let saved = sd.join(format!("{label_s}-panic-{iseed:x}"));
                    std::fs::write(&saved, &b).unwrap();
                    findings.push(Finding {
                        what: format!("seed {iseed:#x} ({how}): panic: {msg}"),
                        saved,
                    });
                }
            }
        }
        tx.send((tried, accepted, slowest, findings)).unwrap();
    });
    match rx.recv_timeout(budget + Duration::from_secs(20)) {
        Ok(r) => r,
        Err(_) => {
            let (iseed, b, how) = current.lock().unwrap().clone();
            let saved = saved_dir.join(format!("{label}-hang-{iseed:x}"));
            std::fs::write(&saved, &b).unwrap();
            panic!(
                "{label}: the target did not return within 20 s on seed {iseed:#x} ({how}); input saved to {}",
                saved.display()
            );
        }
    }
}

fn fxhash(b: &[u8]) -> u64 {
    b.iter().fold(0xcbf29ce484222325u64, |h, &c| {
        (h ^ c as u64).wrapping_mul(0x100000001b3)
    })
}

/// The mesh reader, then (if it accepts the file) the checks on every group and `mesh-info`.
fn mesh_target(b: &[u8]) -> bool {
    let Ok(mesh) = gmsh::parse(b, Path::new("fuzz.msh")) else {
        return false;
    };
    let bodies: Vec<&str> = mesh
        .groups
        .iter()
        .filter(|g| g.dim == GroupDim::Surface)
        .map(|g| g.name.as_str())
        .collect();
    let curves: Vec<&str> = mesh
        .groups
        .iter()
        .filter(|g| g.dim == GroupDim::Curve)
        .map(|g| g.name.as_str())
        .collect();
    let _ = check::check(&mesh, &bodies, &curves);
    for b in &bodies {
        let _ = check::check(&mesh, &[b], &[]);
    }
    let _ = info::info(&mesh);
    true
}

fn report(label: &str, r: &(usize, usize, Duration, Vec<Finding>)) -> Vec<String> {
    println!(
        "{label}: {} mutants, {} accepted by the reader, slowest {:.1} ms, {} panic(s)",
        r.0,
        r.1,
        r.2.as_secs_f64() * 1e3,
        r.3.len()
    );
    r.3.iter()
        .map(|f| format!("{label}: {} — input saved to {}", f.what, f.saved.display()))
        .collect()
}

#[test]
fn mutated_mesh_files_never_panic_or_hang() {
    let mut failures = Vec::new();
    // (file, mutants, accepted by the reader) for the validation table.
    let mut counts = Vec::new();
    let (min_mutants, slowest) = (20, Duration::from_secs(5));
    for (file, iters) in [
        ("meshes/patch_curved.msh", 20_000),
        ("meshes/vm272_L0.msh", 4_000),
        ("meshes/vm272_L1_ascii.msh", 2_000),
    ] {
        let bytes = std::fs::read(repo().join(file)).unwrap();
        assert!(
            mesh_target(&bytes),
            "{file}: the unmutated file must be accepted"
        );
        let r = fuzz(
            Path::new(file).file_name().unwrap().to_str().unwrap(),
            bytes,
            fuzz_budget(),
            iteration_cap(iters),
            mesh_target,
        );
        failures.extend(report(file, &r));
        assert!(
            r.0 >= min_mutants,
            "{file}: only {} mutants in the budget",
            r.0
        );
        assert!(
            r.2 < slowest,
            "{file}: one mutant took {:?} to read and check",
            r.2
        );
        counts.push(format!(
            "{} ({} mutants, {} accepted)",
            Path::new(file).file_name().unwrap().to_string_lossy(),
            r.0,
            r.1
        ));
    }
    assert!(failures.is_empty(), "panics:\n{}", failures.join("\n"));
    validation_row(
        "281-fuzz-mesh",
        "hostile input: bounded fixed-seed fuzz of the mesh reader, mesh checks and `mesh-info` (random byte, number and section mutations and truncations of real MSH 4.1 files)",
        "—",
        &format!(
            "{}: no panic, each mutant read and checked in under {} s (at least {min_mutants} mutants per file within the time budget)",
            counts.join(", "),
            slowest.as_secs()
        ),
        "hostile",
    );
}

/// Hand-picked mesh files: empty, headers only, huge counts with no data.
#[test]
fn degenerate_mesh_files_are_refused_without_panic() {
    let head = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("empty", vec![]),
        ("header only", head.into()),
        ("binary header, nothing else", b"$MeshFormat\n4.1 1 8\n\x01\x00\x00\x00\n$EndMeshFormat\n".to_vec()),
        ("no nodes", format!("{head}$Nodes\n0 0 0 0\n$EndNodes\n$Elements\n0 0 0 0\n$EndElements\n").into()),
        ("huge node count, no data", format!("{head}$Nodes\n1 18446744073709551615 1 18446744073709551615\n2 1 0 18446744073709551615\n$EndNodes\n").into()),
        ("huge block count", format!("{head}$Nodes\n18446744073709551615 1 1 1\n$EndNodes\n").into()),
        ("huge physical-name count", format!("{head}$PhysicalNames\n18446744073709551615\n$EndPhysicalNames\n").into()),
        ("unterminated physical names", format!("{head}$PhysicalNames\n1\n2 1 \"a\"\n").into()),
        ("version 4.1 with size_t 3", "$MeshFormat\n4.1 1 3\n\x01\x00\x00\x00\n$EndMeshFormat\n$Nodes\n".into()),
        ("version 4.1 with size_t 2^32", "$MeshFormat\n4.1 0 4294967296\n$EndMeshFormat\n$Nodes\n".into()),
        ("version 4.1 with size_t 0", "$MeshFormat\n4.1 0 0\n$EndMeshFormat\n$Nodes\n1 1 1 1\n2 1 0 1\n1\n0 0 0\n$EndNodes\n".into()),
        ("NaN coordinates", format!("{head}$Nodes\n1 1 1 1\n2 1 0 1\n1\nnan nan 0\n$EndNodes\n$Elements\n0 0 0 0\n$EndElements\n").into()),
        ("version 4", "$MeshFormat\n4 0 8\n$EndMeshFormat\n".into()),
        (
            "triangles on a curve entity",
            std::fs::read_to_string(repo().join("meshes/patch_curved.msh"))
                .unwrap()
                .replacen("\n2 1 9 26\n", "\n1 1 9 26\n", 1)
                .into(),
        ),
        ("version 99", "$MeshFormat\n99 0 8\n$EndMeshFormat\n".into()),
        ("only a marker", "$MeshFormat".into()),
        ("non-UTF-8", vec![0xff, 0xfe, 0x00, 0x24, 0x4d]),
    ];
    for (what, b) in cases {
        let r = catch_unwind(AssertUnwindSafe(|| mesh_target(&b)));
        assert!(r.is_ok(), "{what}: the mesh reader panicked");
    }
}

// ---------------------------------------------------------------------------------------------
// Case files
// ---------------------------------------------------------------------------------------------

fn case_target(b: &[u8]) -> bool {
    let Ok(text) = std::str::from_utf8(b) else {
        return false;
    };
    let Ok(case) = serde_json::from_str::<Case>(text) else {
        return false;
    };
    let ok = case.validate("x").is_ok();
    let _ = case.total_steps();
    let _ = case.mesh_path(Path::new("cases/x.json"));
    if let Some(c) = &case.contact
        && let Some(f) = &c.friction
    {
        for e_star in [109.89, 0.0, -1.0, f64::MIN_POSITIVE, 1e300] {
            if let Ok(law) = f.resolve(e_star) {
                for u in [0.0, 1e-9, 1e-3, 1.0, 1e300, -1.0, f64::NAN] {
                    let _ = law.mu(u);
                    let _ = law.dmu_du(u);
                }
                let _ = law.f_static();
                let _ = law.f_dynamic();
            }
        }
    }
    ok
}

/// Values that replace a leaf of a case: wrong types, out of range, huge, tiny, empty.
fn nasty_values() -> Vec<Value> {
    vec![
        json!(0),
        json!(-1),
        json!(-0.0),
        json!(1e308),
        json!(-1e308),
        json!(5e-324),
        json!(0.5),
        json!(u64::MAX),
        json!(i64::MIN),
        json!("1.0"),
        json!(""),
        json!("lower_body"),
        json!(null),
        json!(true),
        json!([]),
        json!([[0.0, 0.2]]),
        json!([[0.0, 0.2], [0.0, 0.1]]),
        json!([[1.0, 0.2], [0.0, 0.1]]),
        json!({}),
        json!({"force": 1e308}),
        json!({"displacement": -1e308}),
        json!({"force": 1.0, "displacement": 1.0}),
        json!({"shape": "table", "rows": [[0.0, 0.2]]}),
        json!({"shape": "table", "rows": [[0.0, -0.2], [1.0, 0.1]]}),
        json!({"shape": "ramp", "fs": 0.1, "fd": 0.2, "delta": 0.001}),
        json!({"shape": "ramp", "fs": 0.1, "fd": 0.1, "delta": 0.0}),
        json!({"shape": "exponential", "fs": 1e308, "fd": 0.0, "delta": 5e-324}),
        json!({"shape": "ramp", "fs": 0.15, "fd": 0.1, "lambda": 1e308, "radius": 5e-324, "load": 1e308}),
        json!({"shape": "ramp", "fs": 0.15, "fd": 0.1, "lambda": 0.05, "radius": 4.0, "load": 0.0}),
        json!({"preset": "copper-mild-steel", "shape": "step"}),
        json!({"preset": ""}),
    ]
}

/// Every leaf and container of a JSON value, as JSON pointers.
fn pointers(v: &Value, at: String, out: &mut Vec<String>) {
    out.push(at.clone());
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                pointers(x, format!("{at}/{k}"), out);
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                pointers(x, format!("{at}/{i}"), out);
            }
        }
        _ => {}
    }
}

fn mutate_case(rng: &mut Rng, v: &mut Value, nasty: &[Value]) -> String {
    let mut ps = Vec::new();
    pointers(v, String::new(), &mut ps);
    let p = rng.pick(&ps).clone();
    match rng.below(4) {
        0 | 1 => {
            let x = rng.pick(nasty).clone();
            let s = format!("{p} := {x}");
            if let Some(t) = v.pointer_mut(&p) {
                *t = x;
            }
            s
        }
        2 => {
            // Remove a key or an array element.
            let (parent, last) = p.rsplit_once('/').unwrap_or(("", ""));
            if let Some(t) = v.pointer_mut(parent) {
                match t {
                    Value::Object(m) => {
                        m.remove(last);
                    }
                    Value::Array(a) => {
                        if let Ok(i) = last.parse::<usize>()
                            && i < a.len()
                        {
                            a.remove(i);
                        }
                    }
                    _ => {}
                }
            }
            format!("remove {p}")
        }
        _ => {
            // Duplicate an array element (e.g. a second body, stage or support).
            if let Some(Value::Array(a)) = v.pointer_mut(&p)
                && !a.is_empty()
            {
                let x = a[0].clone();
                a.push(x);
            }
            format!("duplicate first element of {p}")
        }
    }
}

#[test]
fn mutated_case_files_never_panic() {
    let nasty = nasty_values();
    let mut files: Vec<PathBuf> = std::fs::read_dir(repo().join("cases"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    assert!(!files.is_empty());
    let mut failures = Vec::new();
    let budget = fuzz_budget().mul_f64(0.25);
    // Mutants over all files: (byte-level, structural, structural ones still valid).
    let (mut bytes_total, mut struct_total, mut valid_total) = (0, 0, 0);
    let hang = Duration::from_secs(2);
    for f in &files {
        let text = std::fs::read(f).unwrap();
        assert!(
            case_target(&text),
            "{}: the shipped case must be valid",
            f.display()
        );
        let name = f.file_name().unwrap().to_str().unwrap().to_string();
        // Byte-level mutations of the text.
        let r = fuzz(
            &format!("{name}-bytes"),
            text.clone(),
            budget,
            iteration_cap(5_000),
            case_target,
        );
        failures.extend(report(&format!("{name} (bytes)"), &r));
        // Structural mutations: leaves replaced by nasty values, keys removed, arrays grown.
        let v0: Value = serde_json::from_slice(&text).unwrap();
        let start = Instant::now();
        let (mut tried, mut accepted) = (0, 0);
        let mut rng = Rng(base_seed() ^ fxhash(name.as_bytes()));
        while start.elapsed() < budget && tried < iteration_cap(5_000) {
            let mut v = v0.clone();
            let mut how = Vec::new();
            for _ in 0..1 + rng.below(3) {
                how.push(mutate_case(&mut rng, &mut v, &nasty));
            }
            let s = serde_json::to_string_pretty(&v).unwrap();
            let t0 = Instant::now();
            match catch_unwind(AssertUnwindSafe(|| case_target(s.as_bytes()))) {
                Ok(a) => accepted += a as usize,
                Err(_) => failures.push(format!("{name}: {} panics:\n{s}", how.join("; "))),
            }
            assert!(
                t0.elapsed() < hang,
                "{name}: {} took {:?}",
                how.join("; "),
                t0.elapsed()
            );
            tried += 1;
        }
        println!("{name} (structure): {tried} mutants, {accepted} valid");
        bytes_total += r.0;
        struct_total += tried;
        valid_total += accepted;
    }
    assert!(failures.is_empty(), "panics:\n{}", failures.join("\n"));
    validation_row(
        "282-fuzz-case",
        "hostile input: bounded fixed-seed fuzz of the case parser and its validation (byte mutations of the shipped case files; leaves replaced by nasty values, keys removed, arrays grown)",
        "—",
        &format!(
            "{} case files: {bytes_total} byte-level and {struct_total} structural mutants ({valid_total} of them still valid): no panic, no hang (each structural mutant parsed and validated in under {} s)",
            files.len(),
            hang.as_secs()
        ),
        "hostile",
    );
}

// ---------------------------------------------------------------------------------------------
// The binary on hand-made hostile inputs
// ---------------------------------------------------------------------------------------------

/// What a CLI case must produce.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Expect {
    /// Refused with this exit status; stderr contains every needle (case-insensitive).
    Refused(i32, &'static [&'static str]),
    /// Completes (exit 0).
    Completes,
}

struct CliCase {
    name: &'static str,
    input: &'static str,
    /// Files to write into the case directory: (name, bytes). `case.json` is run.
    files: Vec<(&'static str, Vec<u8>)>,
    args: Vec<String>,
    expect: Expect,
}

struct Outcome {
    code: Option<i32>,
    stderr: String,
    secs: f64,
    timed_out: bool,
    dir: PathBuf,
}

fn run_with_timeout(dir: &Path, args: &[String], timeout: Duration) -> Outcome {
    let mut child = Command::new(env!("CARGO_BIN_EXE_stickslip"))
        // No model cache: tests leave the user's cache directory alone.
        .env("STICKSLIP_NO_CACHE", "1")
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        use std::io::Read;
        let mut buf = Vec::new();
        let _ = err.read_to_end(&mut buf);
        s.push_str(&String::from_utf8_lossy(&buf));
        s
    });
    let t0 = Instant::now();
    let mut timed_out = false;
    let code = loop {
        if let Some(st) = child.try_wait().unwrap() {
            break st.code();
        }
        if t0.elapsed() > timeout {
            let _ = child.kill();
            let _ = child.wait();
            timed_out = true;
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Outcome {
        code,
        stderr: reader.join().unwrap(),
        secs: t0.elapsed().as_secs_f64(),
        timed_out,
        dir: dir.to_path_buf(),
    }
}

/// Two flat blocks: lower [0,2]×[0,1], upper [0,2]×[y0, y0+1], non-matching meshes, with groups
/// lower, upper, bottom, lower_left, lower_top, upper_bottom, upper_left, top.
fn blocks(y0: f64) -> Vec<u8> {
    two_blocks([4, 2], [5, 2], y0, 0.0).into_bytes()
}

/// The blocks pressed together through a rigid pilot on the top face.
fn blocks_case(fy: f64, friction: Option<Value>) -> Value {
    let mut v = json!({
        "mesh": "mesh.msh",
        "bodies": [{"group": "lower", "E": 70.0, "nu": 0.3}, {"group": "upper", "E": 200.0, "nu": 0.25}],
        "supports": [{"group": "bottom", "ux": 0.0, "uy": 0.0}],
        "pilot": {"group": "top"},
        "contact": {"slave": "lower_top", "master": "upper_bottom"},
        "stages": [{"steps": 1, "pilot_x": {"displacement": 0.0}, "pilot_y": {"force": fy}}]
    });
    if let Some(f) = friction {
        v["contact"]["friction"] = f;
    }
    v
}

/// `cases/FILE` with its mesh read from `mesh.msh` next to the case.
fn local_case(file: &str) -> Value {
    edited(shipped_case(file), |v| v["mesh"] = json!("mesh.msh"))
}

/// `cases/hertz.json` on the coarsest VM272 mesh (copied next to the case as `mesh.msh`).
fn hertz_case() -> Value {
    local_case("hertz.json")
}

/// VM272 L0 rewritten as ASCII MSH 4.1 with the upper body moved down by `dy`.
fn overlapping_vm272(dy: f64) -> Vec<u8> {
    let m = gmsh::read(&repo().join("meshes/vm272_L0.msh")).unwrap();
    let mut nodes = m.nodes.clone();
    for n in m.group_nodes(m.group("upper_body").unwrap()) {
        nodes[n][1] -= dy;
    }
    let elements = |name: &str| m.group(name).unwrap().elements.iter();
    let surf = |name: &'static str| -> (&str, Vec<[usize; 6]>) {
        (
            name,
            elements(name).map(|&e| m.triangles[e].nodes).collect(),
        )
    };
    let curve = |name: &'static str| -> (&str, Vec<[usize; 3]>) {
        (name, elements(name).map(|&l| m.lines[l].nodes).collect())
    };
    msh41(
        &nodes,
        &[surf("lower_body"), surf("upper_body")],
        &[
            curve("bottom"),
            curve("top"),
            curve("lower_arc"),
            curve("upper_arc"),
        ],
    )
    .into_bytes()
}

fn l0() -> Vec<u8> {
    std::fs::read(repo().join("meshes/vm272_L0.msh")).unwrap()
}

fn js(v: &Value) -> Vec<u8> {
    serde_json::to_string_pretty(v).unwrap().into_bytes()
}

fn edited(mut v: Value, f: impl FnOnce(&mut Value)) -> Value {
    f(&mut v);
    v
}

/// The arguments of a CLI case by default: run `case.json` (`--log error` rather than
/// `--quiet`: the table wants the exit-5 message, which `--quiet` omits).
const RUN: &[&str] = &["run", "case.json", "--out", "out", "--log", "error"];

/// A CLI case that runs `case.json` ([`RUN`]).
fn cli(
    name: &'static str,
    input: &'static str,
    files: Vec<(&'static str, Vec<u8>)>,
    expect: Expect,
) -> CliCase {
    CliCase {
        name,
        input,
        files,
        args: RUN.iter().map(|s| s.to_string()).collect(),
        expect,
    }
}

impl CliCase {
    /// The same case with other arguments.
    fn args(mut self, args: &[&str]) -> CliCase {
        self.args = args.iter().map(|s| s.to_string()).collect();
        self
    }
}

/// The hostile CLI inputs, one per row of `docs/hostile_inputs.md`.
fn cli_cases() -> Vec<CliCase> {
    use Expect::{Completes, Refused};
    let mesh = l0();
    let half = mesh[..mesh.len() / 2].to_vec();
    let hertz = js(&hertz_case());
    let hertz_text = String::from_utf8(hertz.clone()).unwrap();
    // `case.json` and the L0 mesh; the hertz case edited by `edit` on L0; the flat blocks.
    let on_l0 = |case: Vec<u8>| vec![("case.json", case), ("mesh.msh", mesh.clone())];
    let hertz_edit = |edit: fn(&mut Value)| on_l0(js(&edited(hertz_case(), edit)));
    let on_blocks = |case: Value, y0: f64| vec![("case.json", js(&case)), ("mesh.msh", blocks(y0))];
    let mut corrupt = mesh.clone();
    let p = find(&corrupt, b"$Elements").unwrap() + 10;
    for b in &mut corrupt[p..p + 64] {
        *b = 0xff;
    }
    let patch = std::fs::read_to_string(repo().join("meshes/patch_curved.msh")).unwrap();
    let patch_case = js(&json!({
        "mesh": "mesh.msh",
        "bodies": [{"group": "body", "E": 1.0, "nu": 0.3}],
        "supports": [{"group": "bottom", "ux": 0.0, "uy": 0.0}],
        "stages": [{"steps": 1}]
    }));
    let mut ascii_nan = patch.clone();
    {
        // Replace the coordinates of the first node with NaN: the fifth line from `$Nodes`
        // ($Nodes, section header, block header, first tag, first coordinates).
        let s = ascii_nan.find("$Nodes").unwrap();
        let mut at = s;
        for _ in 0..4 {
            at += ascii_nan[at..].find('\n').unwrap() + 1;
        }
        let end = at + ascii_nan[at..].find('\n').unwrap();
        ascii_nan.replace_range(at..end, "nan nan 0");
    }
    // A zero-length boundary edge: the first line of `bottom` collapsed onto one node.
    let zero_edge = {
        let (nodes, tris, [mut b, r, t, l]) = structured(2, 2, 0.0, 1.0, 0.0, 1.0, 0.0);
        b.push([b[0][0], b[0][0], b[0][0]]);
        msh41_sides(&nodes, &[("body", tris)], [b, r, t, l]).into_bytes()
    };
    // A triangle with two coincident vertices (zero-length edge inside the body).
    let zero_tri_edge = {
        let (mut nodes, tris, sides) = structured(2, 2, 0.0, 1.0, 0.0, 1.0, 0.0);
        let t0 = tris[0];
        nodes[t0[1]] = nodes[t0[0]];
        msh41_sides(&nodes, &[("body", tris)], sides).into_bytes()
    };
    let square_case = js(&json!({
        "mesh": "mesh.msh",
        "bodies": [{"group": "body", "E": 1.0, "nu": 0.3}],
        "supports": [{"group": "bottom", "ux": 0.0, "uy": 0.0}],
        "tractions": [{"group": "top", "kind": "uniform", "ty": -1.0}],
        "stages": [{"steps": 1, "traction_scale": 1.0}]
    }));
    let mut cm_zero = local_case("vm272_cm.json");
    cm_zero["stages"][0]["pilot_y"] = json!({"force": 0.0});
    cm_zero["stages"][1]["pilot_x"] = json!({"force": 0.0});
    cm_zero["stages"][1]["steps"] = json!(2);
    let cm_edit = |edit: fn(&mut Value)| on_l0(js(&edited(local_case("vm272_cm.json"), edit)));
    vec![
        cli(
            "truncated binary mesh",
            "vm272_L0.msh cut at half its length",
            vec![("case.json", hertz.clone()), ("mesh.msh", half)],
            Refused(2, &["mesh.msh"]),
        ),
        cli(
            "corrupt binary mesh",
            "64 bytes of 0xFF written into the $Elements section of vm272_L0.msh",
            vec![("case.json", hertz.clone()), ("mesh.msh", corrupt)],
            Refused(2, &["mesh.msh"]),
        ),
        cli(
            "empty mesh file",
            "0-byte mesh.msh",
            vec![("case.json", hertz.clone()), ("mesh.msh", vec![])],
            Refused(2, &["mesh.msh", "$MeshFormat"]),
        ),
        cli(
            "mesh path is a directory",
            "`\"mesh\": \".\"`",
            vec![("case.json", js(&edited(hertz_case(), |v| v["mesh"] = json!("."))))],
            Refused(2, &["cannot read"]),
        ),
        cli(
            "NaN node coordinate",
            "patch_curved.msh with the first node at (nan, nan)",
            vec![("case.json", patch_case.clone()), ("mesh.msh", ascii_nan.into_bytes())],
            Refused(2, &["mesh.msh"]),
        ),
        cli(
            "zero-length boundary edge",
            "unit square; an extra line in `bottom` whose three nodes coincide",
            vec![("case.json", square_case.clone()), ("mesh.msh", zero_edge)],
            Refused(2, &["zero length", "bottom"]),
        ),
        cli(
            "zero-length triangle edge",
            "unit square; two vertices of the first triangle coincide",
            vec![("case.json", square_case), ("mesh.msh", zero_tri_edge)],
            Refused(2, &["element 9", "degenerate"]),
        ),
        cli(
            "number out of range (1e400)",
            "`\"E\": 1e400` (JSON has no NaN; 1e400 overflows f64)",
            on_l0(hertz_text.replacen("200.0", "1e400", 1).into_bytes()),
            Refused(2, &["case.json", "line"]),
        ),
        cli(
            "NaN literal",
            "`\"nu\": NaN`",
            on_l0(hertz_text.replacen("0.3", "NaN", 1).into_bytes()),
            Refused(2, &["case.json", "line"]),
        ),
        cli(
            "string where a number goes",
            "`\"E\": \"200\"`",
            hertz_edit(|v| v["bodies"][0]["E"] = json!("200")),
            Refused(2, &["case.json", "invalid type"]),
        ),
        cli(
            "negative step count",
            "`\"steps\": -1`",
            hertz_edit(|v| v["stages"][0]["steps"] = json!(-1)),
            Refused(2, &["case.json"]),
        ),
        cli(
            "step count beyond u64",
            "`\"steps\": 1e20`",
            hertz_edit(|v| v["stages"][0]["steps"] = json!(1e20)),
            Refused(2, &["case.json"]),
        ),
        cli(
            "huge Young's modulus",
            "`\"E\": 1e300` on both bodies (finite, so valid)",
            hertz_edit(|v| {
                v["bodies"][0]["E"] = json!(1e300);
                v["bodies"][1]["E"] = json!(1e300);
            }),
            Refused(3, &["singular"]),
        ),
        cli(
            "huge load",
            "`\"pilot_y\": {\"force\": -1e300}`",
            hertz_edit(|v| v["stages"][0]["pilot_y"] = json!({"force": -1e300})),
            Refused(3, &["contact zone kept growing"]),
        ),
        cli(
            "tiny load",
            "`\"pilot_y\": {\"force\": -1e-300}`",
            hertz_edit(|v| v["stages"][0]["pilot_y"] = json!({"force": -1e-300})),
            Completes,
        ),
        cli(
            "zero load, frictionless",
            "`cases/hertz.json` on L0 with `\"pilot_y\": {\"force\": 0.0}`",
            hertz_edit(|v| v["stages"][0]["pilot_y"] = json!({"force": 0.0})),
            Completes,
        ),
        cli(
            "zero load, Coulomb friction",
            "`cases/vm272_cm.json` on L0 with every pilot force 0",
            on_l0(js(&cm_zero)),
            Completes,
        ),
        cli(
            "zero load, flat blocks",
            "two flat blocks touching at y = 1, pilot force 0",
            on_blocks(blocks_case(0.0, None), 1.0),
            Completes,
        ),
        cli(
            "overlapping bodies",
            "two flat blocks, the upper one moved down by 0.1 into the lower one",
            on_blocks(blocks_case(-1.0, None), 0.9),
            Refused(2, &["penetrate", "lower_top", "upper_bottom", "at ("]),
        ),
        cli(
            "overlapping half-cylinders",
            "VM272 L0 with every node of `upper_body` moved down by 0.05 mm (initial overlap at x = 0)",
            vec![("case.json", hertz.clone()), ("mesh.msh", overlapping_vm272(0.05))],
            Refused(2, &["penetrate", "lower_arc", "upper_arc", "at ("]),
        ),
        cli(
            "bodies pulled apart",
            "`cases/vm272_cm.json` on L0 with `\"pilot_y\": {\"force\": 10.0}` (pulling; it completed with pilot displacements of 1e11 before the fix)",
            cm_edit(|v| v["stages"][0]["pilot_y"] = json!({"force": 10.0})),
            Refused(3, &["pulls", "upper_body", "no equilibrium"]),
        ),
        cli(
            "pressed, then pulled apart",
            "`cases/vm272_cm.json` on L0 with the tangential stage also ramping `pilot_y` from −10 to +10 (the contact carries Q until Q = 0.2 P)",
            cm_edit(|v| v["stages"][1]["pilot_y"] = json!({"force": 10.0})),
            Refused(5, &["equilibrium lost", "Q_max = 0.37"]),
        ),
        cli(
            "frictionless, pilot_x left to force control",
            "`cases/hertz.json` on L0 with `\"pilot_x\": {\"force\": 0.0}`: nothing holds the upper body along x",
            hertz_edit(|v| v["stages"][0]["pilot_x"] = json!({"force": 0.0})),
            Refused(2, &["`pilot_x`", "give `pilot_x` a displacement"]),
        ),
        cli(
            "Q/P above μ at every load",
            "`cases/vm272_cm.json` on L0 as one stage driving `pilot_x` 2.5 and `pilot_y` −10 together from no load, μ = 0.2",
            cm_edit(|v| {
                v["stages"] = json!([{"name": "both", "steps": 4,
                    "pilot_x": {"force": 2.5}, "pilot_y": {"force": -10.0}}]);
            }),
            Refused(2, &["Q/P = 0.250000", "0.200000"]),
        ),
        cli(
            "lifted by displacement",
            "`cases/hertz.json` on L0 with `\"pilot_y\": {\"displacement\": 0.1}` (the pilot holds the body; the contact opens)",
            hertz_edit(|v| v["stages"][0]["pilot_y"] = json!({"displacement": 0.1})),
            Completes,
        ),
        cli(
            "bodies start apart",
            "VM272 L0 with every node of `upper_body` moved up by 0.01 mm: the load closes the gap",
            vec![("case.json", hertz.clone()), ("mesh.msh", overlapping_vm272(-0.01))],
            Completes,
        ),
        cli(
            "faces that do not face each other",
            "VM272 L0 with `upper_arc` as slave and `bottom` as master",
            hertz_edit(|v| {
                v["contact"]["slave"] = json!("upper_arc");
                v["contact"]["master"] = json!("bottom");
            }),
            Refused(2, &["candidate gap"]),
        ),
        cli(
            "unsupported data size in $MeshFormat",
            "patch_curved.msh with the header `4.1 0 3` (mshio panicked on this before the fix)",
            vec![
                ("case.json", patch_case),
                ("mesh.msh", patch.replacen("4.1 0 8", "4.1 0 3", 1).into_bytes()),
            ],
            Refused(2, &["mesh.msh", "data size"]),
        ),
        cli(
            "friction table with one row",
            "`\"friction\": {\"shape\": \"table\", \"rows\": [[0.0, 0.2]]}`",
            on_blocks(
                blocks_case(-1.0, Some(json!({"shape": "table", "rows": [[0.0, 0.2]]}))),
                1.0,
            ),
            Refused(2, &["row"]),
        ),
        cli(
            "friction table, decreasing slip",
            "`\"rows\": [[1.0, 0.2], [0.0, 0.1]]`",
            on_blocks(
                blocks_case(
                    -1.0,
                    Some(json!({"shape": "table", "rows": [[1.0, 0.2], [0.0, 0.1]]})),
                ),
                1.0,
            ),
            Refused(2, &["friction"]),
        ),
        cli(
            "negative friction coefficient",
            "`\"friction\": {\"shape\": \"constant\", \"mu\": -0.2}`",
            on_blocks(
                blocks_case(-1.0, Some(json!({"shape": "constant", "mu": -0.2}))),
                1.0,
            ),
            Refused(2, &["friction"]),
        ),
        cli(
            "non-UTF-8 case file",
            "bytes FF FE 00 …",
            vec![("case.json", vec![0xff, 0xfe, 0x00, 0x7b, 0x7d])],
            Refused(2, &["case.json"]),
        ),
        cli(
            "empty case file",
            "0-byte case.json",
            vec![("case.json", vec![])],
            Refused(2, &["case.json"]),
        ),
        cli(
            "missing case file",
            "`stickslip run nothere.json`",
            vec![],
            Refused(2, &["nothere.json"]),
        )
        .args(&["run", "nothere.json", "--quiet"]),
        cli(
            "zero threads",
            "`--threads 0`",
            on_l0(hertz),
            Refused(2, &["threads"]),
        )
        .args(&[RUN, &["--threads", "0"]].concat()),
        cli(
            "triangles on a curve entity",
            "`stickslip mesh-info` on patch_curved.msh with the triangle block's entity dimension 2 → 1 (panicked with exit 101 before the fix)",
            vec![("mesh.msh", patch.replacen("\n2 1 9 26\n", "\n1 1 9 26\n", 1).into_bytes())],
            Refused(2, &["mesh.msh", "dimension 1"]),
        )
        .args(&["mesh-info", "mesh.msh"]),
        cli(
            "mesh-info on a truncated mesh",
            "`stickslip mesh-info` on vm272_L0.msh cut at 1000 bytes",
            vec![("mesh.msh", mesh[..1000].to_vec())],
            Refused(2, &["mesh.msh"]),
        )
        .args(&["mesh-info", "mesh.msh"]),
    ]
}

fn excerpt(s: &str) -> String {
    let line = s
        .lines()
        .find(|l| l.starts_with("error"))
        .or_else(|| s.lines().find(|l| !l.trim().is_empty()))
        .unwrap_or("")
        .trim();
    let mut e: String = line.chars().take(230).collect();
    if line.chars().count() > 230 {
        e.push('…');
    }
    e.replace('\t', " ").replace('|', "\\|")
}

#[test]
fn hostile_command_lines_give_a_message_and_never_panic_or_hang() {
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    // Cases per exit status, and the largest contact force of a completed zero-load run.
    let mut by_status = std::collections::BTreeMap::<String, usize>::new();
    let (mut zero_loads, mut zero_force) = (0, 0.0f64);
    // Measured 4.4e-15 (contact_fy of the frictionless zero load).
    let zero_tol = 2e-14;
    for (i, c) in cli_cases().into_iter().enumerate() {
        let dir = tempdir(&format!("hostile-cli-{i}"));
        for (n, b) in &c.files {
            std::fs::write(dir.join(n), b).unwrap();
        }
        let o = run_with_timeout(&dir, &c.args, Duration::from_secs(60));
        let status = if o.timed_out {
            "timeout".to_string()
        } else {
            o.code.map_or("signal".into(), |c| c.to_string())
        };
        *by_status.entry(status.clone()).or_default() += 1;
        println!(
            "{:>32}: exit {status} in {:.2} s: {}",
            c.name,
            o.secs,
            excerpt(&o.stderr)
        );
        let mut why = Vec::new();
        if o.timed_out {
            why.push("hung (killed after 60 s)".to_string());
        }
        if o.code == Some(101) || o.stderr.contains("panicked") {
            why.push("panicked".to_string());
        }
        let lower = o.stderr.to_lowercase();
        match c.expect {
            Expect::Refused(code, needles) => {
                if o.code != Some(code) {
                    why.push(format!("exit {status}, expected {code}"));
                }
                for n in needles {
                    if !lower.contains(&n.to_lowercase()) {
                        why.push(format!("message lacks `{n}`"));
                    }
                }
                if code == 2 && o.dir.join("out").exists() {
                    why.push("bad input, yet an output directory was written".into());
                }
            }
            Expect::Completes => {
                if o.code != Some(0) {
                    why.push(format!("exit {status}, expected 0"));
                }
            }
        }
        // A completed contact run: record the total contact force of the last step.
        let mut note = String::new();
        if o.code == Some(0) {
            if let Ok(h) = std::fs::read_to_string(o.dir.join("out/history.csv")) {
                let head: Vec<&str> = h.lines().next().unwrap_or("").split(',').collect();
                let last: Vec<&str> = h.lines().last().unwrap_or("").split(',').collect();
                let get = |k: &str| {
                    head.iter()
                        .position(|x| *x == k)
                        .and_then(|i| last.get(i))
                        .map(|s| s.to_string())
                };
                for k in [
                    "pilot_uy",
                    "pilot_fy",
                    "contact_fx",
                    "contact_fy",
                    "n_contact",
                ] {
                    if let Some(v) = get(k) {
                        note += &format!("{k} = {v}; ");
                    }
                }
                if c.name.starts_with("zero load") {
                    zero_loads += 1;
                    for k in ["contact_fx", "contact_fy"] {
                        let fc: f64 = get(k).and_then(|s| s.parse().ok()).unwrap_or(f64::NAN);
                        // Round-off of a 10 N/mm load scale at most.
                        if fc.is_nan() || fc.abs() >= zero_tol {
                            why.push(format!("zero load but {k} = {fc}"));
                        }
                        zero_force = zero_force.max(fc.abs());
                    }
                }
            } else if c.name.starts_with("zero load") {
                why.push("completed without writing out/history.csv".into());
            }
        }
        if !why.is_empty() {
            failures.push(format!(
                "{}: {} (stderr: {})",
                c.name,
                why.join("; "),
                o.stderr.trim()
            ));
        }
        rows.push(format!(
            "| {} | {} | {} | {} |",
            c.name,
            c.input.replace('|', "\\|"),
            status,
            if o.code == Some(0) {
                format!("completes; {}", note.trim_end_matches("; "))
            } else {
                excerpt(&o.stderr)
            }
        ));
        let _ = std::fs::remove_dir_all(&dir);
    }
    if std::env::var("HOSTILE_WRITE_DOC").is_ok_and(|v| v == "1") {
        write_doc(&rows);
    }
    assert!(
        failures.is_empty(),
        "hostile CLI inputs:\n{}",
        failures.join("\n")
    );
    let statuses: Vec<String> = by_status
        .iter()
        .map(|(s, n)| format!("exit {s}: {n}"))
        .collect();
    validation_row(
        "280-hostile",
        &format!(
            "hostile input: {} CLI cases (truncated/corrupt meshes, huge values, zero-length edges, overlapping bodies, bodies pulled apart or starting apart, one-row friction table, zero loads, …); table in [docs/hostile_inputs.md](docs/hostile_inputs.md)",
            rows.len()
        ),
        "—",
        &format!(
            "each as expected ({}): bad input a clear message and no output, never a panic or hang (60 s limit); the {zero_loads} zero loads complete with contact force ≤ {zero_force:.0e} (asserted < {zero_tol:.0e})",
            statuses.join(", ")
        ),
        "hostile",
    );
}

fn write_doc(rows: &[String]) {
    let path = repo().join("docs/hostile_inputs.md");
    let old = std::fs::read_to_string(&path).unwrap_or_default();
    let begin = "<!-- BEGIN generated by tests/hostile.rs (HOSTILE_WRITE_DOC=1) -->";
    let end = "<!-- END generated -->";
    let table = format!(
        "{begin}\n| input | what | exit | message (first error line) or result |\n|---|---|---|---|\n{}\n{end}",
        rows.join("\n")
    );
    let text = match (old.find(begin), old.find(end)) {
        (Some(a), Some(b)) => format!("{}{}{}", &old[..a], table, &old[b + end.len()..]),
        _ => format!("{old}\n{table}\n"),
    };
    std::fs::write(path, text).unwrap();
}
