//! The fields written per step: the bodies' VTU (displacement, stresses), and the contact
//! surface's VTU and CSV (pressure, shear, gap, slip, status, μ, q/p).

use crate::contact::solver::State;
use crate::model::Model;
use crate::output::{self, vtu};

/// Per slave node: (p, q, gap, slip, slip increment, status, μ, q/p, the slip μ sees, slip
/// rate). The slip rate is the slip increment over the time step `dt` of a step integrated in
/// time, zero in a quasi-static step (which takes no time).
fn contact_fields(model: &Model, st: &State, dt: Option<f64>) -> Vec<[f64; 10]> {
    let m = &model.contact.as_ref().expect("contact").pair.mortar;
    (0..m.slave_nodes.len())
        .map(|j| {
            let p = st.f_n[j] / m.weight[j];
            // Shear traction on the slave body along its tangent (the master force is −F_t τ on the slave).
            let q = -st.f_t[j] / m.weight[j];
            let ratio = if p > 0.0 { q / p } else { 0.0 };
            [
                p,
                q,
                st.gap[j],
                st.slip[j],
                st.dv[j],
                st.status[j].code(),
                st.mu[j],
                ratio,
                st.slip_mu[j],
                dt.map_or(0.0, |dt| st.dv[j] / dt),
            ]
        })
        .collect()
}

const CONTACT_FIELDS: [&str; 10] = [
    "pressure",
    "shear",
    "gap",
    "slip",
    "slip_increment",
    "status",
    "mu",
    "q_over_p",
    "slip_mu",
    "slip_rate",
];

/// The contact dataset: the slave edges of the candidate zone with the nodal contact fields
/// (`compress`: zlib-compressed arrays; `dt`: the time step of a step integrated in time).
pub fn contact_vtu(model: &Model, st: &State, dt: Option<f64>, compress: bool) -> Vec<u8> {
    let cm = model.contact.as_ref().expect("contact");
    let m = &cm.pair.mortar;
    let mut index = std::collections::HashMap::new();
    let mut points = Vec::new();
    let mut node_ids = Vec::new();
    for e in &cm.pair.zone_edges {
        for &n in e {
            index.entry(n).or_insert_with(|| {
                points.push(model.mesh.nodes[n]);
                node_ids.push(n);
                points.len() - 1
            });
        }
    }
    let cells: Vec<Vec<usize>> = cm
        .pair
        .zone_edges
        .iter()
        .map(|e| e.iter().map(|n| index[n]).collect())
        .collect();
    let fields = contact_fields(model, st, dt);
    let slot: std::collections::HashMap<usize, usize> = m
        .slave_nodes
        .iter()
        .enumerate()
        .map(|(j, &n)| (n, j))
        .collect();
    let mut data: Vec<vtu::Field> = CONTACT_FIELDS
        .iter()
        .enumerate()
        .map(|(k, name)| {
            vtu::Field::scalar(
                name,
                node_ids
                    .iter()
                    .map(|n| slot.get(n).map_or(0.0, |&j| fields[j][k]))
                    .collect(),
            )
        })
        .collect();
    let mut traction = Vec::new();
    let mut normal = Vec::new();
    for n in &node_ids {
        match slot.get(n) {
            Some(&j) => {
                let (p, q) = (fields[j][0], fields[j][1]);
                let (nv, tv) = (m.normal[j], m.tangent[j]);
                // Traction on the slave body: pressure pushes against its outward normal.
                traction.extend([-p * nv[0] + q * tv[0], -p * nv[1] + q * tv[1], 0.0]);
                normal.extend([nv[0], nv[1], 0.0]);
            }
            None => {
                traction.extend([0.0; 3]);
                normal.extend([0.0; 3]);
            }
        }
    }
    data.push(vtu::Field::vector("traction", traction));
    data.push(vtu::Field::vector("normal", normal));
    let topology = vtu::Topology::new(&points, &cells, vtu::Kind::Line3);
    vtu::unstructured(&topology, &data, &[], compress).to_vec()
}

/// The per-step CSV along the slave face (`dt`: the time step of a step integrated in time).
pub fn contact_csv(model: &Model, st: &State, dt: Option<f64>) -> String {
    let m = &model.contact.as_ref().expect("contact").pair.mortar;
    let fields = contact_fields(model, st, dt);
    let rows: Vec<Vec<f64>> = m
        .slave_nodes
        .iter()
        .zip(&fields)
        .map(|(&n, f)| {
            let x = model.mesh.nodes[n];
            let mut r = vec![x[0], x[1]];
            r.extend_from_slice(f);
            r
        })
        .collect();
    let mut header = vec!["x", "y"];
    header.extend(CONTACT_FIELDS);
    output::csv(&header, &rows, &["status"])
}

