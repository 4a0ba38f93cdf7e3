//! The contact output: the per-step CSV and the contact VTU describe the same nodes (the slave
//! nodes of the candidate zone's edges), so the two files a user opens side by side agree in
//! extent; and the CSV carries the documented columns.

mod common;
use common::vtu::Vtu;
use common::{run_case, shipped_case_on, validation_row};
use serde_json::json;

#[test]
fn contact_csv_and_vtu_hold_the_same_nodes() {
    let mut counts = Vec::new();
    for (case, mesh) in [
        ("vm272_cm.json", "vm272_L1.msh"),
        ("fig2.json", "vm272_L2.msh"),
    ] {
        let mut v = shipped_case_on(case, mesh);
        v["output"] = json!({"every": 1000});
        let r = run_case(&format!("contact-output-{case}"), &v, &["--quiet"]);
        r.assert_ok(case);
        let csv = r.last_contact();
        for col in [
            "x",
            "y",
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
            csv.col(col);
        }
        let step = r.history().rows.last().unwrap()[0] as usize;
        let vtu = Vtu::read(&r.out.join(format!("case_contact_{step:04}.vtu"))).unwrap();
        let points = vtu.points;
        let (xc, xs) = (csv.col("x"), &csv.rows);
        let extent = xs.iter().map(|r| r[xc].abs()).fold(0.0, f64::max);
        println!(
            "{case} on {mesh}: CSV {} nodes over |x| ≤ {extent:.4}, VTU {points} points",
            xs.len()
        );
        assert_eq!(
            points,
            xs.len(),
            "{case}: the VTU and the CSV differ in nodes"
        );
        counts.push(format!("{case} on {mesh}: {} and {points}", xs.len()));
    }
    validation_row(
        "325-contact-output",
        "contact CSV against contact VTU of the same step",
        "the same nodes",
        &format!("equal node counts ({})", counts.join("; ")),
        "contact_output",
    );
}
