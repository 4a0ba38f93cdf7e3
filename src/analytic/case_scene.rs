//! The scene of a case file, as the closed forms see it (`stickslip analytic … --case CASE`):
//! the two bodies in contact with their moduli, the radii of their contact faces at the first
//! touch, the normal load and the friction law, so that theory and FE describe the same scene.
//!
//! * Body 1 is the body that holds `contact.slave`, body 2 the one that holds `contact.master`
//!   (each face's nodes belong to the triangles of one of the case's `bodies`).
//! * Each radius is fitted to its face's nodes near the first touch (the closest pair of
//!   nodes of the two faces): a least-squares circle (Kåsa's algebraic fit), first over a
//!   quarter of the face's extent, then over |t| ≤ 1.5a of the Hertz semi-width a those radii
//!   give; a straight face (its nodes within 1e-9 of their extent from a line) has R = ∞.
//!   On faces whose nodes lie on circles (gmsh puts mid-edge nodes on the geometry) the fit
//!   is exact to round-off.
//! * The normal load P is |F| of the first stage whose `pilot_y` is a force.
//! * The law is `contact.friction`, with Δ from Λ resolved with the pair's E*.

use super::hertz::{Geometry, Hertz};
use crate::case::Case;
use crate::case::Control;
use crate::friction::FrictionLaw;
use crate::mesh::{GroupDim, Mesh};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Why a case does not give a scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error(transparent)]
    Case(#[from] crate::case::CaseError),
    #[error(transparent)]
    MeshRead(#[from] crate::mesh::gmsh::MeshReadError),
    #[error(transparent)]
    MeshCheck(#[from] crate::mesh::check::MeshCheckError),
    #[error("--case {path}: {why}")]
    Scene { path: String, why: String },
}

/// One body of the scene.
#[derive(Clone, Debug)]
pub struct SceneBody {
    /// The case's surface group.
    pub group: String,
    /// Its contact face (a curve group of the case's `contact`).
    pub face: String,
    /// Radius of the face at the first touch (∞ for a flat).
    pub r: f64,
    pub e: f64,
    pub nu: f64,
    /// Face nodes the radius was fitted to.
    pub fitted_nodes: usize,
}

/// The scene of a case.
#[derive(Clone, Debug)]
pub struct CaseScene {
    pub path: PathBuf,
    pub body1: SceneBody,
    pub body2: SceneBody,
    /// The normal load, if a stage gives `pilot_y` as a force.
    pub load: Option<f64>,
    /// The friction law (`None`: frictionless).
    pub law: Option<FrictionLaw>,
    /// The first touch (midway between the closest nodes of the two faces).
    pub touch: [f64; 2],
    /// Half-width of the window the radii were fitted over.
    pub window: f64,
}

impl CaseScene {
    /// Reads the case at `path` and its mesh, and fits the scene.
    pub fn load(path: &Path) -> Result<CaseScene, SceneError> {
        let p = path.display().to_string();
        let bad = |why: String| SceneError::Scene {
            path: p.clone(),
            why,
        };
        let case = Case::load(path)?;
        let contact = case.contact.as_ref().ok_or_else(|| {
            bad("the case has no `contact`: there is no pair of faces to take radii from".into())
        })?;
        let mesh = crate::mesh::gmsh::read(&case.mesh_path(path))?;
        for (key, g) in [
            ("contact.slave", &contact.slave),
            ("contact.master", &contact.master),
        ] {
            crate::mesh::check::require_group(&mesh, g, GroupDim::Curve)
                .map_err(|e| bad(format!("`{key}`: {e}")))?;
        }
        for (i, b) in case.bodies.iter().enumerate() {
            crate::mesh::check::require_group(&mesh, &b.group, GroupDim::Surface)
                .map_err(|e| bad(format!("`bodies[{i}].group`: {e}")))?;
        }
        let faces = [contact.slave.as_str(), contact.master.as_str()];
        let nodes: Vec<Vec<usize>> = faces
            .iter()
            .map(|f| mesh.group_nodes(mesh.group(f).expect("checked")))
            .collect();
        // The body of each face: the case body whose triangles hold most of its nodes.
        let mut owner = vec![usize::MAX; mesh.nodes.len()];
        for (bi, b) in case.bodies.iter().enumerate() {
            for &e in &mesh.group(&b.group).expect("checked").elements {
                for &n in &mesh.triangles[e].nodes {
                    owner[n] = bi;
                }
            }
        }
        let mut body_of = [0usize; 2];
        for k in 0..2 {
            let mut count = vec![0usize; case.bodies.len()];
            for &n in &nodes[k] {
                if owner[n] != usize::MAX {
                    count[owner[n]] += 1;
                }
            }
            let (bi, &c) = count
                .iter()
                .enumerate()
                .max_by_key(|(_, c)| **c)
                .expect("a case has bodies");
            if c == 0 {
                return Err(bad(format!(
                    "`{}` ({}) is on none of the case's bodies",
                    if k == 0 {
                        "contact.slave"
                    } else {
                        "contact.master"
                    },
                    faces[k]
                )));
            }
            body_of[k] = bi;
        }
        if body_of[0] == body_of[1] {
            return Err(bad(format!(
                "`contact.slave` ({}) and `contact.master` ({}) are both on body `{}`: the closed \
                 forms are for two bodies",
                faces[0], faces[1], case.bodies[body_of[0]].group
            )));
        }
        // The first touch: the closest pair of nodes of the two faces.
        let x = &mesh.nodes;
        let (mut best, mut i0, mut j0) = (f64::INFINITY, 0, 0);
        for &i in &nodes[0] {
            for &j in &nodes[1] {
                let d = (x[i][0] - x[j][0]).powi(2) + (x[i][1] - x[j][1]).powi(2);
                if d < best {
                    (best, i0, j0) = (d, i, j);
                }
            }
        }
        let touch = [0.5 * (x[i0][0] + x[j0][0]), 0.5 * (x[i0][1] + x[j0][1])];
        let load = case.stages.iter().find_map(|s| match s.pilot_y {
            Some(Control::Force(f)) if f != 0.0 => Some(f.abs()),
            _ => None,
        });
        let body = |k: usize| &case.bodies[body_of[k]];
        let e_star =
            1.0 / ((1.0 - body(0).nu.powi(2)) / body(0).e + (1.0 - body(1).nu.powi(2)) / body(1).e);
        // Radii over a quarter of the smaller face's extent, then over |t| ≤ 1.5a.
        let extent = |k: usize| {
            let (lo, hi) = mesh.bounding_box(nodes[k].iter().copied());
            (hi[0] - lo[0]).hypot(hi[1] - lo[1])
        };
        let mut window = 0.25 * extent(0).min(extent(1));
        let mut fit = fit_both(&mesh, &nodes, touch, window);
        if let (Some(p), Ok(r)) = (load, fit.as_ref().map(|f| f.radius())) {
            let a = (4.0 * p * r / (std::f64::consts::PI * e_star)).sqrt();
            let w = 1.5 * a;
            if w < window
                && let Ok(f) = fit_both(&mesh, &nodes, touch, w)
            {
                (fit, window) = (Ok(f), w);
            }
        }
        let fit = fit.map_err(bad)?;
        let law = match &contact.friction {
            None => None,
            Some(spec) => Some(
                spec.resolve(e_star)
                    .map_err(|e| bad(format!("`contact.friction`: {e}")))?,
            ),
        };
        let scene_body = |k: usize| SceneBody {
            group: body(k).group.clone(),
            face: faces[k].to_string(),
            r: fit.r[k],
            e: body(k).e,
            nu: body(k).nu,
            fitted_nodes: fit.n[k],
        };
        Ok(CaseScene {
            path: path.to_path_buf(),
            body1: scene_body(0),
            body2: scene_body(1),
            load,
            law,
            touch,
            window,
        })
    }

    /// The closed forms' geometry: R from the two radii, E* from the two bodies.
    pub fn geometry(&self) -> super::Result<Geometry> {
        Geometry::from_bodies(
            self.body1.r,
            self.body2.r,
            self.body1.e,
            self.body1.nu,
            self.body2.e,
            self.body2.nu,
        )
    }

    /// The scene as JSON, for the output of the subcommands.
    pub fn to_json(&self) -> Value {
        let radius = |r: f64| {
            if r.is_finite() {
                json!(r)
            } else {
                json!("inf")
            }
        };
        let body = |b: &SceneBody| {
            json!({"group": b.group, "face": b.face, "r": radius(b.r), "e": b.e, "nu": b.nu,
                   "fitted_nodes": b.fitted_nodes})
        };
        json!({
            "case": self.path.display().to_string(),
            "body1": body(&self.body1),
            "body2": body(&self.body2),
            "load": self.load,
            "law": self.law,
            "first_touch": self.touch,
            "radius_window": self.window,
        })
    }

    /// Hertz for this scene's geometry under `load`.
    pub fn hertz(&self, load: f64) -> super::Result<Hertz> {
        Hertz::new(self.geometry()?, load)
    }
}

/// The radii of both faces fitted over |t| ≤ `window` of the touch point, and their node counts.
struct Fit {
    r: [f64; 2],
    n: [usize; 2],
}

impl Fit {
    /// The effective radius 1/(1/R1 + 1/R2).
    fn radius(&self) -> f64 {
        1.0 / (1.0 / self.r[0] + 1.0 / self.r[1])
    }
}

fn fit_both(
    mesh: &Mesh,
    nodes: &[Vec<usize>],
    touch: [f64; 2],
    window: f64,
) -> Result<Fit, String> {
    let mut r = [0.0; 2];
    let mut n = [0; 2];
    for k in 0..2 {
        let pts: Vec<[f64; 2]> = nodes[k]
            .iter()
            .map(|&i| [mesh.nodes[i][0] - touch[0], mesh.nodes[i][1] - touch[1]])
            .filter(|p| p[0].hypot(p[1]) <= window)
            .collect();
        if pts.len() < 3 {
            return Err(format!(
                "only {} node(s) of a contact face within {window:.3e} of the first touch: too few \
                 to fit its radius",
                pts.len()
            ));
        }
        // The other face's nodes near the touch, to tell a convex face from a concave one.
        let other: Vec<[f64; 2]> = nodes[1 - k]
            .iter()
            .map(|&i| [mesh.nodes[i][0] - touch[0], mesh.nodes[i][1] - touch[1]])
            .filter(|p| p[0].hypot(p[1]) <= window)
            .collect();
        r[k] = fit_circle(&pts, &other)?;
        n[k] = pts.len();
    }
    if r[0].is_infinite() && r[1].is_infinite() {
        return Err("both contact faces are straight: the closed forms need a curved face".into());
    }
    Ok(Fit { r, n })
}

/// The radius of the circle through `pts` (coordinates relative to the first touch), ∞ for a
/// straight face; an error for a face that is concave towards `other`.
fn fit_circle(pts: &[[f64; 2]], other: &[[f64; 2]]) -> Result<f64, String> {
    let m = pts.len() as f64;
    let mean = pts
        .iter()
        .fold([0.0; 2], |s, p| [s[0] + p[0] / m, s[1] + p[1] / m]);
    // Straight? The smaller principal deviation from the mean against the larger.
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in pts {
        let (dx, dy) = (p[0] - mean[0], p[1] - mean[1]);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    let tr = sxx + syy;
    let disc = ((sxx - syy).powi(2) + 4.0 * sxy * sxy).sqrt();
    let (l_max, l_min) = (0.5 * (tr + disc), (0.5 * (tr - disc)).max(0.0));
    if l_min.sqrt() <= 1e-9 * l_max.sqrt() {
        return Ok(f64::INFINITY);
    }
    // Kåsa: x² + y² + D x + E y + F = 0 in the least-squares sense.
    let mut a = [[0.0f64; 4]; 3];
    for p in pts {
        let z = p[0] * p[0] + p[1] * p[1];
        let row = [p[0], p[1], 1.0];
        for i in 0..3 {
            for j in 0..3 {
                a[i][j] += row[i] * row[j];
            }
            a[i][3] -= row[i] * z;
        }
    }
    let [d, e, f] = solve3(a).ok_or("the face's nodes do not determine a circle")?;
    let centre = [-0.5 * d, -0.5 * e];
    let r = (0.25 * (d * d + e * e) - f).sqrt();
    if !(r.is_finite() && r > 0.0) {
        return Err("the face's nodes do not determine a circle".into());
    }
    // Convex: the centre lies away from the other face.
    let m2 = other.len().max(1) as f64;
    let towards = other
        .iter()
        .fold([0.0; 2], |s, p| [s[0] + p[0] / m2, s[1] + p[1] / m2]);
    let side = centre[0] * (towards[0] - mean[0]) + centre[1] * (towards[1] - mean[1]);
    if !other.is_empty() && side > 0.0 {
        return Err(format!(
            "a contact face is concave at the first touch (radius {r:.4e}): the closed forms are \
             for convex cylinders"
        ));
    }
    Ok(r)
}

/// Gaussian elimination with partial pivoting on an augmented 3 × 4 system.
fn solve3(mut a: [[f64; 4]; 3]) -> Option<[f64; 3]> {
    for c in 0..3 {
        let p = (c..3).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))?;
        a.swap(c, p);
        if a[c][c] == 0.0 || !a[c][c].is_finite() {
            return None;
        }
        for r in c + 1..3 {
            let k = a[r][c] / a[c][c];
            for j in c..4 {
                a[r][j] -= k * a[c][j];
            }
        }
    }
    let mut x = [0.0; 3];
    for c in (0..3).rev() {
        let s: f64 = (c + 1..3).map(|j| a[c][j] * x[j]).sum();
        x[c] = (a[c][3] - s) / a[c][c];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_fit_is_exact_on_a_circle_and_infinite_on_a_line() {
        let arc: Vec<[f64; 2]> = (-10..=10)
            .map(|i| {
                let t = 0.01 * i as f64;
                [3.0 * t.sin(), 3.0 - 3.0 * t.cos()]
            })
            .collect();
        let below = [[0.0, -0.01]];
        let r = fit_circle(&arc, &below).unwrap();
        assert!((r / 3.0 - 1.0).abs() < 1e-9, "{r}");
        // The same arc seen from above is concave towards the other face.
        assert!(fit_circle(&arc, &[[0.0, 0.5]]).is_err());
        let line: Vec<[f64; 2]> = (-5..=5).map(|i| [0.1 * i as f64, 0.0]).collect();
        assert!(fit_circle(&line, &below).unwrap().is_infinite());
    }
}
