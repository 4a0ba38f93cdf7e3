//! Quadrature rules on the reference triangle and on [−1, 1].

/// A point of a triangle rule: reference coordinates (ξ, η) and weight (weights sum to ½).
pub type TriPoint = ([f64; 2], f64);

/// Degree-2 rule, 3 interior points (the classical ξ = 1/6, 2/3 rule).
pub const TRI_3: [TriPoint; 3] = [
    ([1.0 / 6.0, 1.0 / 6.0], 1.0 / 6.0),
    ([2.0 / 3.0, 1.0 / 6.0], 1.0 / 6.0),
    ([1.0 / 6.0, 2.0 / 3.0], 1.0 / 6.0),
];

const A6: f64 = 0.445_948_490_915_965;
const WA6: f64 = 0.223_381_589_678_011 / 2.0;
const B6: f64 = 0.091_576_213_509_771;
const WB6: f64 = 0.109_951_743_655_322 / 2.0;

/// Degree-4 rule, 6 points (Strang & Fix / Dunavant).
pub const TRI_6: [TriPoint; 6] = [
    ([A6, A6], WA6),
    ([1.0 - 2.0 * A6, A6], WA6),
    ([A6, 1.0 - 2.0 * A6], WA6),
    ([B6, B6], WB6),
    ([1.0 - 2.0 * B6, B6], WB6),
    ([B6, 1.0 - 2.0 * B6], WB6),
];

const A7: f64 = 0.059_715_871_789_770;
const B7: f64 = 0.470_142_064_105_115;
const WB7: f64 = 0.132_394_152_788_506 / 2.0;
const C7: f64 = 0.797_426_985_353_087;
const D7: f64 = 0.101_286_507_323_456;
const WD7: f64 = 0.125_939_180_544_827 / 2.0;

/// Degree-5 rule, 7 points (Radon / Dunavant); used for error norms.
pub const TRI_7: [TriPoint; 7] = [
    ([1.0 / 3.0, 1.0 / 3.0], 0.225 / 2.0),
    ([B7, B7], WB7),
    ([A7, B7], WB7),
    ([B7, A7], WB7),
    ([D7, D7], WD7),
    ([C7, D7], WD7),
    ([D7, C7], WD7),
];

/// Gauss–Legendre points and weights on [−1, 1] with `n` points, n = 1..=5.
pub fn gauss_legendre(n: usize) -> &'static [(f64, f64)] {
    const G1: [(f64, f64); 1] = [(0.0, 2.0)];
    const G2: [(f64, f64); 2] = [
        (-0.577_350_269_189_625_8, 1.0),
        (0.577_350_269_189_625_8, 1.0),
    ];
    const G3: [(f64, f64); 3] = [
        (-0.774_596_669_241_483_4, 5.0 / 9.0),
        (0.0, 8.0 / 9.0),
        (0.774_596_669_241_483_4, 5.0 / 9.0),
    ];
    const G4: [(f64, f64); 4] = [
        (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
        (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
        (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
        (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
    ];
    const G5: [(f64, f64); 5] = [
        (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
        (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
        (0.0, 0.568_888_888_888_888_9),
        (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
        (0.906_179_845_938_664, 0.236_926_885_056_189_1),
    ];
    match n {
        1 => &G1,
        2 => &G2,
        3 => &G3,
        4 => &G4,
        _ => &G5,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫∫_T ξ^p η^q = p! q! / (p + q + 2)!
    fn exact(p: i32, q: i32) -> f64 {
        let f = |k: i32| (1..=k).map(|v| v as f64).product::<f64>();
        f(p) * f(q) / f(p + q + 2)
    }

    fn check(rule: &[TriPoint], degree: i32) {
        for p in 0..=degree {
            for q in 0..=(degree - p) {
                let s: f64 = rule
                    .iter()
                    .map(|(x, w)| w * x[0].powi(p) * x[1].powi(q))
                    .sum();
                assert!((s - exact(p, q)).abs() < 1e-14, "p={p} q={q}");
            }
        }
    }

    #[test]
    fn triangle_rules_are_exact_to_their_degree() {
        check(&TRI_3, 2);
        check(&TRI_6, 4);
        check(&TRI_7, 5);
    }

    #[test]
    fn gauss_rules_are_exact() {
        for n in 1..=5 {
            for k in 0..(2 * n as i32) {
                let s: f64 = gauss_legendre(n).iter().map(|(x, w)| w * x.powi(k)).sum();
                let e = if k % 2 == 1 {
                    0.0
                } else {
                    2.0 / (k as f64 + 1.0)
                };
                assert!((s - e).abs() < 1e-14, "n={n} k={k}");
            }
        }
    }
}
