//! Complete elliptic integrals by the arithmetic–geometric mean.
//!
//! **Parameter convention**: `m = k²` (the *parameter*, as in Abramowitz & Stegun 17.2 and
//! `scipy.special.ellipk`), so `K(m) = ∫₀^{π/2} dθ / sqrt(1 − m sin²θ)` and
//! `E(m) = ∫₀^{π/2} sqrt(1 − m sin²θ) dθ`. The paper writes `K(k)`, `E(k)` with `k² = 1 − c²/b²`;
//! that is `m = 1 − c²/b²` here. Because `m` close to 1 loses digits in `1 − m`, the functions
//! [`ke_from_complement`] take the complementary modulus `k' = sqrt(1 − m)` (= `c/b`) directly.

use std::f64::consts::PI;

/// `(K, E)` from the complementary modulus `k' = sqrt(1 − m) ∈ [0, 1]`.
/// `K(1) = ∞` is returned as `f64::INFINITY` (with `E = 1`).
pub fn ke_from_complement(kp: f64) -> (f64, f64) {
    assert!(
        (0.0..=1.0).contains(&kp),
        "complementary modulus {kp} outside [0, 1]"
    );
    if kp == 0.0 {
        return (f64::INFINITY, 1.0);
    }
    // AGM: a0 = 1, g0 = k', c0² = m; E = K (1 − Σ 2^{n−1} c_n²), K = π / (2 a_∞)
    let (mut a, mut g) = (1.0_f64, kp);
    let m = (1.0 - kp) * (1.0 + kp);
    let mut sum = 0.5 * m;
    let mut pow = 0.5;
    for _ in 0..64 {
        let cn = 0.5 * (a - g);
        let an = 0.5 * (a + g);
        let gn = (a * g).sqrt();
        pow *= 2.0;
        sum += pow * cn * cn;
        a = an;
        g = gn;
        // quadratic convergence: once a − g is at rounding level, stop (further "terms" are
        // rounding noise multiplied by 2^n)
        if cn.abs() <= 1e-15 * a {
            break;
        }
    }
    let k = PI / (2.0 * a);
    (k, k * (1.0 - sum))
}

/// Complete elliptic integral of the first kind `K(m)`, `m = k² ∈ [0, 1]`.
pub fn ellipk(m: f64) -> f64 {
    ke_from_complement((1.0 - m).max(0.0).sqrt()).0
}

/// Complete elliptic integral of the second kind `E(m)`, `m = k² ∈ [0, 1]`.
pub fn ellipe(m: f64) -> f64 {
    ke_from_complement((1.0 - m).max(0.0).sqrt()).1
}

/// `J(b, c) = ∫_c^b sqrt((b² − x²)(x² − c²)) dx` for `0 ≤ c ≤ b`.
///
/// Closed form `J = (b/3) [(b² + c²) E(m) − 2 c² K(m)]`, `m = 1 − c²/b²` (the bracket of
/// eq. (W1)). The bracket cancels catastrophically as `c → b`, so for `m ≤ 1/2` the equivalent
/// series `J = (π b³ m² / 16) ₂F₁(1/2, 3/2; 3; m)` is used instead (from the substitution
/// `x² = b² − (b² − c²) cos²θ`).
pub fn j_integral(b: f64, c: f64) -> f64 {
    assert!(
        b >= 0.0 && c >= 0.0 && c <= b,
        "j_integral needs 0 <= c <= b, got b={b}, c={c}"
    );
    if b == 0.0 || c == b {
        return 0.0;
    }
    let kp = c / b;
    if kp == 0.0 {
        return b * b * b / 3.0;
    }
    let m = (1.0 - kp) * (1.0 + kp);
    if m <= 0.5 {
        let (mut term, mut sum) = (1.0_f64, 1.0_f64);
        let mut n = 0.0;
        while term > 1e-17 * sum {
            term *= (0.5 + n) * (1.5 + n) / ((3.0 + n) * (1.0 + n)) * m;
            sum += term;
            n += 1.0;
        }
        PI * b * b * b * m * m / 16.0 * sum
    } else {
        let (k, e) = ke_from_complement(kp);
        b / 3.0 * ((b * b + c * c) * e - 2.0 * c * c * k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        // mpmath (25 digits): K(0.5) = 1.8540746773013719, E(0.5) = 1.3506438810476755
        assert!((ellipk(0.5) - 1.854_074_677_301_371_9).abs() < 1e-14);
        assert!((ellipe(0.5) - 1.350_643_881_047_675_5).abs() < 2e-15);
        assert!((ellipk(0.0) - PI / 2.0).abs() < 1e-15);
        assert!((ellipe(0.0) - PI / 2.0).abs() < 1e-15);
        assert!((ellipe(1.0) - 1.0).abs() < 1e-15);
        // mpmath: K(0.99) = 3.6956373629898742, E(0.99) = 1.0159935450252239
        assert!((ellipk(0.99) - 3.695_637_362_989_874).abs() < 1e-14);
        assert!((ellipe(0.99) - 1.015_993_545_025_224).abs() < 2e-15);
    }

    #[test]
    fn j_branches_agree() {
        // both formulas at m = 0.5 exactly
        let b = 1.3;
        let c = b * 0.5_f64.sqrt();
        let (k, e) = ke_from_complement(c / b);
        let closed = b / 3.0 * ((b * b + c * c) * e - 2.0 * c * c * k);
        // the closed form loses ~2 digits to cancellation at m = 1/2
        assert!((j_integral(b, c) - closed).abs() < 1e-12 * closed);
        assert!((j_integral(2.0, 0.0) - 8.0 / 3.0).abs() < 1e-15);
    }
}
