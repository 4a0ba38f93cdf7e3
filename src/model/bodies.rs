//! What a case gives on its mesh before any matrix: the active elements and nodes of its
//! bodies, the orientation of its boundary groups, the contact pair and the nodes it retains,
//! the DOF numbering, the grounded DOFs of the bodies that only the pilot or the contact
//! holds, the contact's constraint rows and the nodal forces of the tractions ([`prepare`]).

use crate::case::{Case, TractionKind};
use crate::dofs::{DofMap, SupportSpec};
use crate::elasticity::Material;
use crate::error::ModelError;
use crate::loads::{EdgeOrientation, Traction};
use crate::mesh::{Mesh, check};
use std::time::Instant;

/// A model's parts before its matrix ([`prepare`]).
pub(super) struct Prepared {
    /// Active triangles with their materials, and the body index of each.
    pub elems: Vec<(usize, Material)>,
    pub elem_body: Vec<usize>,
    /// Active nodes (used by some active triangle).
    pub active: Vec<bool>,
    pub dofs: DofMap,
    /// The retained DOFs (as retained indices) grounded by springs: the pilot's, and the
    /// anchors of the bodies that nothing else holds.
    pub grounded: Vec<usize>,
    /// The contact pair, its constraint rows, the composite modulus E* of its bodies and the
    /// order of the rows in the saddle-point factorisation (large contact zones).
    pub pair: Option<crate::contact::Pair>,
    pub y: Option<crate::contact::ConstraintRows>,
    pub e_star: Option<f64>,
    pub row_order: Option<Vec<usize>>,
    /// See [`super::Model::pilot_separation`].
    pub pilot_separation: Option<(usize, [f64; 2])>,
    /// Nodal forces of the tractions at scale 1 (free DOFs).
    pub f_traction: Vec<f64>,
    /// Seconds to build the contact pair, and the traction forces.
    pub t_pair: f64,
    pub t_traction: f64,
}

/// Checks the mesh against the groups the case names and prepares the model's parts on it
/// (`gap` overrides the contact candidate gap).
pub(super) fn prepare(case: &Case, mesh: &Mesh, gap: Option<f64>) -> Result<Prepared, ModelError> {
    let path = mesh.source.display().to_string();
    // Each group with the case key that names it, for the messages.
    let (named_bodies, named_curves) = case.named_groups();
    check::check_named(mesh, &named_bodies, &named_curves)?;
    let curves = boundary_groups(case);
    crate::trace::mark("mesh checked");

    let (elems, elem_body) = body_elements(case, mesh);
    let active = active_nodes(mesh, &elems);
    let tris: Vec<usize> = elems.iter().map(|(e, _)| *e).collect();
    let orient = EdgeOrientation::for_groups(mesh, &tris, &curves);
    // Every boundary group must lie on the active bodies.
    for name in &curves {
        let g = mesh.group(name).expect("checked");
        for &l in &g.elements {
            orient
                .oriented_coords(mesh, l, name)
                .map_err(|source| ModelError::Edge {
                    path: path.clone(),
                    source,
                })?;
        }
    }

    // Contact: candidate zone and mortar operator, whose nodes are retained.
    crate::trace::mark("orientation");
    let t = Instant::now();
    let pair = contact_pair(case, mesh, &orient, gap, &path)?;
    let t_pair = t.elapsed().as_secs_f64();
    crate::trace::mark("contact pair");
    let retained = retained_nodes(pair.as_ref());
    let e_star = pair
        .as_ref()
        .map(|p| pair_e_star(case, mesh, &orient, &elems, &elem_body, p));

    let (dofs, pilot_nodes) = number_dofs(case, mesh, &active, &retained, &path)?;
    let pilot_separation = pilot_nodes
        .as_ref()
        .zip(pair.as_ref())
        .and_then(|(pn, p)| pilot_separation(mesh, &elems, &elem_body, pn, p, &dofs));
    // The pilot's DOFs are grounded: the body it drives may be held by nothing else.
    let mut grounded: Vec<usize> = dofs
        .pilot
        .map(|p| p.iter().map(|d| d - dofs.n_interior).collect())
        .unwrap_or_default();
    if !retained.is_empty() {
        grounded.extend(anchors_of_floating_bodies(
            mesh,
            &elems,
            &elem_body,
            case.bodies.len(),
            &dofs,
            &retained,
        ));
    }
    let y = pair
        .as_ref()
        .map(|p| crate::contact::ConstraintRows::new(p, &dofs, &grounded));
    // The order of the constraint rows in the saddle-point factorisation (large contact
    // zones: the one whose trailing block is also a Cholesky factor of leading sets).
    let row_order = y
        .as_ref()
        .filter(|y| y.rows.len() >= crate::contact::solver::PREFIX_FROM)
        .map(|y| crate::contact::solver::prefix_order(&y.gap0, y.rows.len()));
    crate::trace::mark("pair, dofs");
    let t = Instant::now();
    let f_traction = traction_forces(case, mesh, &orient, &dofs);
    let t_traction = t.elapsed().as_secs_f64();
    Ok(Prepared {
        elems,
        elem_body,
        active,
        dofs,
        grounded,
        pair,
        y,
        e_star,
        row_order,
        pilot_separation,
        f_traction,
        t_pair,
        t_traction,
    })
}

