//! The fronts of a contact state, at each end separately: the stick zone, the zone where μ
//! has not yet weakened to `f_d`, and the mode-II stress intensity at each end of the stick
//! zone measured from the nodal tractions of the slave face.
//!
//! # Zones
//!
//! The nodes of the slave face are ordered along it (in +x or in −x). A zone (the stick nodes;
//! the weakening zone, the nodes in contact with `μ(slip) > f_d + 10⁻⁹ (f_s − f_d)`; the process
//! zone, those of them whose slip is below [`process_slip`]) runs from its first to its last
//! node, and each of its ends lies midway between the outermost node of the zone and the next
//! node outward (the node itself at the end of the face): located to ± h/4, h the node
//! spacing. The symmetric half-widths `c` and `b` of `history.csv` are half the distance
//! between the two ends.
//!
//! # K_II
//!
//! With a slip-weakening law the paper's JKR limit (eqs. sing, KII) puts a square-root
//! singularity in the shear traction at the stick front,
//!
//! ```text
//!   q_x(x) = f_d p(x) − f_d p*_c(x) + K sqrt(c / (π (c² − x²)))        |x| < c
//!   K_II   = lim_{x→c⁻} [q_x(x) − f_d p(x) + f_d p*_c(x)] sqrt(2π (c − x)) = sqrt(2 W E*)
//! ```
//!
//! where `p*_c` is the pressure of the same profile at contact semi-width `c` (Hertz:
//! `E* sqrt(c² − x²) / 2R`, eq. CM-q; any profile: `p(x, c)`, §4.4) and `W = (W/p) p` the
//! fracture energy at the front's pressure (eqs. Maugis, KIIa). The finite-element tractions are
//! bounded: the transition from `f_s` to `f_d` spans `[c, b]` (the process zone, a few s0 wide,
//! eq. s0), and `K_II` is the strength of the singular field *outside* it.
//!
//! **Estimator.** Per node of the stick zone, the excess of the shear traction over dynamic
//! friction, `e_j = s τ_j − f_d p_j` (`s = ±1` the direction of the shear on the slipping node
//! next to the front). In the JKR field above, with the stick zone between the tips `t_L` and
//! `t_R`,
//!
//! ```text
//!   w(x) ≡ e(x) sqrt((t_R − x)(x − t_L)) = K sqrt(c/π) − f_d E* (c² − x²) / 2R
//!   (t_R = −t_L = c)
//! ```
//!
//! is a quadratic in x, and for any smooth profile (and unequal `K` at the two ends) a smooth
//! function whose values at the tips are the stress intensities:
//! `K_L,R = w(t_L,R) sqrt(2π / (t_R − t_L))`. [`k2_fit`] fits
//! `w_j = e_j sqrt((t_R − x_j)(x_j − t_L))` by least squares with `w₀ + w₁ ρ + w₂ ρ²`, ρ the
//! distance from the tip, over the nodes of one front's band, and returns
//! `K = w₀ sqrt(2π / (t_R − t_L))`. It recovers the JKR field above to rounding, and a field
//! that is singular at one end only, `K / sqrt(2π ρ)`, to 0.1 % at that end
//! (`tests/fronts.rs`).
//!
//! **Tips.** The singular field seen from outside a process zone `[c, b]` is centred at its
//! midpoint, `t = (c + b)/2`: the process-zone part of the double Cattaneo–Mindlin traction
//! (eq. qx2CM), `C [sqrt(b² − x²) − sqrt(c² − x²)] = 2 C t δ / [sqrt(b² − x²) + sqrt(c² − x²)]`,
//! equals `C δ t / sqrt(t² − x²)` up to terms of relative order `(δ/ρ)²` (`δ = b − c`, ρ the
//! distance from `t`), where about `c` a first-order term `−δ / 4(c − x)` remains; the paper
//! notes the same when it plots `Q_x` against `(c + b)/2`. The process zone ends where the slip
//! reaches [`process_slip`]: the end `b` of the weakening zone for a ramp or a step, and the
//! slip `2Δ` for a law that reaches `f_d` only as the slip grows without bound (exponential).
//! Without weakening the tip is `c`.
//!
//! **Band.** `ρ ∈ [max(3 h_e, 4 δ), (t_R − t_L)/2]`, from the tip `t` of the front: from three
//! element lengths `h_e` (closer, the nodal tractions of the quadratic mortar elements do not
//! follow a square-root singularity) and four process-zone widths (the outer field), to the
//! centre of the stick zone (each front reads its own half). At least [`MIN_POINTS`] nodes, else
//! no value. With Fig. 2's ramp law at `Q = 0.8 f_d P` this gives `K_II / sqrt(2 W E*)` = 1.138,
//! 1.067 and 1.019 at Λ = 0.05 (L5), 0.0125 (L6) and 0.003 (L7), and 1.139 and 1.052 one mesh
//! level finer at the first two; the double Cattaneo–Mindlin field read the same way gives
//! 1.084, 1.026 and 1.008: the approach to the JKR limit is the problem's, not the estimator's.
//! From one load step to the next the values scatter by about ±1 %: the stick zone changes a
//! node at a time, and with it the origin of the regular part `−f_d p*_c ∝ sqrt(ρ)`, which moves
//! `K` by up to `f_d (E*/2R) sqrt(2π c) h/4` (h the node spacing). Cattaneo–Mindlin (no
//! weakening, no singularity) reads `|K_II| ≤ 0.0045 μ p0 sqrt(π a)`.

