//! Contact benchmark: the shipped contact cases on the finest mesh (L5), each in its own
//! `stickslip` process, with the time of every phase and the ratio of the whole run to one
//! assembly plus factorisation measured in the same run.
//!
//! Run: `cargo bench --bench contact` (set STICKSLIP_THREADS, default 2; STICKSLIP_LEVEL to
//! change the mesh level). Output is written only at the last step.

use std::path::PathBuf;

#[path = "common/mod.rs"]
mod common;

fn main() {
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let tmp = std::env::temp_dir().join(format!("stickslip-bench-contact-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let threads = std::env::var("STICKSLIP_THREADS").unwrap_or_else(|_| "2".into());
    let level: usize = std::env::var("STICKSLIP_LEVEL")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    println!(
        "| case | steps | Newton its | read | assemble | analyse | factorise | condense (W) | contact Newton | other solve | write | total | total / (assemble+analyse+factorise) | peak MiB |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for case in ["hertz", "vm272_cm", "fig2", "fig3_ramp", "fig3_step"] {
        let mut v: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(repo.join(format!("cases/{case}.json"))).unwrap(),
        )
        .unwrap();
        v["mesh"] = serde_json::json!(
            repo.join(format!("meshes/vm272_L{level}.msh"))
                .to_str()
                .unwrap()
        );
        v["output"] = serde_json::json!({"vtu": true, "every": 100000});
        if case == "vm272_cm" {
            v["stages"][1]["steps"] = serde_json::json!(40);
        }
        let (ok, wall, s) = common::run_case(&v, case, &tmp, &threads);
        assert!(ok, "{case} failed");
        let g = |k: &str| s["timings_s"][k].as_f64().unwrap();
        let newton = s["contact_solve_s"].as_f64().unwrap();
        let floor = g("assemble") + g("analyse") + g("factorise");
        let total = g("read")
            + g("assemble")
            + g("analyse")
            + g("factorise")
            + g("condense")
            + g("solve")
            + g("write_wait");
        println!(
            "| {case} | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} (process {wall:.2}) | {:.2} | {:.0} |",
            s["steps"].as_array().unwrap().len(),
            s["newton_iterations"],
            g("read"),
            g("assemble"),
            g("analyse"),
            g("factorise"),
            g("condense"),
            newton,
            g("solve") - newton,
            g("write"),
            total,
            total / floor,
            s["peak_memory_mib"].as_f64().unwrap()
        );
    }
    println!(
        "\n(mesh level {level}; threads: {threads}; seconds; `condense` builds the Delassus operator W on the contact unknowns; `other solve` is the recovery of the full field at each step)"
    );
    let _ = std::fs::remove_dir_all(&tmp);
}
