//! Bracketing root finder and helpers (no bare Newton anywhere).

/// Bisection for a root of `f` in `[lo, hi]`, given `f(lo)` and `f(hi)` of opposite signs (or
/// one of them zero). Stops when the bracket is narrower than `xtol` (absolute) or after 200
/// halvings. Returns the midpoint of the final bracket.
pub(crate) fn bisect(mut f: impl FnMut(f64) -> f64, mut lo: f64, mut hi: f64, xtol: f64) -> f64 {
    let mut flo = f(lo);
    let fhi = f(hi);
    if flo == 0.0 {
        return lo;
    }
    if fhi == 0.0 {
        return hi;
    }
    debug_assert!(flo.signum() != fhi.signum(), "bisect: no sign change");
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if (hi - lo).abs() <= xtol || mid == lo || mid == hi {
            break;
        }
        let fm = f(mid);
        if fm == 0.0 {
            return mid;
        }
        if fm.signum() == flo.signum() {
            lo = mid;
            flo = fm;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Maximum of a function on `[lo, hi]`: dense scan with `n` intervals, then golden-section
/// refinement around the best sample. Returns `(x, f(x))`. Robust for unimodal functions and
/// for functions that are merely continuous (the scan picks the global basin).
pub(crate) fn maximize(f: impl Fn(f64) -> f64, lo: f64, hi: f64, n: usize) -> (f64, f64) {
    let n = n.max(2);
    let h = (hi - lo) / n as f64;
    let (mut ibest, mut fbest) = (0usize, f(lo));
    for i in 1..=n {
        let v = f(lo + h * i as f64);
        if v > fbest {
            ibest = i;
            fbest = v;
        }
    }
    let mut a = lo + h * ibest.saturating_sub(1) as f64;
    let mut b = (lo + h * (ibest + 1) as f64).min(hi);
    let gr = 0.5 * (5.0_f64.sqrt() - 1.0);
    let mut x1 = b - gr * (b - a);
    let mut x2 = a + gr * (b - a);
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..200 {
        if (b - a).abs() <= 1e-15 * (1.0 + a.abs().max(b.abs())) {
            break;
        }
        if f1 < f2 {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + gr * (b - a);
            f2 = f(x2);
        } else {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - gr * (b - a);
            f1 = f(x1);
        }
    }
    let x = 0.5 * (a + b);
    let fx = f(x);
    if fx >= fbest {
        (x, fx)
    } else {
        (lo + h * ibest as f64, fbest)
    }
}
