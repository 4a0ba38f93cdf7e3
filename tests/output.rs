//! The `.vtu`/`.pvd` output reads back (through the test reader `common::vtu`, written from
//! the VTK format documentation) with the documented arrays, types and cells; the contact
//! VTU holds the values of the contact CSV, the bodies VTU the pilot's displacement on the
//! pilot face; compressed files (`output.compress`) hold the same arrays as raw ones.

mod common;
use common::vtu::{Values, Vtu};
use common::{repo, run_case, shipped_case_on, stickslip};
use serde_json::json;

#[test]
fn vtu_holds_every_documented_array_with_finite_values() {
    let dir = common::tempdir("vtu");
    let t0 = std::time::Instant::now();
    let (code, _, err) = stickslip(&[
        "run",
        repo().join("cases/arc_hertz.json").to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
    ]);
    let process_s = t0.elapsed().as_secs_f64();
    assert!(code == 0, "{err}");
    let pvd = std::fs::read_to_string(dir.join("arc_hertz.pvd")).unwrap();
    assert!(pvd.contains("file=\"arc_hertz_0001.vtu\""));
    let vtu = Vtu::read(&dir.join("arc_hertz_0001.vtu")).unwrap();
    assert!(!vtu.compressed);
    let npts = vtu.points;
    let expect = [
        ("displacement", 3),
        ("stress_xx", 1),
        ("stress_yy", 1),
        ("stress_xy", 1),
        ("stress_zz", 1),
        ("von_mises", 1),
    ];
    for (name, ncomp) in expect {
        let arr = vtu
            .array("PointData", name)
            .unwrap_or_else(|| panic!("{name} missing"));
        assert_eq!(arr.ncomp, ncomp, "{name}");
        let Values::F64(v) = &arr.values else {
            panic!("{name} not f64")
        };
        assert_eq!(v.len(), npts * ncomp, "{name}");
        assert!(
            v.iter().all(|x| x.is_finite()),
            "{name} has non-finite values"
        );
    }
    let body = vtu.f64s("CellData", "body_id");
    assert!(body.iter().all(|&b| b == 0.0), "one body");
    check_cells(&vtu, 22, 6);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "completed");
    // Every phase is reported, and the disjoint parts of the run add up to no more than the
    // process took from the outside: a phase counted twice would exceed it. The writer's busy
    // time `write` overlaps the solve (it writes on a thread of its own): what it adds to the
    // run is the time waited for it, `write_wait`. The assembly overlaps the analysis: what
    // the two and the factorisation took together is `build_span`, at most their sum and at
    // least the factorisation after the longer of the two.
    let write = summary["timings_s"]["write"].as_f64();
    assert!(
        write.is_some_and(|v| v.is_finite() && v > 0.0),
        "write: {write:?}"
    );
    let t = |k: &str| {
        let v = summary["timings_s"][k].as_f64();
        assert!(v.is_some_and(|v| v.is_finite() && v >= 0.0), "{k}: {v:?}");
        v.unwrap()
    };
    let (span, assemble, analyse, factorise) =
        (t("build_span"), t("assemble"), t("analyse"), t("factorise"));
    assert!(
        span <= assemble + analyse + factorise + 1e-6
            && span >= assemble.max(analyse) + factorise - 1e-6,
        "build_span {span} against assemble {assemble}, analyse {analyse}, factorise {factorise}"
    );
    // The dense block of the constraint rows is a part of the factorisation, timed inside it.
    let block = t("constraint_block");
    assert!(
        block <= factorise,
        "constraint_block {block} exceeds factorise {factorise}"
    );
    let phases = [
        "read",
        "pair",
        "build_span",
        "condense",
        "solve",
        "write_wait",
    ];
    let sum: f64 = phases
        .iter()
        .map(|k| {
            let v = summary["timings_s"][*k].as_f64();
            assert!(v.is_some_and(|v| v.is_finite() && v >= 0.0), "{k}: {v:?}");
            v.unwrap()
        })
        .sum();
    println!("phases add up to {sum:.3} s of the process's {process_s:.3} s");
    assert!(
        sum <= process_s,
        "phases {sum} s exceed the process's {process_s} s"
    );
    assert!(summary["peak_memory_mib"].as_f64().unwrap() > 0.0);
}