/// The parts of the bodies dataset that are the same at every step: the active nodes (as
/// points), the cells over them and each cell's body.
pub struct BodiesMesh {
    topology: vtu::Topology,
    cell_data: [vtu::Field; 1],
}

impl BodiesMesh {
    pub fn new(model: &Model) -> BodiesMesh {
        let mut index = vec![usize::MAX; model.mesh.nodes.len()];
        let mut points = Vec::new();
        for (n, &a) in model.active.iter().enumerate() {
            if a {
                index[n] = points.len();
                points.push(model.mesh.nodes[n]);
            }
        }
        let cells: Vec<[usize; 6]> = model
            .elems
            .iter()
            .map(|(e, _)| model.mesh.triangles[*e].nodes.map(|n| index[n]))
            .collect();
        let body = model.elem_body.iter().map(|&b| b as f64).collect();
        BodiesMesh {
            topology: vtu::Topology::new(&points, &cells, vtu::Kind::Tri6),
            cell_data: [vtu::Field::scalar("body_id", body)],
        }
    }
}

/// The names and component counts of the bodies dataset's point fields, in their order.
const BODIES_FIELDS: [(&str, u32); 6] = [
    ("displacement", 3),
    ("stress_xx", 1),
    ("stress_yy", 1),
    ("stress_xy", 1),
    ("stress_zz", 1),
    ("von_mises", 1),
];

/// The point fields of the bodies dataset at one step: displacement, stresses, von Mises
/// (`parallel`: the stresses on rayon's threads, else on the calling thread).
pub fn bodies_fields(model: &Model, u: &[f64], parallel: bool) -> Vec<vtu::Field> {
    fields_with_stress(model, u, model.nodal_stresses(u, parallel))
}

/// [`bodies_fields`] of several fields, their nodal stresses up to four at a time
/// ([`Model::nodal_stresses_many`], on the calling thread): the same fields.
pub fn bodies_fields_many(model: &Model, us: &[&[f64]]) -> Vec<Vec<vtu::Field>> {
    us.iter()
        .zip(model.nodal_stresses_many(us))
        .map(|(u, stress)| fields_with_stress(model, u, stress))
        .collect()
}

/// The point fields of a field `u` with its nodal stresses.
fn fields_with_stress(model: &Model, u: &[f64], stress: Vec<[f64; 4]>) -> Vec<vtu::Field> {
    let n = model.active.iter().filter(|&&a| a).count();
    let mut disp = Vec::with_capacity(n * 3);
    let (mut sxx, mut syy, mut sxy, mut szz, mut vm) = (
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    );
    for (n, &a) in model.active.iter().enumerate() {
        if !a {
            continue;
        }
        let d = model.dofs.displacement(n, u);
        disp.extend([d[0], d[1], 0.0]);
        let s = stress[n];
        sxx.push(s[0]);
        syy.push(s[1]);
        sxy.push(s[2]);
        szz.push(s[3]);
        vm.push(crate::elasticity::von_mises(s[0], s[1], s[2], s[3]));
    }
    [disp, sxx, syy, sxy, szz, vm]
        .into_iter()
        .zip(BODIES_FIELDS)
        .map(|(values, (name, ncomp))| vtu::Field {
            name: name.into(),
            ncomp,
            values,
        })
        .collect()
}

/// The bodies dataset of one step from its [`bodies_fields`] (`compress`: zlib-compressed
/// arrays).
pub fn bodies_vtu<'a>(
    mesh: &'a BodiesMesh,
    fields: &'a [vtu::Field],
    compress: bool,
) -> vtu::Encoded<'a> {
    vtu::unstructured(&mesh.topology, fields, &mesh.cell_data, compress)
}

/// What follows the point fields in the raw bodies dataset of every step
/// ([`vtu::raw_after_point_data`]): the cells' data, the points and the cells.
pub fn bodies_after_point_data(mesh: &BodiesMesh) -> vtu::AfterPointData<'_> {
    vtu::raw_after_point_data(&mesh.topology, &BODIES_FIELDS, &mesh.cell_data)
}
