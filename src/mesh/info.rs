//! Summary figures of a mesh for `stickslip mesh-info`: counts, groups, element sizes, quality.

use super::{GroupDim, Mesh};
use crate::quadrature::TRI_6;
use crate::shapes::tri6;
use serde::Serialize;

/// Figures of one physical group.
#[derive(Debug, Clone, Serialize)]
pub struct GroupInfo {
    pub name: String,
    pub dim: u8,
    pub tag: i32,
    pub elements: usize,
    pub nodes: usize,
    /// Smallest element size: chord length of a line, shortest vertex-to-vertex edge of a triangle.
    pub h_min: f64,
    /// Largest element size, as `h_min`.
    pub h_max: f64,
    /// Surfaces only: the smallest interior angle of any triangle (degrees, straight-sided).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_angle_deg: Option<f64>,
    /// Surfaces only: the largest ratio of longest edge to shortest altitude × √3/2 (1 for equilateral).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_aspect: Option<f64>,
    /// Surfaces only: the smallest ratio min det J / max det J within an element (1 for straight).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_scaled_jacobian: Option<f64>,
}

/// Figures of the whole mesh.
#[derive(Debug, Clone, Serialize)]
pub struct MeshInfo {
    pub file: String,
    pub nodes: usize,
    pub triangles: usize,
    pub lines: usize,
    pub reoriented_triangles: usize,
    pub groups: Vec<GroupInfo>,
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Computes the figures of every group of the mesh.
pub fn info(mesh: &Mesh) -> MeshInfo {
    let groups = mesh
        .groups
        .iter()
        .map(|g| {
            let (mut hmin, mut hmax) = (f64::INFINITY, 0.0f64);
            let mut quality = None;
            match g.dim {
                GroupDim::Curve => {
                    for &l in &g.elements {
                        let xe = mesh.line_coords(l);
                        let h = dist(xe[0], xe[1]);
                        hmin = hmin.min(h);
                        hmax = hmax.max(h);
                    }
                }
                GroupDim::Surface => {
                    let (mut amin, mut asp, mut sj) = (180.0f64, 1.0f64, 1.0f64);
                    for &e in &g.elements {
                        let xe = mesh.tri_coords(e);
                        let l = [dist(xe[1], xe[2]), dist(xe[2], xe[0]), dist(xe[0], xe[1])];
                        let (lo, hi) = (
                            l.iter().cloned().fold(f64::INFINITY, f64::min),
                            l.iter().cloned().fold(0.0, f64::max),
                        );
                        hmin = hmin.min(lo);
                        hmax = hmax.max(hi);
                        // Angles by the law of cosines.
                        for k in 0..3 {
                            let (a, b, c) = (l[k], l[(k + 1) % 3], l[(k + 2) % 3]);
                            let cos = ((b * b + c * c - a * a) / (2.0 * b * c)).clamp(-1.0, 1.0);
                            amin = amin.min(cos.acos().to_degrees());
                        }
                        let area = tri6::vertex_area(&xe).abs();
                        let alt_min = 2.0 * area / hi;
                        asp = asp.max(hi / alt_min * 3f64.sqrt() / 2.0);
                        let dets: Vec<f64> = TRI_6
                            .iter()
                            .map(|(p, _)| p)
                            .chain(tri6::NODE_REF_COORDS.iter())
                            .map(|p| tri6::map_point(&xe, p[0], p[1]).det_j)
                            .collect();
                        let (dmin, dmax) = (
                            dets.iter().cloned().fold(f64::INFINITY, f64::min),
                            dets.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
                        );
                        sj = sj.min(dmin / dmax);
                    }
                    quality = Some((amin, asp, sj));
                }
            }
            if g.elements.is_empty() {
                hmin = 0.0;
            }
            GroupInfo {
                name: g.name.clone(),
                dim: if g.dim == GroupDim::Curve { 1 } else { 2 },
                tag: g.tag,
                elements: g.elements.len(),
                nodes: mesh.group_nodes(g).len(),
                h_min: hmin,
                h_max: hmax,
                min_angle_deg: quality.map(|q| q.0),
                max_aspect: quality.map(|q| q.1),
                min_scaled_jacobian: quality.map(|q| q.2),
            }
        })
        .collect();
    MeshInfo {
        file: mesh.source.display().to_string(),
        nodes: mesh.nodes.len(),
        triangles: mesh.triangles.len(),
        lines: mesh.lines.len(),
        reoriented_triangles: mesh.reoriented.len(),
        groups,
    }
}
