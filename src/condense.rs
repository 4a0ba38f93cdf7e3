//! Static condensation onto the retained DOFs.
//!
//! With the free DOFs split into interior `I` and retained `R` (numbered last),
//! ```text
//!   [K_II K_IR] [u_I]   [f_I]
//!   [K_RI K_RR] [u_R] = [f_R + r_R]
//! ```
//! where `r_R` are the forces the retained DOFs receive from outside the elastic bodies (the
//! pilot force, contact forces). Eliminating `u_I` gives the condensed system
//! ```text
//!   S u_R = g + r_R,   S = K_RR − K_RI K_II⁻¹ K_IR,   g = f_R − K_RI K_II⁻¹ f_I .
//! ```
//! Without contact, `S` comes out of one sparse Cholesky factorisation that orders `R` last
//! ([`PartialCholesky`]): `S = L_RR L_RRᵀ`. With contact the condensation goes straight to the
//! contact unknowns: the saddle-point matrix `[K̂ Yᵀ; Y 0]` is factorised ([`SaddleFactor`],
//! [`Factor::Saddle`]) and only `K̂` solves are asked of this module (`S` is never formed).
//!
//! A body held only through retained DOFs (the upper half-cylinder hangs on the pilot) makes
//! `K` singular. The listed *grounded* DOFs get a spring `k_g` to ground in the factorised
//! matrix `K̂ = K + k_g E Eᵀ`; since `Ŝ = S + k_g E Eᵀ` exactly, the spring is taken back out of
//! every equation (it appears as the force `k_g u` the spring would carry).

use crate::assembly::UpperCsc;
use crate::la::{FactorError, PartialCholesky, PartialSymbolic, SaddleFactor, SaddleSymbolic};

/// The factorisation behind a [`Condensed`] system.
pub enum Factor {
    /// `K̂` with the retained DOFs last and the dense `L_RR` (models without contact: the
    /// retained DOFs are the pilot's).
    Partial(PartialCholesky),
    /// The saddle-point matrix `[K̂ Yᵀ; Y 0]` of a contact model (see [`SaddleSymbolic`]):
    /// `K̂` solves from its leading block, the Delassus operator from its trailing block.
    Saddle(SaddleFactor),
}

impl Factor {
    /// Gives up the factor's hold on its values ([`SaddleFactor::release`]): `None` for a
    /// factor without contact, whose solves a run needs to its end. Any later solve panics.
    pub fn release(&self) -> Option<crate::la::SharedValues> {
        match self {
            Factor::Partial(_) => None,
            Factor::Saddle(s) => s.release(),
        }
    }

    /// Solves `K̂ x = b` in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        match self {
            Factor::Partial(c) => c.solve_in_place(b),
            Factor::Saddle(s) => s.solve_in_place(b),
        }
    }

    /// Solves `K̂ X = B` in place for a column-major block of `ncols` right-hand sides.
    pub fn solve_block_in_place(&self, b: &mut [f64], ncols: usize) {
        match self {
            Factor::Partial(c) => c.solve_block_in_place(b, ncols),
            Factor::Saddle(s) => s.solve_block_in_place(b, ncols),
        }
    }

    /// As [`Self::solve_block_in_place`], the columns of a saddle factor in one sweep on the
    /// calling thread ([`crate::la::SaddleFactor::solve_block_in_place_one_sweep`]).
    pub fn solve_block_in_place_one_sweep(&self, b: &mut [f64], ncols: usize) {
        match self {
            Factor::Partial(c) => c.solve_block_in_place(b, ncols),
            Factor::Saddle(s) => s.solve_block_in_place_one_sweep(b, ncols),
        }
    }

    /// `L_RR` of a partial factorisation.
    fn l_rr(&self) -> faer::MatRef<'_, f64> {
        match self {
            Factor::Partial(c) => c.l_rr(),
            Factor::Saddle(_) => {
                panic!("the dense condensed stiffness is formed only for models without contact")
            }
        }
    }
}

