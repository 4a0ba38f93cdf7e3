//! Checks run on a mesh before anything is assembled; each failure names the element, node or
//! group so that the user can find it in gmsh.

use super::{GroupDim, Mesh};
use crate::quadrature::TRI_6;
use crate::shapes::tri6;

/// A mesh that cannot be used, with what is wrong and where.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeshCheckError {
    #[error(
        "{path}: {}physical group `{name}` is not in the mesh (its groups: {available})",
        named_by(key)
    )]
    MissingGroup {
        path: String,
        /// The case key that names the group (`contact.slave`), or empty.
        key: String,
        name: String,
        available: String,
    },
    #[error("{path}: {}physical group `{name}` is empty", named_by(key))]
    EmptyGroup {
        path: String,
        key: String,
        name: String,
    },
    #[error(
        "{path}: {}physical group `{name}` is a {found}, but a {expected} is needed here",
        named_by(key)
    )]
    WrongDim {
        path: String,
        key: String,
        name: String,
        found: &'static str,
        expected: &'static str,
    },
    #[error("{path}: element {tag} is degenerate (its vertices are collinear or coincide)")]
    Degenerate { path: String, tag: u64 },
    #[error(
        "{path}: element {tag} is curved so much that its Jacobian is not positive at every \
         quadrature point (min det J = {min_det:.3e}); move its mid-edge nodes or refine there"
    )]
    BadJacobian {
        path: String,
        tag: u64,
        min_det: f64,
    },
    #[error(
        "{path}: bodies `{a}` and `{b}` share node {node} (and {more} more); each body must be \
         meshed on its own so that contact can separate them"
    )]
    SharedNodes {
        path: String,
        a: String,
        b: String,
        node: u64,
        more: usize,
    },
    #[error("{path}: boundary element {tag} in group `{group}` has zero length")]
    ZeroLengthEdge {
        path: String,
        tag: u64,
        group: String,
    },
    #[error("{path}: node {node} has a coordinate that is not a finite number")]
    NonFiniteNode { path: String, node: u64 },
    #[error(
        "{path}: boundary element {tag} in group `{group}` is not an edge of any triangle of the \
         bodies in use"
    )]
    DanglingEdge {
        path: String,
        tag: u64,
        group: String,
    },
}

/// What the checks found that is not an error.
#[derive(Debug, Clone, Default)]
pub struct CheckReport {
    /// Triangles that were clockwise in the file and were reoriented (gmsh tags).
    pub reoriented: Vec<u64>,
}

fn path(mesh: &Mesh) -> String {
    mesh.source.display().to_string()
}

/// `` `key`: `` before a group's message, when the key that names the group is known.
fn named_by(key: &str) -> String {
    if key.is_empty() {
        String::new()
    } else {
        format!("`{key}`: ")
    }
}

/// Checks that a group exists, is not empty and has the expected dimension.
pub fn require_group(mesh: &Mesh, name: &str, dim: GroupDim) -> Result<(), MeshCheckError> {
    require_named_group(mesh, "", name, dim)
}