/// The curve groups the case names: supports, tractions, the pilot, then the contact pair
/// (slave, master).
fn boundary_groups(case: &Case) -> Vec<&str> {
    let mut curves: Vec<&str> = case.supports.iter().map(|s| s.group.as_str()).collect();
    curves.extend(case.tractions.iter().map(|t| t.group.as_str()));
    if let Some(p) = &case.pilot {
        curves.push(&p.group);
    }
    if let Some(c) = &case.contact {
        curves.push(&c.slave);
        curves.push(&c.master);
    }
    curves
}

/// The active triangles with their materials, body by body, and the body index of each.
fn body_elements(case: &Case, mesh: &Mesh) -> (Vec<(usize, Material)>, Vec<usize>) {
    let mut elems = Vec::new();
    let mut elem_body = Vec::new();
    for (bi, b) in case.bodies.iter().enumerate() {
        let mat = Material { e: b.e, nu: b.nu };
        for &e in &mesh.group(&b.group).expect("checked").elements {
            elems.push((e, mat));
            elem_body.push(bi);
        }
    }
    (elems, elem_body)
}

/// Flags per mesh node: used by some active triangle.
fn active_nodes(mesh: &Mesh, elems: &[(usize, Material)]) -> Vec<bool> {
    let mut active = vec![false; mesh.nodes.len()];
    for (e, _) in elems {
        for &n in &mesh.triangles[*e].nodes {
            active[n] = true;
        }
    }
    active
}

/// The contact pair of the case (candidate zone and mortar operator), if it has a `contact`.
fn contact_pair(
    case: &Case,
    mesh: &Mesh,
    orient: &EdgeOrientation,
    gap: Option<f64>,
    path: &str,
) -> Result<Option<crate::contact::Pair>, ModelError> {
    let Some(cs) = &case.contact else {
        return Ok(None);
    };
    let perr = |source| ModelError::Contact {
        path: path.to_string(),
        source,
    };
    let slave = crate::contact::oriented_edges(mesh, orient, &cs.slave).map_err(perr)?;
    let master = crate::contact::oriented_edges(mesh, orient, &cs.master).map_err(perr)?;
    let g = gap
        .or(cs.candidate_gap)
        .unwrap_or_else(|| crate::contact::default_candidate_gap(mesh, &slave));
    Ok(Some(
        crate::contact::build_pair(
            mesh,
            &cs.slave,
            &cs.master,
            &slave,
            &master,
            g,
            cs.normal == crate::case::NormalKind::Common,
        )
        .map_err(perr)?,
    ))
}

/// The nodes kept in the condensed system: those of the candidate zone and of the mortar rows,
/// each once, in order of first appearance.
fn retained_nodes(pair: Option<&crate::contact::Pair>) -> Vec<usize> {
    let mut retained: Vec<usize> = Vec::new();
    if let Some(p) = pair {
        let m = &p.mortar;
        retained.extend(p.zone_edges.iter().flatten());
        retained.extend(m.g_rows.iter().chain(&m.t_rows).flatten().map(|(n, _)| *n));
        let mut seen = std::collections::HashSet::new();
        retained.retain(|n| seen.insert(*n));
    }
    retained
}