use crate::contact::solver::Status;

/// Fewest nodes in a front's band for a K_II value (three coefficients are fitted).
pub const MIN_POINTS: usize = 6;

/// Relative margin above `f_d` (in units of `f_s − f_d`) below which a node counts as weakened.
pub const WEAKENED_TOL: f64 = 1e-9;

/// A zone of consecutive face nodes: its first and last node (in the face's order) and its
/// two ends (positions, the first node's side first).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Zone {
    pub first: usize,
    pub last: usize,
    pub ends: [f64; 2],
}

impl Zone {
    /// The nodes of `x` (positions, in the face's order) from the first to the last for which
    /// `pred` holds, each end midway between the outermost node and the next one outward (the
    /// node itself at the end of the face). `None` when no node qualifies.
    pub fn of(x: &[f64], pred: impl Fn(usize) -> bool) -> Option<Zone> {
        let first = (0..x.len()).find(|&j| pred(j))?;
        let last = (0..x.len()).rfind(|&j| pred(j))?;
        let lo = if first > 0 {
            0.5 * (x[first] + x[first - 1])
        } else {
            x[first]
        };
        let hi = if last + 1 < x.len() {
            0.5 * (x[last] + x[last + 1])
        } else {
            x[last]
        };
        Some(Zone {
            first,
            last,
            ends: [lo, hi],
        })
    }

    /// Half the distance between the two ends.
    pub fn half_width(&self) -> f64 {
        0.5 * (self.ends[1] - self.ends[0]).abs()
    }

    /// The ends ordered by position: `[left, right]`.
    pub fn left_right(&self) -> [f64; 2] {
        [
            self.ends[0].min(self.ends[1]),
            self.ends[0].max(self.ends[1]),
        ]
    }
}

/// The nodal fields of the slave face that the fronts are read from, in the face's order.
pub struct Face<'a> {
    /// Position of each node along x.
    pub x: &'a [f64],
    /// Contact pressure `p_j = F_n,j / w_j`.
    pub p: &'a [f64],
    /// Shear traction on the slave body along its tangent, `τ_j = −F_t,j / w_j` (the `shear` of
    /// the contact output).
    pub tau: &'a [f64],
    pub status: &'a [Status],
    /// Element length at each node (the edge chord).
    pub h: &'a [f64],
}