/// The values of `K̂ = K + k_g E Eᵀ` (springs on the `grounded` retained DOFs: `springs[i]`
/// on `grounded[i]` where given, else the matrix's own diagonal entry there), the springs
/// (retained index, `k_g`) and the largest diagonal entry of `K_RR`.
fn grounded_values(
    k: &UpperCsc,
    n_i: usize,
    grounded: &[usize],
    springs: Option<&[f64]>,
) -> (Vec<f64>, Vec<(usize, f64)>, f64) {
    let mut values = k.values.clone();
    let diag = |c: usize| k.position(c, c);
    let krr_scale = (n_i..k.n)
        .map(|c| k.values[diag(c)].abs())
        .fold(0.0, f64::max);
    let mut grounding = Vec::new();
    for (i, &r) in grounded.iter().enumerate() {
        let p = diag(n_i + r);
        let kg = match springs {
            Some(s) => s[i],
            None => k.values[p].abs().max(f64::MIN_POSITIVE),
        };
        values[p] += kg;
        grounding.push((r, kg));
    }
    (values, grounding, krr_scale)
}

/// The condensed system on the retained DOFs.
pub struct Condensed {
    pub n_i: usize,
    pub n_r: usize,
    /// Factorisation of `K̂`.
    pub chol: Factor,
    /// Grounding springs: (retained index, stiffness `k_g`).
    pub grounding: Vec<(usize, f64)>,
    /// Largest diagonal entry of `K_RR` before condensation: the scale against which a
    /// vanishing pivot of `S` (a retained DOF that nothing holds) is judged.
    pub krr_scale: f64,
}

impl Condensed {
    /// Factorises `K̂` (the assembled free stiffness `k` with springs on the `grounded`
    /// retained DOFs, given by retained index) with the symbolic analysis `symbolic`.
    pub fn build(
        k: &UpperCsc,
        n_i: usize,
        grounded: &[usize],
        symbolic: &PartialSymbolic,
    ) -> Result<Condensed, FactorError> {
        Self::build_with_springs(k, n_i, grounded, None, symbolic)
    }

    /// [`Condensed::build`] with the springs' stiffnesses `springs` (one per grounded DOF)
    /// instead of the matrix's diagonal: models of one case that share them (the quasi-static
    /// one and those of its time steps) hold the same anchor unknowns for the same forces.
    pub fn build_with_springs(
        k: &UpperCsc,
        n_i: usize,
        grounded: &[usize],
        springs: Option<&[f64]>,
        symbolic: &PartialSymbolic,
    ) -> Result<Condensed, FactorError> {
        let (values, grounding, krr_scale) = grounded_values(k, n_i, grounded, springs);
        let chol = Factor::Partial(symbolic.factorise(&k.col_ptr, &k.row_idx, &values)?);
        Ok(Condensed {
            n_i,
            n_r: k.n - n_i,
            chol,
            grounding,
            krr_scale,
        })
    }

    /// As [`Condensed::build`] for a contact model: factorises the saddle-point matrix
    /// `[K̂ Yᵀ; Y 0]` with the constraint rows `y_rows` (free-DOF index, coefficient), which
    /// must end with one unit row per grounded DOF, as analysed by `symbolic`.
    /// `springs`: as in [`Condensed::build_with_springs`].
    pub fn build_saddle(
        k: &UpperCsc,
        n_i: usize,
        (grounded, springs): (&[usize], Option<&[f64]>),
        y_rows: &[Vec<(usize, f64)>],
        symbolic: &SaddleSymbolic,
        dest: Option<Box<dyn crate::la::ValuesDestination>>,
    ) -> Result<Condensed, FactorError> {
        let (values, grounding, krr_scale) = grounded_values(k, n_i, grounded, springs);
        let chol = Factor::Saddle(symbolic.factorise_in(&values, y_rows, dest)?);
        Ok(Condensed {
            n_i,
            n_r: k.n - n_i,
            chol,
            grounding,
            krr_scale,
        })
    }

