//! The factorisation's modelled operations (`factor_flops` of `summary.json`) along the VM272
//! ladder, L3–L7: the figures docs/benchmarks.md gives for them ("The factorisation's
//! operations"). They are counts from the symbolic analysis of a
//! deterministic ordering, the same on every machine and thread count, so they are asserted
//! close to the documented values: the L5 parts, the L7 / L5 ratios and the fitted exponents.

mod common;
use common::{ensure_mesh, fitted_rate, run_case_in, shipped_case_on, tempdir};
use serde_json::{Value, json};

/// `factor_flops` and the free DOFs of Fig. 2 on level `l` (four tangential steps, no VTU: the
/// counts come from the analysis alone).
fn flops_of(dir: &std::path::Path, l: usize) -> ([f64; 3], f64, f64) {
    ensure_mesh(&format!("vm272_L{l}"));
    let mut case = shipped_case_on("fig2.json", &format!("vm272_L{l}.msh"));
    case["stages"][1]["steps"] = json!(4);
    case["output"] = json!({"vtu": false});
    // The end summary of one level is printed (the others run quietly).
    let log = if l == 3 { "info" } else { "error" };
    let level_dir = dir.join(format!("L{l}"));
    std::fs::create_dir_all(&level_dir).unwrap();
    let run = run_case_in(
        &level_dir,
        "fig2.json",
        &serde_json::to_string(&case).unwrap(),
        &["--log", log],
    );
    assert_eq!(run.code, 0, "L{l}: {}", run.stderr);
    let out = run.out;
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let f = &s["factor_flops"];
    let parts = ["k", "coupling", "constraint_block"].map(|k| {
        f[k].as_f64()
            .unwrap_or_else(|| panic!("L{l}: factor_flops.{k} missing: {f}"))
    });
    if l == 3 {
        let printed = &run.stderr;
        let line = printed
            .lines()
            .find(|x| x.trim_start().starts_with("factor"))
            .unwrap_or_else(|| panic!("no factor line in the run's summary:\n{printed}"));
        let total: f64 = parts.iter().sum();
        assert!(
            line.contains(&format!("{total:.2e} modelled operations")) && line.contains("Gflop/s"),
            "{line}"
        );
    }
    // The first step's Newton iterations, the first contact from Hertz's contact set
    // (docs/benchmarks.md, "What each mechanism buys": 5 on L5, 7 on L7; L3's zone is below
    // the frictionless start's 512 contact unknowns).
    let first = s["steps"][0]["iterations"].as_u64().unwrap();
    let want = [9, 5, 5, 6, 7][l - 3];
    assert_eq!(first, want, "L{l}: the first step's Newton iterations");
    (
        parts,
        s["dofs_free"].as_f64().unwrap(),
        s["contact_nodes"].as_f64().unwrap(),
    )
}

#[test]
fn the_factorisation_operations_grow_along_the_ladder_as_documented() {
    let dir = tempdir("factor-flops");
    let runs: Vec<(usize, [f64; 3], f64, f64)> = (3..=7)
        .map(|l| {
            let (f, dofs, ns) = flops_of(&dir, l);
            (l, f, dofs, ns)
        })
        .collect();
    let close = |got: f64, want: f64, tol: f64, what: &str| {
        assert!(
            (got - want).abs() <= tol * want.abs(),
            "{what}: {got:.4e} against {want:.4e} (±{:.1} %)",
            100.0 * tol
        );
    };
    for (l, f, _, ns) in &runs {
        // The constraint columns end the factor in one dense block of m = 2 n_s + 2 rows.
        let m = 2.0 * ns + 2.0;
        close(
            f[2],
            m.powi(3) / 3.0,
            1e-9,
            &format!("L{l} block against m³/3"),
        );
    }
    let at = |l: usize| runs.iter().find(|r| r.0 == l).unwrap().1;
    let (f5, f7) = (at(5), at(7));
    // docs/benchmarks.md: L5 2.69e9, 3.07e9, 3.54e8, to 0.5 %.
    close(f5[0], 2.69e9, 5e-3, "L5 K̂");
    close(f5[1], 3.07e9, 5e-3, "L5 coupling");
    close(f5[2], 3.54e8, 5e-3, "L5 constraint block");
    // L7 / L5: 13.1 in all, K̂ 4.4, the coupling 15.1, the block 62; the coupling and the
    // block at L7 11.1 × L5's whole factorisation.
    let (t5, t7): (f64, f64) = (f5.iter().sum(), f7.iter().sum());
    close(t7 / t5, 13.1, 5e-3, "total L7 / L5");
    close(f7[0] / f5[0], 4.4, 1e-2, "K̂ L7 / L5");
    close(f7[1] / f5[1], 15.1, 5e-3, "coupling L7 / L5");
    close(f7[2] / f5[2], 62.0, 1e-2, "block L7 / L5");
    close(
        (f7[1] + f7[2]) / t5,
        11.1,
        5e-3,
        "coupling + block at L7 / L5's total",
    );
    // Exponents against the free DOFs over L3–L7: N^1.24, N^2.15, N^3.80.
    let dofs: Vec<f64> = runs.iter().map(|r| r.2).collect();
    for (k, want) in [(0, 1.24), (1, 2.15), (2, 3.80)] {
        let part: Vec<f64> = runs.iter().map(|r| r.1[k]).collect();
        let e = fitted_rate(&dofs, &part);
        assert!(
            (e - want).abs() <= 0.006,
            "part {k}: exponent {e:.3} against {want}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
