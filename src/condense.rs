//! Static condensation onto the retained DOFs.
//!
//! With the free DOFs split into interior `I` and retained `B`,
//! ```text
//!   [K_II K_IB] [u_I]   [f_I]
//!   [K_BI K_BB] [u_B] = [f_B + r_B]
//! ```
//! where `r_B` are the forces the retained DOFs receive from outside the elastic bodies
//! (the pilot force, contact forces). Eliminating `u_I = K_II⁻¹ (f_I − K_IB u_B)` gives
//! ```text
//!   S u_B = g + r_B,   S = K_BB − K_BI K_II⁻¹ K_IB,   g = f_B − K_BI K_II⁻¹ f_I .
//! ```
//! `S` is dense and small; it is built once per model from `n_B` interior solves, done in
//! blocks of columns so that memory stays `O(n_I × block)`.

use crate::assembly::UpperCsc;
use crate::linsolve::Cholesky;
use rayon::prelude::*;

/// The condensed (Schur complement) system on the retained DOFs.
pub struct Condensed {
    pub n_i: usize,
    pub n_b: usize,
    /// `S`, dense, row-major `n_b × n_b`.
    pub s: Vec<f64>,
    /// `K_IB` by retained column: (interior row, value).
    k_ib: Vec<Vec<(usize, f64)>>,
    /// Largest diagonal entry of `K_BB` before condensation: the scale against which a
    /// vanishing pivot of `S` (a retained DOF that nothing holds) is judged.
    pub kbb_scale: f64,
}

/// Columns solved per block when building `S`.
const BLOCK: usize = 64;

impl Condensed {
    /// Builds `S` from the assembled free stiffness `k` and the factorised interior block.
    pub fn build(k: &UpperCsc, n_i: usize, chol: &Cholesky) -> Condensed {
        let n_b = k.n - n_i;
        let mut k_ib = vec![Vec::new(); n_b];
        let mut s = vec![0.0; n_b * n_b];
        for c in n_i..k.n {
            for p in k.col_ptr[c]..k.col_ptr[c + 1] {
                let (r, v) = (k.row_idx[p], k.values[p]);
                if r < n_i {
                    k_ib[c - n_i].push((r, v));
                } else {
                    let (i, j) = (r - n_i, c - n_i);
                    s[i * n_b + j] = v;
                    s[j * n_b + i] = v;
                }
            }
        }
        let kbb_scale = (0..n_b).map(|i| s[i * n_b + i].abs()).fold(0.0, f64::max);
        for start in (0..n_b).step_by(BLOCK) {
            let cols = BLOCK.min(n_b - start);
            let mut x = vec![0.0; n_i * cols];
            for j in 0..cols {
                for &(r, v) in &k_ib[start + j] {
                    x[j * n_i + r] = v;
                }
            }
            chol.solve_block_in_place(&mut x, cols);
            // S[i, start + j] −= K_IB[:, i] · X[:, j]
            let upd: Vec<(usize, usize, f64)> = (0..n_b)
                .into_par_iter()
                .flat_map_iter(|i| {
                    let x = &x;
                    let col = &k_ib[i];
                    (0..cols).map(move |j| {
                        let d: f64 = col.iter().map(|&(r, v)| v * x[j * n_i + r]).sum();
                        (i, start + j, d)
                    })
                })
                .collect();
            for (i, j, d) in upd {
                s[i * n_b + j] -= d;
            }
        }
        // Symmetrise round-off.
        for i in 0..n_b {
            for j in 0..i {
                let m = 0.5 * (s[i * n_b + j] + s[j * n_b + i]);
                s[i * n_b + j] = m;
                s[j * n_b + i] = m;
            }
        }
        Condensed {
            n_i,
            n_b,
            s,
            k_ib,
            kbb_scale,
        }
    }

    /// `g = f_B − K_BI K_II⁻¹ f_I`, and `x_f = K_II⁻¹ f_I` for later recovery.
    pub fn reduce(&self, f: &[f64], chol: &Cholesky) -> (Vec<f64>, Vec<f64>) {
        let mut xf = f[..self.n_i].to_vec();
        chol.solve_in_place(&mut xf);
        let g = (0..self.n_b)
            .map(|i| f[self.n_i + i] - self.k_ib[i].iter().map(|&(r, v)| v * xf[r]).sum::<f64>())
            .collect();
        (g, xf)
    }

    /// The full free solution from the retained values: `u_I = K_II⁻¹ (f_I − K_IB u_B)`.
    pub fn recover(&self, f: &[f64], u_b: &[f64], chol: &Cholesky) -> Vec<f64> {
        let mut u = f[..self.n_i].to_vec();
        for (i, col) in self.k_ib.iter().enumerate() {
            for &(r, v) in col {
                u[r] -= v * u_b[i];
            }
        }
        chol.solve_in_place(&mut u);
        u.extend_from_slice(u_b);
        u
    }

    /// `S u_B` (the forces the retained DOFs need, less `g`).
    pub fn s_mul(&self, u_b: &[f64]) -> Vec<f64> {
        (0..self.n_b)
            .map(|i| {
                (0..self.n_b)
                    .map(|j| self.s[i * self.n_b + j] * u_b[j])
                    .sum()
            })
            .collect()
    }
}