/// A front of weakening on the contact line: a node in contact whose friction has weakened
/// (`μ(slip) < f_s`) next to one in contact that has not. A rupture spreading from a weakened
/// patch has one at each end, moving outwards; a stick zone shrinking under a tangential load
/// has one at each of its ends, moving inwards.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeakeningFront {
    /// Midway between the outermost weakened node and the first unweakened one.
    pub x: f64,
    /// `+1` when the unweakened side lies at larger x (the front moves in +x), else `−1`.
    pub dir: f64,
    /// The length of its process zone: from the front back to the first node whose slip has
    /// reached the law's process slip (to the end of the weakened run where none has).
    pub process: f64,
    /// The node spacing at the front.
    pub spacing: f64,
    /// The nodes of the process zone, `lo..=hi` in the sorted order.
    pub nodes: (usize, usize),
}

/// The leftmost and the rightmost fronts of weakening of a contact line whose nodes lie at `x`
/// (increasing), in contact where `on`, weakened where `weak`, with the slip μ sees `slip` and
/// the law's process slip `process_slip`. A line with one front only gives it on the side it
/// moves towards (`[front, None]` for a front moving in −x).
pub fn weakening_fronts(
    x: &[f64],
    on: &[bool],
    weak: &[bool],
    slip: &[f64],
    process_slip: f64,
) -> [Option<WeakeningFront>; 2] {
    let n = x.len();
    let boundary = |k: usize| on[k] && on[k + 1] && weak[k] != weak[k + 1];
    let front = |k: usize| {
        let dir = if weak[k] { 1.0 } else { -1.0 };
        let lead = if weak[k] { k } else { k + 1 };
        // Walk back through the weakened run to where the slip reached the process slip.
        let mut end = lead;
        while slip[end] < process_slip {
            let next = if dir > 0.0 {
                end.checked_sub(1)
            } else {
                Some(end + 1).filter(|&j| j < n)
            };
            match next {
                Some(j) if weak[j] && on[j] => end = j,
                _ => break,
            }
        }
        let xf = 0.5 * (x[k] + x[k + 1]);
        WeakeningFront {
            x: xf,
            dir,
            process: (xf - x[end]).abs(),
            spacing: x[k + 1] - x[k],
            nodes: (lead.min(end), lead.max(end)),
        }
    };
    let first = (0..n.saturating_sub(1)).find(|&k| boundary(k));
    let last = (0..n.saturating_sub(1)).rfind(|&k| boundary(k));
    match (first, last) {
        (Some(a), Some(b)) if a != b => [Some(front(a)), Some(front(b))],
        (Some(a), _) => {
            let f = front(a);
            if f.dir < 0.0 {
                [Some(f), None]
            } else {
                [None, Some(f)]
            }
        }
        _ => [None, None],
    }
}

/// The slip at which the process zone of `law` ends: `2Δ`, with `Δ = (W/p)/(f_s − f_d)`
/// (eq. Maugis10) — the slip over which a linear ramp of the same `f_s`, `f_d` and `W` weakens
/// to `f_d`. A ramp and a step reach `f_d` by then (the process zone is the weakening zone); an
/// exponential law, which never does, has released `1 − e⁻² = 86 %` of `W`. `None` for a law
/// without weakening or whose `Δ` is not defined.
pub fn process_slip(law: &crate::friction::FrictionLaw) -> Option<f64> {
    let fd = law.f_dynamic().ok()?;
    (law.f_static() > fd)
        .then(|| law.delta().ok())
        .flatten()
        .filter(|d| *d > 0.0)
        .map(|d| 2.0 * d)
}