/// [`require_group`] for a group that the case key `key` (`contact.slave`, `bodies[0].group`)
/// names; the errors name the key.
pub fn require_named_group(
    mesh: &Mesh,
    key: &str,
    name: &str,
    dim: GroupDim,
) -> Result<(), MeshCheckError> {
    let g = mesh
        .group(name)
        .ok_or_else(|| MeshCheckError::MissingGroup {
            path: path(mesh),
            key: key.into(),
            name: name.into(),
            available: mesh
                .groups
                .iter()
                .map(|g| g.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        })?;
    let label = |d: GroupDim| match d {
        GroupDim::Curve => "curve",
        GroupDim::Surface => "surface",
    };
    if g.dim != dim {
        return Err(MeshCheckError::WrongDim {
            path: path(mesh),
            key: key.into(),
            name: name.into(),
            found: label(g.dim),
            expected: label(dim),
        });
    }
    if g.elements.is_empty() {
        return Err(MeshCheckError::EmptyGroup {
            path: path(mesh),
            key: key.into(),
            name: name.into(),
        });
    }
    Ok(())
}

/// Checks the mesh for use with the given body (surface) groups and boundary (curve) groups.
///
/// * every named group exists, has the right dimension and is not empty;
/// * node coordinates are finite;
/// * no triangle of the bodies is degenerate, and the Jacobian of every (possibly curved)
///   triangle is positive at the vertices, the mid-edge nodes and the 6 quadrature points;
/// * no two bodies share a node;
/// * every boundary line has non-zero length.
pub fn check(
    mesh: &Mesh,
    bodies: &[&str],
    boundaries: &[&str],
) -> Result<CheckReport, MeshCheckError> {
    let keyless = |v: &[&str]| -> Vec<(String, String)> {
        v.iter().map(|g| (String::new(), g.to_string())).collect()
    };
    check_named(mesh, &keyless(bodies), &keyless(boundaries))
}

/// [`check`] with the case key that names each group (`(key, group)`, as
/// [`crate::case::Case::named_groups`] gives them): a missing, empty or wrong-dimension group's
/// error names the key (`` `contact.slave`: physical group `body` is a surface, … ``).
pub fn check_named<K: AsRef<str>, G: AsRef<str>>(
    mesh: &Mesh,
    bodies: &[(K, G)],
    boundaries: &[(K, G)],
) -> Result<CheckReport, MeshCheckError> {
    for (k, b) in bodies {
        require_named_group(mesh, k.as_ref(), b.as_ref(), GroupDim::Surface)?;
    }
    for (k, b) in boundaries {
        require_named_group(mesh, k.as_ref(), b.as_ref(), GroupDim::Curve)?;
    }
    let bodies: Vec<&str> = bodies.iter().map(|(_, b)| b.as_ref()).collect();
    let boundaries: Vec<&str> = boundaries.iter().map(|(_, b)| b.as_ref()).collect();
    let (bodies, boundaries) = (&bodies[..], &boundaries[..]);
    for (i, x) in mesh.nodes.iter().enumerate() {
        if !x[0].is_finite() || !x[1].is_finite() {
            return Err(MeshCheckError::NonFiniteNode {
                path: path(mesh),
                node: mesh.node_tags[i],
            });
        }
    }
    // Element geometry, body by body: the elements on rayon's threads, the first bad one (in
    // the group's order) reported; then the nodes each body owns.
    let mut owner: Vec<u32> = vec![u32::MAX; mesh.nodes.len()];
    for (bi, b) in bodies.iter().enumerate() {
        let g = mesh.group(b).expect("checked above");
        {
            use rayon::prelude::*;
            let d = jacobian_points();
            if let Some(Err(e)) = g
                .elements
                .par_iter()
                .map(|&e| element_geometry(mesh, e, &d))
                .find_first(Result::is_err)
            {
                return Err(e);
            }
        }
        for &e in &g.elements {
            for &n in &mesh.triangles[e].nodes {
                let o = owner[n];
                if o != u32::MAX && o as usize != bi {
                    let shared = shared_nodes(mesh, bodies[o as usize], b);
                    return Err(MeshCheckError::SharedNodes {
                        path: path(mesh),
                        a: bodies[o as usize].to_string(),
                        b: b.to_string(),
                        node: mesh.node_tags[shared[0]],
                        more: shared.len() - 1,
                    });
                }
                owner[n] = bi as u32;
            }
        }
    }
    for b in boundaries {
        let g = mesh.group(b).expect("checked above");
        for &l in &g.elements {
            let xe = mesh.line_coords(l);
            let len = (xe[0][0] - xe[1][0]).hypot(xe[0][1] - xe[1][1]);
            if len.is_nan() || len <= 0.0 {
                return Err(MeshCheckError::ZeroLengthEdge {
                    path: path(mesh),
                    tag: mesh.lines[l].tag,
                    group: b.to_string(),
                });
            }
        }
    }
    Ok(CheckReport {
        reoriented: mesh.reoriented.clone(),
    })
}

/// The reference derivatives of the shape functions where [`element_geometry`] checks the
/// Jacobian: the 6 quadrature points and the 6 nodes.
fn jacobian_points() -> [[[f64; 2]; 6]; 12] {
    std::array::from_fn(|k| {
        let p = if k < 6 {
            TRI_6[k].0
        } else {
            tri6::NODE_REF_COORDS[k - 6]
        };
        tri6::dn(p[0], p[1])
    })
}

/// An element's geometry: not degenerate (its vertex area above round-off of its size) and
/// a positive Jacobian at the quadrature points and the nodes (`d`: [`jacobian_points`]).
fn element_geometry(mesh: &Mesh, e: usize, d: &[[[f64; 2]; 6]; 12]) -> Result<(), MeshCheckError> {
    let xe = mesh.tri_coords(e);
    let tag = mesh.triangles[e].tag;
    // The longest vertex edge, squared.
    let scale2 = (0..3)
        .map(|k| {
            let [a, c] = [xe[k], xe[(k + 1) % 3]];
            (a[0] - c[0]).powi(2) + (a[1] - c[1]).powi(2)
        })
        .fold(0.0, f64::max);
    let area = tri6::vertex_area(&xe);
    if area.is_nan() || area <= 1e-12 * scale2 {
        return Err(MeshCheckError::Degenerate {
            path: path(mesh),
            tag,
        });
    }
    let min_det = d
        .iter()
        .map(|d| tri6::jacobian_det(&xe, d))
        .fold(f64::INFINITY, f64::min);
    if min_det.is_nan() || min_det <= 0.0 {
        return Err(MeshCheckError::BadJacobian {
            path: path(mesh),
            tag,
            min_det,
        });
    }
    Ok(())
}

fn shared_nodes(mesh: &Mesh, a: &str, b: &str) -> Vec<usize> {
    let na = mesh.group_nodes(mesh.group(a).expect("exists"));
    let nb = mesh.group_nodes(mesh.group(b).expect("exists"));
    na.into_iter()
        .filter(|n| nb.binary_search(n).is_ok())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Group;

    #[test]
    fn a_group_error_names_the_key_that_names_the_group() {
        let group = |name: &str, dim| Group {
            name: name.into(),
            dim,
            tag: 1,
            elements: vec![0],
        };
        let mesh = Mesh {
            source: "m.msh".into(),
            groups: vec![
                group("body", GroupDim::Surface),
                group("face", GroupDim::Curve),
            ],
            ..Default::default()
        };
        let e = require_named_group(&mesh, "contact.slave", "body", GroupDim::Curve).unwrap_err();
        assert_eq!(
            e.to_string(),
            "m.msh: `contact.slave`: physical group `body` is a surface, but a curve is needed \
             here"
        );
        let e = require_named_group(&mesh, "bodies[1].group", "ghost", GroupDim::Surface)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`bodies[1].group`: physical group `ghost` is not"),
            "{e}"
        );
        // Without a key, the message is as before.
        let e = require_group(&mesh, "body", GroupDim::Curve).unwrap_err();
        assert!(
            e.to_string()
                .contains("m.msh: physical group `body` is a surface")
        );
    }
}
