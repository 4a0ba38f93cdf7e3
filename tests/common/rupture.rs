//! The rupture fronts of a run read back from `history.csv` (`front_*`, `g_*`, `gamma_*`):
//! tracks per front, speeds by least squares over a window of steps, and the energy release
//! rate over the fracture energy averaged over the same window; the plane-strain wave speeds
//! of the PMMA-like blocks of `cases/rupture_pmma.json`.

use super::Table;

/// Young's modulus (MPa), Poisson's ratio and density (t/mm³) of the blocks.
pub const E: f64 = 5650.0;
pub const NU: f64 = 0.35;
pub const RHO: f64 = 1.17e-9;

/// Plane-strain wave speeds (mm/s): P, S and Rayleigh. The Rayleigh speed is the root of
/// `4 α_d α_s − (1 + α_s²)²` (`α = sqrt(1 − v²/c²)`) between 0.5 c_s and c_s, by bisection.
pub fn wave_speeds() -> (f64, f64, f64) {
    let mu = E / (2.0 * (1.0 + NU));
    let lambda = E * NU / ((1.0 + NU) * (1.0 - 2.0 * NU));
    let (cp, cs) = (((lambda + 2.0 * mu) / RHO).sqrt(), (mu / RHO).sqrt());
    let d = |v: f64| {
        let (ad, a_s) = (
            (1.0 - v * v / (cp * cp)).sqrt(),
            (1.0 - v * v / (cs * cs)).sqrt(),
        );
        4.0 * ad * a_s - (1.0 + a_s * a_s).powi(2)
    };
    let (mut lo, mut hi) = (0.5 * cs, (1.0 - 1e-12) * cs);
    for _ in 0..200 {
        let m = 0.5 * (lo + hi);
        if d(m) > 0.0 { lo = m } else { hi = m }
    }
    (cp, cs, 0.5 * (lo + hi))
}

/// One front over the steps integrated in time: time, distance from the centre `|x|`, the
/// energy release rate `G` and the fracture energy `Γ` of its process zone (NaN where none).
pub struct Track {
    pub t: Vec<f64>,
    pub ell: Vec<f64>,
    pub g: Vec<f64>,
    pub gamma: Vec<f64>,
}

/// The left and the right front of the steps integrated in time (`t > 0`) that have both.
pub fn tracks(h: &Table) -> [Track; 2] {
    let tc = h.col("t");
    let rows: Vec<&Vec<f64>> = h
        .rows
        .iter()
        .filter(|r| {
            r[tc] > 0.0 && r[h.col("front_left")].is_finite() && r[h.col("front_right")].is_finite()
        })
        .collect();
    ["left", "right"].map(|side| {
        let (x, g, gm) = (
            h.col(&format!("front_{side}")),
            h.col(&format!("g_{side}")),
            h.col(&format!("gamma_{side}")),
        );
        Track {
            t: rows.iter().map(|r| r[tc]).collect(),
            ell: rows.iter().map(|r| r[x].abs()).collect(),
            g: rows.iter().map(|r| r[g]).collect(),
            gamma: rows.iter().map(|r| r[gm]).collect(),
        }
    })
}

/// A front at one step: time, distance from the centre, speed (least-squares slope of `ell`
/// over the steps `i − k ..= i + k`) and the mean of `G/Γ` over the same steps (NaN if one of
/// them has no value).
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    pub t: f64,
    pub ell: f64,
    pub v: f64,
    pub ratio: f64,
}

/// The samples of `tr` with a window of `2k + 1` steps.
pub fn samples(tr: &Track, k: usize) -> Vec<Sample> {
    (k..tr.t.len().saturating_sub(k))
        .map(|i| {
            let w = i - k..=i + k;
            let n = (2 * k + 1) as f64;
            let (tm, lm) = (
                tr.t[w.clone()].iter().sum::<f64>() / n,
                tr.ell[w.clone()].iter().sum::<f64>() / n,
            );
            let (mut sxy, mut sxx) = (0.0, 0.0);
            for j in w.clone() {
                sxy += (tr.t[j] - tm) * (tr.ell[j] - lm);
                sxx += (tr.t[j] - tm).powi(2);
            }
            let ratio = w.map(|j| tr.g[j] / tr.gamma[j]).sum::<f64>() / n;
            Sample {
                t: tr.t[i],
                ell: tr.ell[i],
                v: sxy / sxx,
                ratio,
            }
        })
        .collect()
}

/// Per speed band `[lo, lo + 0.1) c_R` from `lo = 0.1` to `0.8`: the number of samples and
/// the mean, least and largest `G/Γ` of those in it.
pub fn bands(s: &[Sample], c_r: f64) -> Vec<(f64, usize, f64, f64, f64)> {
    (1..9)
        .map(|b| {
            let lo = 0.1 * b as f64;
            let r: Vec<f64> = s
                .iter()
                .filter(|x| x.v >= lo * c_r && x.v < (lo + 0.1) * c_r)
                .map(|x| x.ratio)
                .collect();
            let n = r.len();
            let mean = r.iter().sum::<f64>() / n.max(1) as f64;
            let min = r.iter().copied().fold(f64::INFINITY, f64::min);
            let max = r.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (lo, n, mean, min, max)
        })
        .collect()
}