/// The tips of the two ends of the stick zone `stick` (in the order of `stick.ends`) and the
/// widths `δ = |b − c|` of their process zones: `t = (c + b)/2` with `b` the end of the
/// process zone `process` on the same side where it lies outside `c`, else `t = c`, `δ = 0`.
pub fn tips(stick: &Zone, process: Option<&Zone>) -> ([f64; 2], [f64; 2]) {
    let dir = (stick.ends[1] - stick.ends[0]).signum();
    let mut t = stick.ends;
    let mut delta = [0.0; 2];
    for k in 0..2 {
        let c = stick.ends[k];
        // Outward from the stick zone: against the face's order at the first end.
        let out = if k == 0 { -dir } else { dir };
        if let Some(b) = process.map(|w| w.ends[k]).filter(|b| (b - c) * out > 0.0) {
            t[k] = 0.5 * (c + b);
            delta[k] = (b - c).abs();
        }
    }
    (t, delta)
}

/// The mode-II stress intensity at the two ends of the stick zone `stick` (in the order of
/// `stick.ends`), by [`k2_fit`] from the traction excess `s τ − f_d p` of the stick nodes; the
/// ends of the process zone `process` outside the stick zone place the tips ([`tips`]), and the
/// band of an end starts at `max(3 h_e, 4 δ)` from its tip (`h_e` the element length at the
/// outermost stick node). An end gets no value when the node beyond it does not slip (the
/// contact edge, or the end of the face), its shear is zero, or its band holds fewer than
/// [`MIN_POINTS`] stick nodes.
pub fn k2_ends(face: &Face, stick: &Zone, process: Option<&Zone>, fd: f64) -> [Option<f64>; 2] {
    let n = face.x.len();
    let (tips, widths) = tips(stick, process);
    let neighbour = [stick.first.checked_sub(1), Some(stick.last + 1)];
    let edge_node = [stick.first, stick.last];
    let mut k2 = [None, None];
    for k in 0..2 {
        let Some(j) = neighbour[k].filter(|&j| j < n && face.status[j] == Status::Slip) else {
            continue;
        };
        let s = face.tau[j].signum();
        if face.tau[j] == 0.0 || !s.is_finite() {
            continue;
        }
        let (xs, es): (Vec<f64>, Vec<f64>) = (stick.first..=stick.last)
            .filter(|&i| face.status[i] == Status::Stick)
            .map(|i| (face.x[i], s * face.tau[i] - fd * face.p[i]))
            .unzip();
        let rho_min = (3.0 * face.h[edge_node[k]]).max(4.0 * widths[k]);
        k2[k] = k2_fit(&xs, &es, tips, k, rho_min);
    }
    k2
}

/// `K_II` at the tip `tips[end]` of a stick zone between the tips `tips` from the traction
/// excess `e[j]` at the positions `x[j]`:
///
/// ```text
///   w_j = e_j sqrt(|x_j − t₀| |t₁ − x_j|)  ≈  w₀ + w₁ ρ_j + w₂ ρ_j²   (least squares)
///   K   = w₀ sqrt(2π / |t₁ − t₀|)
/// ```
///
/// over the nodes strictly between the tips with `ρ_j = |x_j − tips[end]|` in
/// `[rho_min, |t₁ − t₀|/2]`. Exact for `e(x) = w(x) / sqrt((t₁ − x)(x − t₀))` with `w` a
/// quadratic, whose limit `e sqrt(2π ρ)` at `tips[end]` is `K`. `None` with fewer than
/// [`MIN_POINTS`] nodes in the band or a singular fit.
pub fn k2_fit(x: &[f64], e: &[f64], tips: [f64; 2], end: usize, rho_min: f64) -> Option<f64> {
    let width = (tips[1] - tips[0]).abs();
    let half = 0.5 * width;
    if half.is_nan() || half <= 0.0 {
        return None;
    }
    let t = tips[end];
    // Normal equations in ξ = ρ / half ∈ (0, 1], which keeps them well conditioned.
    let mut a = [[0.0f64; 3]; 3];
    let mut r = [0.0f64; 3];
    let mut count = 0;
    for (&xj, &ej) in x.iter().zip(e) {
        let inside = (xj - tips[0]) * (tips[1] - xj);
        let rho = (xj - t).abs();
        if inside.is_nan() || inside <= 0.0 || rho < rho_min || rho > half {
            continue;
        }
        let y = ej * inside.sqrt();
        let xi = rho / half;
        let phi = [1.0, xi, xi * xi];
        for p in 0..3 {
            r[p] += phi[p] * y;
            for q in 0..3 {
                a[p][q] += phi[p] * phi[q];
            }
        }
        count += 1;
    }
    if count < MIN_POINTS {
        return None;
    }
    let w = solve3(a, r)?;
    Some(w[0] * (2.0 * std::f64::consts::PI / width).sqrt())
}