    /// Wall time of the contact constraint block within the numeric factorisation, seconds
    /// (zero where it was not timed apart: no contact, faer's loop, a factor from the cache).
    pub fn constraint_block_s(&self) -> f64 {
        match &self.chol {
            Factor::Saddle(f) => f.constraint_block_s,
            Factor::Partial(_) => 0.0,
        }
    }

    /// `Ŝ x` for a retained vector `x` (with the grounding springs).
    pub fn s_hat_mul(&self, x: &[f64]) -> Vec<f64> {
        let l = self.chol.l_rr();
        let n = self.n_r;
        // y = Lᵀ x, then L y.
        let mut y = vec![0.0; n];
        for j in 0..n {
            let mut s = 0.0;
            for i in j..n {
                s += l[(i, j)] * x[i];
            }
            y[j] = s;
        }
        let mut z = vec![0.0; n];
        for j in 0..n {
            for i in j..n {
                z[i] += l[(i, j)] * y[j];
            }
        }
        z
    }

    /// `S` as a dense row-major matrix (grounding removed).
    pub fn s_dense(&self) -> Vec<f64> {
        let n = self.n_r;
        let l = self.chol.l_rr();
        let mut s = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..=i {
                let v: f64 = (0..=j).map(|k| l[(i, k)] * l[(j, k)]).sum();
                s[i * n + j] = v;
                s[j * n + i] = v;
            }
        }
        for &(r, kg) in &self.grounding {
            s[r * n + r] -= kg;
        }
        s
    }

    /// The condensed load `g = f_R − K_RI K_II⁻¹ f_I` of a free load vector `f`.
    pub fn reduce(&self, f: &[f64]) -> Vec<f64> {
        let mut x = f.to_vec();
        self.chol.solve_in_place(&mut x);
        self.s_hat_mul(&x[self.n_i..])
    }

    /// The full free solution for loads `f` and forces `r_R` on the retained DOFs, given the
    /// retained displacements `u_R` they produce (needed to take the grounding back out):
    /// `u = K̂⁻¹ (f + [0; r_R + k_g E Eᵀ u_R])`.
    pub fn recover(&self, f: &[f64], r_r: &[f64], u_r: &[f64]) -> Vec<f64> {
        debug_assert_eq!(u_r.len(), self.n_r);
        let mut x = f.to_vec();
        for (i, r) in r_r.iter().enumerate() {
            x[self.n_i + i] += r;
        }
        for &(r, kg) in &self.grounding {
            x[self.n_i + r] += kg * u_r[r];
        }
        self.chol.solve_in_place(&mut x);
        // The retained part reproduces u_R to round-off; keep the exact values.
        x[self.n_i..].copy_from_slice(u_r);
        x
    }

    /// The full free solutions for load cases `(f, r_R)`: loads `f` and total forces `r_R` on
    /// the retained DOFs that already include the grounding-spring forces,
    /// `u = K̂⁻¹ (f + [0; r_R])`. One block solve: the factor is read once for all the cases,
    /// and each field is bit for bit what a solve of its own gives.
    ///
    /// `spread`: the columns split over rayon's threads; else one sweep on the calling thread
    /// (see [`Factor::solve_block_in_place_one_sweep`]).
    pub fn recover_total_many(
        &self,
        cases: &[(Vec<f64>, Vec<f64>)],
        spread: bool,
    ) -> Vec<Vec<f64>> {
        let Some(n) = cases.first().map(|(f, _)| f.len()) else {
            return Vec::new();
        };
        let mut x = Vec::with_capacity(n * cases.len());
        for (f, r_r) in cases {
            let col = x.len();
            x.extend_from_slice(f);
            for (i, r) in r_r.iter().enumerate() {
                x[col + self.n_i + i] += r;
            }
        }
        if spread {
            self.chol.solve_block_in_place(&mut x, cases.len());
        } else {
            self.chol
                .solve_block_in_place_one_sweep(&mut x, cases.len());
        }
        x.chunks_exact(n).map(<[f64]>::to_vec).collect()
    }
}