/// Counts, indices and status codes in the CSV files are integers, not `4.0e0`.
#[test]
fn csv_counts_are_integers() {
    let dir = common::tempdir("csv-int");
    let (code, _, err) = stickslip(&[
        "run",
        repo().join("cases/vm272_cm.json").to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(code == 0, "{err}");
    let check = |file: &str, cols: &[&str]| {
        let text = std::fs::read_to_string(dir.join(file)).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        for line in lines {
            let v: Vec<&str> = line.split(',').collect();
            for c in cols {
                let k = header.iter().position(|h| h == c).unwrap();
                assert!(v[k].parse::<i64>().is_ok(), "{file}: {c} = {}", v[k]);
            }
            // The other columns stay full-precision floats.
            let k = header.iter().position(|h| *h != cols[0]).unwrap();
            assert!(v[k].parse::<f64>().is_ok(), "{file}: {}", v[k]);
        }
    };
    check(
        "history.csv",
        &[
            "step",
            "stage",
            "iterations",
            "cutbacks",
            "n_contact",
            "n_stick",
            "n_slip",
        ],
    );
    let last = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|n| n.contains("contact_") && n.ends_with(".csv"))
        .max()
        .expect("a contact CSV");
    check(&last, &["status"]);
}

/// The points are 3-D with z = 0, and the cells all of VTK type `code` with `nodes` nodes
/// each, numbering points of the piece.
fn check_cells(vtu: &Vtu, code: i64, nodes: usize) {
    let pts = vtu.f64s("Points", "");
    assert_eq!(pts.len(), 3 * vtu.points);
    assert!(pts.iter().skip(2).step_by(3).all(|&z| z == 0.0));
    let (conn, offsets, types) = (
        vtu.ints("connectivity"),
        vtu.ints("offsets"),
        vtu.ints("types"),
    );
    assert_eq!(conn.len(), nodes * vtu.cells);
    assert!(conn.iter().all(|&n| (0..vtu.points as i64).contains(&n)));
    let stride: Vec<i64> = (1..=vtu.cells as i64).map(|c| c * nodes as i64).collect();
    assert_eq!(offsets, stride);
    assert!(types.iter().all(|&t| t == code), "cell types {code}");
    let kinds: Vec<(&str, &str)> = vtu
        .arrays
        .iter()
        .filter(|a| a.section == "Points" || a.section == "Cells")
        .map(|a| (a.name.as_str(), a.vtk_type.as_str()))
        .collect();
    assert_eq!(
        kinds,
        [
            ("", "Float64"),
            ("connectivity", "UInt64"),
            ("offsets", "UInt64"),
            ("types", "UInt8")
        ]
    );
}

/// The contact VTU holds the contact CSV's values at the same nodes, the bodies VTU the
/// pilot's displacement on the pilot face (the top edge), and a run with `output.compress`
/// writes the same arrays, zlib-compressed, in smaller files.
#[test]
fn vtu_values_are_the_runs_and_compressed_files_hold_the_same_arrays() {
    let mut v = shipped_case_on("vm272_cm.json", "vm272_L1.msh");
    v["output"] = json!({"every": 5});
    let raw = run_case("vtu-raw", &v, &["--quiet"]);
    raw.assert_ok("raw");
    v["output"]["compress"] = json!(true);
    let zip = run_case("vtu-compressed", &v, &["--quiet"]);
    zip.assert_ok("compressed");
    let history = raw.history();
    let steps: Vec<usize> = history
        .rows
        .iter()
        .map(|r| r[0] as usize)
        .filter(|s| s % 5 == 0 || *s == history.rows.len())
        .collect();
    assert_eq!(steps, [5, 10, 11]);
    let (mut raw_bytes, mut zip_bytes) = (0, 0);
    for &step in &steps {
        let row = &history.rows[step - 1];
        for file in [
            format!("case_{step:04}.vtu"),
            format!("case_contact_{step:04}.vtu"),
        ] {
            let (a, b) = (raw.out.join(&file), zip.out.join(&file));
            raw_bytes += std::fs::metadata(&a).unwrap().len();
            zip_bytes += std::fs::metadata(&b).unwrap().len();
            let (a, b) = (Vtu::read(&a).unwrap(), Vtu::read(&b).unwrap());
            assert!(!a.compressed && b.compressed, "{file}");
            assert_eq!((a.points, a.cells), (b.points, b.cells), "{file}");
            assert_eq!(a.arrays.len(), b.arrays.len(), "{file}");
            for (x, y) in a.arrays.iter().zip(&b.arrays) {
                assert_eq!(
                    (&x.section, &x.name, &x.vtk_type, x.ncomp),
                    (&y.section, &y.name, &y.vtk_type, y.ncomp),
                    "{file}"
                );
                // Bit for bit (NaN-safe).
                let bits = |v: &Values| match v {
                    Values::F64(f) => f.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                    Values::U64(u) => u.clone(),
                    Values::I64(i) => i.iter().map(|&x| x as u64).collect(),
                    Values::U8(u) => u.iter().map(|&x| x as u64).collect(),
                };
                assert!(
                    bits(&x.values) == bits(&y.values),
                    "{file}: `{}` differs",
                    x.name
                );
            }
        }
        // The contact VTU at the nodes of the contact CSV (matched by position).
        let cv = Vtu::read(&raw.out.join(format!("case_contact_{step:04}.vtu"))).unwrap();
        check_cells(&cv, 21, 3);
        let csv = raw.contact(step);
        let pts = cv.f64s("Points", "");
        assert_eq!(csv.rows.len(), cv.points, "step {step}: nodes");
        let (xc, yc) = (csv.col("x"), csv.col("y"));
        for name in [
            "pressure",
            "shear",
            "gap",
            "slip",
            "slip_increment",
            "status",
            "mu",
            "q_over_p",
            "slip_mu",
            "slip_rate",
        ] {
            let (vals, k) = (cv.f64s("PointData", name), csv.col(name));
            let scale = vals.iter().fold(1e-300f64, |m, x| m.max(x.abs()));
            for r in &csv.rows {
                let i = (0..cv.points)
                    .find(|&i| pts[3 * i] == r[xc] && pts[3 * i + 1] == r[yc])
                    .or_else(|| {
                        (0..cv.points).find(|&i| {
                            (pts[3 * i] - r[xc]).abs() < 1e-11
                                && (pts[3 * i + 1] - r[yc]).abs() < 1e-11
                        })
                    })
                    .unwrap_or_else(|| {
                        panic!(
                            "step {step}: CSV node ({}, {}) not in the VTU",
                            r[xc], r[yc]
                        )
                    });
                // The CSV holds 13 significant digits.
                assert!(
                    (vals[i] - r[k]).abs() <= 1e-11 * scale,
                    "step {step}: {name} at ({}, {}): VTU {} against CSV {}",
                    r[xc],
                    r[yc],
                    vals[i],
                    r[k]
                );
            }
        }
        for name in ["traction", "normal"] {
            assert_eq!(cv.array("PointData", name).unwrap().ncomp, 3, "{name}");
        }
        // The bodies: the top edge (the pilot face) moves with the pilot.
        let bv = Vtu::read(&raw.out.join(format!("case_{step:04}.vtu"))).unwrap();
        check_cells(&bv, 22, 6);
        let (bp, d) = (bv.f64s("Points", ""), bv.f64s("PointData", "displacement"));
        let top = (0..bv.points)
            .map(|i| bp[3 * i + 1])
            .fold(f64::MIN, f64::max);
        let pilot = [row[history.col("pilot_ux")], row[history.col("pilot_uy")]];
        let on_top: Vec<usize> = (0..bv.points).filter(|&i| bp[3 * i + 1] == top).collect();
        assert!(on_top.len() > 2);
        for i in on_top {
            for c in 0..2 {
                assert!(
                    (d[3 * i + c] - pilot[c]).abs() <= 1e-9 * pilot[1].abs(),
                    "step {step}: top node {i}: displacement {c} = {} against the pilot's {}",
                    d[3 * i + c],
                    pilot[c]
                );
            }
        }
        let body = bv.f64s("CellData", "body_id");
        assert!(body.contains(&0.0) && body.contains(&1.0), "two bodies");
    }
    println!(
        "raw .vtu {raw_bytes} bytes, compressed {zip_bytes} bytes ({:.2})",
        zip_bytes as f64 / raw_bytes as f64
    );
    assert!(zip_bytes < raw_bytes);
    // The other files are the same (history.csv without its wall-clock column).
    let wall = history.col("wall_s");
    let without_wall = |t: &common::Table| -> Vec<Vec<u64>> {
        t.rows
            .iter()
            .map(|r| {
                r.iter()
                    .enumerate()
                    .filter(|(i, _)| *i != wall)
                    .map(|(_, x)| x.to_bits())
                    .collect()
            })
            .collect()
    };
    assert_eq!(without_wall(&history), without_wall(&zip.history()));
    for f in ["contact_0011.csv", "case.pvd"] {
        assert_eq!(
            std::fs::read(raw.out.join(f)).unwrap(),
            std::fs::read(zip.out.join(f)).unwrap(),
            "{f}"
        );
    }
}

/// The writer writes the bodies files of a batch of steps side by side; a step that cannot be
/// written (a directory in its file's place) stops the batch there as if its steps were
/// written one by one: no file of a later step of the batch stays behind, and nothing of the
/// failed step but what was in its place.
#[test]
fn a_failed_step_of_a_batch_leaves_no_file_of_the_steps_after_it() {
    use stickslip::output::series::{Series, StepOutput};
    let case: stickslip::case::Case =
        serde_json::from_value(shipped_case_on("vm272_cm.json", "vm272_L1.msh")).unwrap();
    let model = stickslip::model::Model::build(&case, &repo().join("cases/vm272_cm.json")).unwrap();
    let dir = common::tempdir("batch-write-error");
    std::fs::create_dir_all(dir.join("case_0003.vtu")).unwrap();
    let step = |k: usize| StepOutput {
        step: k,
        time: k as f64,
        scale: 1.0,
        u: Some(vec![0.0; model.dofs.n_free()]),
        contact: None,
        state: None,
        reply: None,
        physical: None,
    };
    let mut series = Series::new(&model, &dir, "case", false);
    let err = series.write(vec![step(3), step(4), step(5)]).unwrap_err();
    assert!(err.to_string().contains("case_0003.vtu"), "{err}");
    assert_eq!(common::file_names(&dir), ["case_0003.vtu"]);
    assert!(dir.join("case_0003.vtu").is_dir());
    // A later step of the batch that fails: the steps before it are whole (with their `.pvd`),
    // the failed one keeps what was in its place, and a file of a step after it left by an
    // earlier run is not touched.
    let later = common::tempdir("batch-write-error-later");
    std::fs::create_dir_all(later.join("case_0004.vtu")).unwrap();
    std::fs::write(later.join("case_0005.vtu"), b"an earlier run's").unwrap();
    let mut series = Series::new(&model, &later, "case", false);
    let err = series.write(vec![step(3), step(4), step(5)]).unwrap_err();
    assert!(err.to_string().contains("case_0004.vtu"), "{err}");
    assert_eq!(
        common::file_names(&later),
        [
            "case.pvd",
            "case_0003.vtu",
            "case_0004.vtu",
            "case_0005.vtu"
        ]
    );
    assert_eq!(
        std::fs::read(later.join("case_0005.vtu")).unwrap(),
        b"an earlier run's"
    );
    let pvd = std::fs::read_to_string(later.join("case.pvd")).unwrap();
    assert!(
        pvd.contains("case_0003.vtu") && !pvd.contains("case_0004.vtu"),
        "{pvd}"
    );
    // The same batch into a clean directory writes every step.
    let clean = common::tempdir("batch-write-ok");
    let mut series = Series::new(&model, &clean, "case", false);
    series.write(vec![step(3), step(4), step(5)]).unwrap();
    for f in [
        "case_0003.vtu",
        "case_0004.vtu",
        "case_0005.vtu",
        "case.pvd",
    ] {
        assert!(clean.join(f).is_file(), "{f}");
    }
}
