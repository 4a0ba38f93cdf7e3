//! The initial gap profile of a contact pair: the radius of the parabola fitted to it and
//! whether it is Hertzian, which decides where the paper's closed forms apply (the summary's
//! Λ, s0, JKR and double C–M values, the `hertz_a` check, a step's `k2_paper`).

use crate::model::Model;

/// The relative RMS residual of the parabola fitted to the initial gaps ([`fit_radius`])
/// above which a profile is not Hertzian: no closed form of the paper (Hertz, Cattaneo–Mindlin,
/// double C–M, JKR) is given for it. A circle of radius R fitted over a zone of half-width
/// `t` departs from its parabola by about `t²/(8R²)` of the gap, far below this for the
/// shipped scenes; a flat punch with rounded corners departs by tens of per cent.
pub const HERTZ_PROFILE_LIMIT: f64 = 0.02;

/// Why no closed form applies to a profile fitted with radius `radius` and relative RMS
/// residual `rms` ([`fit_radius`]); `None` when the profile is Hertzian.
pub fn not_hertzian(radius: f64, rms: f64) -> Option<String> {
    if !radius.is_finite() || radius <= 0.0 {
        Some(format!(
            "profile not Hertzian: the initial gap has no positive curvature (fitted R = {radius:.4e})"
        ))
    } else if rms.is_nan() || rms > HERTZ_PROFILE_LIMIT {
        Some(format!(
            "profile not Hertzian: the initial gap departs from its fitted parabola (R = {radius:.4e}) by {:.1} % rms of the largest gap, above {:.0} %",
            100.0 * rms,
            100.0 * HERTZ_PROFILE_LIMIT
        ))
    } else {
        None
    }
}

/// The radius of the initial gap profile `g0 ≈ g_min + t²/(2R)` (t along the tangent of the
/// first touch from the node of smallest gap), fitted by least squares over the zone nodes
/// with |t| ≤ `t_max` (all of them when `None`). Returns (R, the closest node's position, the
/// tangent, the RMS residual of the fit over the largest fitted gap).
pub fn fit_radius(model: &Model, t_max: Option<f64>) -> Option<(f64, [f64; 2], [f64; 2], f64)> {
    let cm = model.contact.as_ref()?;
    let m = &cm.pair.mortar;
    let n0 = cm.pair.common_normal.unwrap_or([0.0, 1.0]);
    let j0 = (0..m.gap0.len()).min_by(|&a, &b| m.gap0[a].total_cmp(&m.gap0[b]))?;
    let x0 = model.mesh.nodes[m.slave_nodes[j0]];
    let tau = [n0[1], -n0[0]];
    let pts: Vec<(f64, f64)> = (0..m.gap0.len())
        .map(|j| {
            let x = model.mesh.nodes[m.slave_nodes[j]];
            let t = (x[0] - x0[0]) * tau[0] + (x[1] - x0[1]) * tau[1];
            (t, m.gap0[j] - m.gap0[j0])
        })
        .filter(|(t, _)| t_max.is_none_or(|tm| t.abs() <= tm))
        .collect();
    let s4: f64 = pts.iter().map(|(t, _)| t.powi(4)).sum();
    let s2g: f64 = pts.iter().map(|(t, g)| t * t * g).sum();
    let radius = if s2g > 0.0 {
        s4 / (2.0 * s2g)
    } else {
        f64::INFINITY
    };
    let gmax = pts.iter().map(|p| p.1.abs()).fold(0.0, f64::max);
    let rms = (pts
        .iter()
        .map(|(t, g)| (g - t * t / (2.0 * radius)).powi(2))
        .sum::<f64>()
        / pts.len().max(1) as f64)
        .sqrt()
        / gmax.max(f64::MIN_POSITIVE);
    Some((radius, x0, tau, rms))
}