/// The composite modulus E* of the pair, from the slave body (of the first zone edge) and the
/// master body (adjacent to the first master edge; the slave body if there is none).
fn pair_e_star(
    case: &Case,
    mesh: &Mesh,
    orient: &EdgeOrientation,
    elems: &[(usize, Material)],
    elem_body: &[usize],
    p: &crate::contact::Pair,
) -> f64 {
    let mut tri_body = vec![usize::MAX; mesh.triangles.len()];
    for ((e, _), &b) in elems.iter().zip(elem_body) {
        tri_body[*e] = b;
    }
    let body_of = |e: &[usize; 3]| {
        orient
            .edge_triangle(e[0], e[1])
            .map(|t| tri_body[t])
            .expect("oriented edge")
    };
    let mb = p.mortar.master_nodes.first().and_then(|_| {
        // The master body: the triangle adjacent to any master edge of the case group.
        let cs = case.contact.as_ref().expect("pair implies contact");
        crate::contact::oriented_edges(mesh, orient, &cs.master)
            .ok()
            .and_then(|v| v.first().map(body_of))
    });
    let sb = body_of(&p.zone_edges[0]);
    let inv = |b: usize| (1.0 - case.bodies[b].nu.powi(2)) / case.bodies[b].e;
    1.0 / (inv(sb) + inv(mb.unwrap_or(sb)))
}

/// Numbers the DOFs (supports, pilot, retained nodes); also returns the pilot's nodes.
fn number_dofs(
    case: &Case,
    mesh: &Mesh,
    active: &[bool],
    retained: &[usize],
    path: &str,
) -> Result<(DofMap, Option<Vec<usize>>), ModelError> {
    let support_nodes: Vec<Vec<usize>> = case
        .supports
        .iter()
        .map(|s| mesh.group_nodes(mesh.group(&s.group).expect("checked")))
        .collect();
    let supports: Vec<SupportSpec> = case
        .supports
        .iter()
        .zip(&support_nodes)
        .map(|(s, nodes)| SupportSpec {
            group: &s.group,
            nodes,
            value: [s.ux, s.uy],
        })
        .collect();
    let pilot_nodes = case
        .pilot
        .as_ref()
        .map(|p| mesh.group_nodes(mesh.group(&p.group).expect("checked")));
    let dofs = DofMap::build(
        &mesh.node_tags,
        active,
        &supports,
        case.pilot
            .as_ref()
            .map(|p| p.group.as_str())
            .zip(pilot_nodes.as_deref()),
        retained,
    )
    .map_err(|source| ModelError::Dof {
        path: path.to_string(),
        source,
    })?;
    Ok((dofs, pilot_nodes))
}

/// [`super::Model::pilot_separation`]: when the pilot (on nodes `pn`) drives the slave or master body
/// and no support holds that body, the body and the direction of pilot motion that opens the
/// contact (the slave's outward normal at the first touch, reversed for the slave body).
fn pilot_separation(
    mesh: &Mesh,
    elems: &[(usize, Material)],
    elem_body: &[usize],
    pn: &[usize],
    p: &crate::contact::Pair,
    dofs: &DofMap,
) -> Option<(usize, [f64; 2])> {
    let node_body = node_bodies(mesh, elems, elem_body);
    let bp = node_body[*pn.first()?];
    let sb = node_body[p.zone_edges[0][0]];
    let mb = node_body[*p.mortar.master_nodes.first()?];
    let n = p.first_touch;
    match held_by_supports(mesh, &node_body, bp, dofs).0 {
        true => None,
        false if bp == mb => Some((bp, n)),
        false if bp == sb => Some((bp, [-n[0], -n[1]])),
        false => None,
    }
}

/// Nodal forces (free DOFs) of the case's tractions at scale 1, edge by edge.
fn traction_forces(case: &Case, mesh: &Mesh, orient: &EdgeOrientation, dofs: &DofMap) -> Vec<f64> {
    let mut f_traction = vec![0.0; dofs.n_free()];
    for spec in &case.tractions {
        let load = match spec.kind {
            TractionKind::Uniform => Traction::Uniform {
                tx: spec.tx.unwrap_or(0.0),
                ty: spec.ty.unwrap_or(0.0),
            },
            TractionKind::Pressure => Traction::Pressure {
                p: spec.p.expect("validated"),
            },
            TractionKind::Hertz => Traction::Hertz {
                p0: spec.p0.expect("validated"),
                a: spec.a.expect("validated"),
                x0: spec.x0.unwrap_or(0.0),
            },
        };
        let g = mesh.group(&spec.group).expect("checked");
        for &l in &g.elements {
            let nodes = orient.oriented_nodes(mesh, l).expect("checked above");
            let xe = nodes.map(|n| mesh.nodes[n]);
            let fe = crate::loads::edge_forces(&xe, &load);
            for a in 0..3 {
                for c in 0..2 {
                    if let crate::dofs::Dof::Free(i) = dofs.node[nodes[a]][c] {
                        f_traction[i] += fe[a][c];
                    }
                }
            }
        }
    }
    f_traction
}

