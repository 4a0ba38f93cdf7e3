//! The jump to sliding in time: `cases/fig2_event.json` (Fig. 2's law pushed past Q_max under
//! force control, the event integrated until every contact node slides at f_d) on the
//! VM272 ladder, with the time step `dt` scaled with the contact elements (the shipped Courant
//! number c_s Δt / h ≈ 1.45) and the shipped largest step `dt_max` kept (it resolves the
//! bodies' vibrations, which do not change with the mesh), and the duration 2e-3 s: the creep
//! before the collapse lasts longer on finer meshes (880 µs on L5). Per level and step control: the
//! quasi-static steps, the event's time steps, the largest, Newton iterations per time step,
//! the factorisation of `K + c M`, the event's wall time and the process's, and peak memory.
//!
//! Run: `cargo bench --bench event` (STICKSLIP_LEVELS, default `5`, e.g. `3,4,5`;
//! STICKSLIP_THREADS, default 2; STICKSLIP_EVENT_FIXED, e.g. `3,4`: the levels also run with
//! every step `dt`, no `dt_max`). Output: only the tables (no `.vtu`).

use std::path::PathBuf;

#[path = "common/mod.rs"]
mod common;

fn main() {
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let tmp = std::env::temp_dir().join(format!("stickslip-bench-event-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let threads = std::env::var("STICKSLIP_THREADS").unwrap_or_else(|_| "2".into());
    let levels: Vec<usize> = std::env::var("STICKSLIP_LEVELS")
        .unwrap_or_else(|_| "5".into())
        .split(',')
        .map(|s| s.trim().parse().expect("levels: comma-separated integers"))
        .collect();
    let shipped: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(repo.join("cases/fig2_event.json")).unwrap())
            .unwrap();
    let dt3 = shipped["on_lost_equilibrium"]["dynamic"]["dt"]
        .as_f64()
        .unwrap();
    println!(
        "| L | step | quasi-static steps | time steps | Δt (s) | largest Δt (s) | t_end (s) | end | Newton its / time step | factorise K + cM (s) | event wall (s) | process wall (s) | peak MiB |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let fixed: Vec<usize> = std::env::var("STICKSLIP_EVENT_FIXED")
        .unwrap_or_default()
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| {
            s.trim()
                .parse()
                .expect("fixed levels: comma-separated integers")
        })
        .collect();
    for (level, mode) in levels.iter().flat_map(|&l| {
        let both = fixed.contains(&l);
        ["adaptive", "fixed"]
            .into_iter()
            .filter(move |m| *m == "adaptive" || both)
            .map(move |m| (l, m))
    }) {
        let mut v = shipped.clone();
        if mode == "fixed" {
            let d = v["on_lost_equilibrium"]["dynamic"].as_object_mut().unwrap();
            d.remove("dt_max");
        }
        v["mesh"] = serde_json::json!(
            repo.join(format!("meshes/vm272_L{level}.msh"))
                .to_str()
                .unwrap()
        );
        // The contact elements halve with each level from L3, the shipped level.
        let dt = dt3 * 2f64.powi(3 - level as i32);
        v["on_lost_equilibrium"]["dynamic"]["dt"] = serde_json::json!(dt);
        v["on_lost_equilibrium"]["dynamic"]["duration"] = serde_json::json!(2e-3);
        v["output"] = serde_json::json!({"vtu": false, "contact_csv": false});
        let name = format!("event_L{level}_{mode}");
        let (_, wall, s) = common::run_case(&v, &name, &tmp, &threads);
        let e = &s["events"][0];
        let steps = e["steps"].as_f64().unwrap();
        let n_records = s["steps"].as_array().unwrap().len();
        println!(
            "| {level} | {mode} | {} | {steps} | {dt:.3e} | {:.3e} | {:.4e} | {} | {:.2} | {:.2} | {:.1} | {wall:.1} | {:.0} |",
            n_records as f64 - steps,
            e["dt_largest"].as_f64().unwrap(),
            e["t_end"].as_f64().unwrap(),
            e["end"].as_str().unwrap(),
            e["newton_iterations"].as_f64().unwrap() / steps,
            e["factorise_s"].as_f64().unwrap(),
            e["wall_s"].as_f64().unwrap(),
            s["peak_memory_mib"].as_f64().unwrap()
        );
    }
    println!(
        "\n(threads: {threads}; the run exits 5: the load has no equilibrium, which is what the case asks to integrate)"
    );
    let _ = std::fs::remove_dir_all(&tmp);
}