/// `A w = r` by Gaussian elimination with partial pivoting; `None` for a pivot below 1e-12 of
/// the largest entry of `A`.
fn solve3(mut a: [[f64; 3]; 3], mut r: [f64; 3]) -> Option<[f64; 3]> {
    let scale = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for col in 0..3 {
        let piv = (col..3).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        let pivot = a[piv][col].abs();
        if pivot.is_nan() || pivot <= 1e-12 * scale {
            return None;
        }
        a.swap(col, piv);
        r.swap(col, piv);
        for row in col + 1..3 {
            let f = a[row][col] / a[col][col];
            for k in col..3 {
                a[row][k] -= f * a[col][k];
            }
            r[row] -= f * r[col];
        }
    }
    let mut w = [0.0; 3];
    for row in (0..3).rev() {
        let s: f64 = (row + 1..3).map(|k| a[row][k] * w[k]).sum();
        w[row] = (r[row] - s) / a[row][row];
    }
    Some(w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rupture_has_a_front_at_each_end_moving_out_and_a_stick_zone_one_at_each_end_moving_in() {
        let x: Vec<f64> = (0..11).map(|k| k as f64).collect();
        let on = vec![true; 11];
        // A rupture over nodes 3..=7, fully weakened (slip ≥ 1) over 4..=6.
        let slip = [0.0, 0.0, 0.0, 0.4, 1.0, 2.0, 1.0, 0.5, 0.0, 0.0, 0.0];
        let weak: Vec<bool> = slip.iter().map(|&s| s > 0.0).collect();
        let [l, r] = weakening_fronts(&x, &on, &weak, &slip, 1.0);
        let (l, r) = (l.unwrap(), r.unwrap());
        assert_eq!((l.x, l.dir, l.process, l.nodes), (2.5, -1.0, 1.5, (3, 4)));
        assert_eq!((r.x, r.dir, r.process, r.nodes), (7.5, 1.0, 1.5, (6, 7)));
        // A stick zone over 4..=6 between weakened runs: fronts moving inwards.
        let weak: Vec<bool> = (0..11).map(|k| !(4..=6).contains(&k)).collect();
        let slip: Vec<f64> = weak.iter().map(|&w| if w { 2.0 } else { 0.0 }).collect();
        let [l, r] = weakening_fronts(&x, &on, &weak, &slip, 1.0);
        assert_eq!((l.unwrap().x, l.unwrap().dir), (3.5, 1.0));
        assert_eq!(
            (r.unwrap().x, r.unwrap().dir, r.unwrap().process),
            (6.5, -1.0, 0.5)
        );
        // Open nodes make no front; a single front is given on the side it moves towards.
        let mut on = vec![true; 11];
        on[0] = false;
        let weak: Vec<bool> = (0..11).map(|k| k < 3).collect();
        let [l, r] = weakening_fronts(&x, &on, &weak, &[1.0; 11], 1.0);
        assert!(l.is_none());
        assert_eq!(r.unwrap().x, 2.5);
        assert_eq!(
            weakening_fronts(&x, &on, &[false; 11], &[0.0; 11], 1.0),
            [None, None]
        );
    }
}