/// The body of each node (`usize::MAX` for nodes of no active triangle).
fn node_bodies(mesh: &Mesh, elems: &[(usize, Material)], elem_body: &[usize]) -> Vec<usize> {
    let mut node_body = vec![usize::MAX; mesh.nodes.len()];
    for ((e, _), &b) in elems.iter().zip(elem_body) {
        for &n in &mesh.triangles[*e].nodes {
            node_body[n] = b;
        }
    }
    node_body
}

/// Whether the supports of body `b` hold its three rigid modes (1,0), (0,1), (−y, x) (their
/// restriction to the body's fixed DOFs has rank 3), and whether the pilot drives the body.
fn held_by_supports(mesh: &Mesh, node_body: &[usize], b: usize, dofs: &DofMap) -> (bool, bool) {
    use crate::dofs::Dof;
    let pilot_dof = |d: Dof| matches!((d, dofs.pilot), (Dof::Free(i), Some(p)) if p.contains(&i));
    let mut g = [[0.0f64; 3]; 3];
    let mut piloted = false;
    let mut scale: f64 = 0.0;
    for (n, &nb) in node_body.iter().enumerate() {
        if nb != b {
            continue;
        }
        let x = mesh.nodes[n];
        scale = scale.max(x[0].abs()).max(x[1].abs());
        for c in 0..2 {
            let d = dofs.node[n][c];
            if pilot_dof(d) {
                piloted = true;
            }
            if let Dof::Fixed(_) = d {
                let row = if c == 0 {
                    [1.0, 0.0, -x[1]]
                } else {
                    [0.0, 1.0, x[0]]
                };
                for i in 0..3 {
                    for j in 0..3 {
                        g[i][j] += row[i] * row[j];
                    }
                }
            }
        }
    }
    // Normalise the rotation column so the determinant test is scale-free.
    let s = scale.max(f64::MIN_POSITIVE);
    for i in 0..3 {
        g[i][2] /= s;
        g[2][i] /= s;
    }
    let det = g[0][0] * (g[1][1] * g[2][2] - g[1][2] * g[2][1])
        - g[0][1] * (g[1][0] * g[2][2] - g[1][2] * g[2][0])
        + g[0][2] * (g[1][0] * g[2][1] - g[1][1] * g[2][0]);
    let tr = g[0][0] + g[1][1] + g[2][2];
    (det > 1e-8 * tr.powi(3), piloted)
}

/// Retained DOFs (as retained indices) to ground in bodies that no support or pilot holds, so
/// that a body held by contact alone still has a factorisable stiffness. Each such body gets
/// three anchors on its contact nodes (both components of one node, one component of the node
/// farthest from it), which the contact solver drives at zero force.
fn anchors_of_floating_bodies(
    mesh: &Mesh,
    elems: &[(usize, Material)],
    elem_body: &[usize],
    nbodies: usize,
    dofs: &DofMap,
    retained: &[usize],
) -> Vec<usize> {
    use crate::dofs::Dof;
    let node_body = node_bodies(mesh, elems, elem_body);
    let mut out = Vec::new();
    for b in 0..nbodies {
        let (held, piloted) = held_by_supports(mesh, &node_body, b, dofs);
        if piloted || held {
            continue;
        }
        let nodes: Vec<usize> = retained
            .iter()
            .copied()
            .filter(|&n| node_body[n] == b)
            .collect();
        let free = |n: usize, c: usize| match dofs.node[n][c] {
            Dof::Free(i) if i >= dofs.n_interior => Some(i - dofs.n_interior),
            _ => None,
        };
        let Some(&a) = nodes
            .iter()
            .find(|&&n| free(n, 0).is_some() && free(n, 1).is_some())
        else {
            continue;
        };
        let xa = mesh.nodes[a];
        let far = nodes.iter().copied().max_by(|&p, &q| {
            let d = |n: usize| (mesh.nodes[n][0] - xa[0]).hypot(mesh.nodes[n][1] - xa[1]);
            d(p).partial_cmp(&d(q)).expect("finite")
        });
        out.extend(free(a, 0));
        out.extend(free(a, 1));
        if let Some(f) = far.filter(|&f| f != a) {
            let xf = mesh.nodes[f];
            let c = if (xf[0] - xa[0]).abs() >= (xf[1] - xa[1]).abs() {
                1
            } else {
                0
            };
            out.extend(free(f, c));
        }
    }
    out
}
