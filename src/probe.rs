//! Field values at arbitrary points: locate the element that contains a point (inverse
//! isoparametric map by Newton's method) and evaluate displacement or stress there.

use crate::dofs::DofMap;
use crate::elasticity::{self, Material};
use crate::mesh::Mesh;
use crate::model::Model;
use crate::shapes::tri6;

/// Reference coordinates of `x` in an element, if it lies inside (with tolerance `tol`).
pub fn inverse_map(xe: &[[f64; 2]; 6], x: [f64; 2], tol: f64) -> Option<[f64; 2]> {
    let mut r = [1.0 / 3.0, 1.0 / 3.0];
    for _ in 0..30 {
        let mp = tri6::map_point(xe, r[0], r[1]);
        let d = tri6::dn(r[0], r[1]);
        let mut j = [[0.0; 2]; 2];
        for a in 0..6 {
            for i in 0..2 {
                for k in 0..2 {
                    j[i][k] += xe[a][i] * d[a][k];
                }
            }
        }
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if det == 0.0 {
            return None;
        }
        let res = [x[0] - mp.x[0], x[1] - mp.x[1]];
        let dr = [
            (j[1][1] * res[0] - j[0][1] * res[1]) / det,
            (-j[1][0] * res[0] + j[0][0] * res[1]) / det,
        ];
        r = [r[0] + dr[0], r[1] + dr[1]];
        if dr[0].abs() + dr[1].abs() < 1e-13 {
            break;
        }
    }
    (r[0] >= -tol && r[1] >= -tol && r[0] + r[1] <= 1.0 + tol).then_some(r)
}

/// The element of `elems` containing `x` and the reference coordinates there.
pub fn locate(
    mesh: &Mesh,
    elems: &[(usize, Material)],
    x: [f64; 2],
) -> Option<(usize, Material, [f64; 2])> {
    elems.iter().find_map(|(e, mat)| {
        let xe = mesh.tri_coords(*e);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &xe {
            for i in 0..2 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
        let pad = 0.1 * (hi[0] - lo[0]).max(hi[1] - lo[1]);
        if x[0] < lo[0] - pad || x[0] > hi[0] + pad || x[1] < lo[1] - pad || x[1] > hi[1] + pad {
            return None;
        }
        inverse_map(&xe, x, 1e-10).map(|r| (*e, *mat, r))
    })
}

/// Stress (σxx, σyy, σxy, σzz) at point `x`, evaluated inside its element (no averaging).
pub fn stress_at(
    mesh: &Mesh,
    elems: &[(usize, Material)],
    dofs: &DofMap,
    u: &[f64],
    x: [f64; 2],
) -> Option<[f64; 4]> {
    let (e, mat, r) = locate(mesh, elems, x)?;
    let nodes = &mesh.triangles[e].nodes;
    let ue: [f64; 12] = dofs.element_displacement(nodes, u);
    let xe = mesh.tri_coords(e);
    let mp = tri6::map_point(&xe, r[0], r[1]);
    Some(elasticity::stress_at_point(&xe, &mp, &ue, &mat))
}

impl Model {
    /// Stress (σxx, σyy, σxy, σzz) at point `x` of the model's bodies.
    pub fn stress_at(&self, x: [f64; 2], u: &[f64]) -> Option<[f64; 4]> {
        stress_at(&self.mesh, &self.elems, &self.dofs, u, x)
    }
}
