//! The mesh: nodes, 6-node triangles, 3-node boundary lines and named physical groups.
//!
//! Read from gmsh MSH 4.1 by [`gmsh::read`], then checked by [`check::check`] before anything
//! is assembled.

pub mod check;
pub mod gmsh;
pub mod info;

use std::path::PathBuf;

/// A 6-node triangle (see [`crate::shapes::tri6`] for the node numbering).
#[derive(Clone, Debug)]
pub struct Tri6 {
    /// Indices into [`Mesh::nodes`].
    pub nodes: [usize; 6],
    /// gmsh element tag (used in messages).
    pub tag: u64,
}

/// A 3-node line (see [`crate::shapes::lin3`]).
#[derive(Clone, Debug)]
pub struct Lin3 {
    /// Indices into [`Mesh::nodes`].
    pub nodes: [usize; 3],
    /// gmsh element tag (used in messages).
    pub tag: u64,
}

/// Dimension of a physical group: 2 for surfaces (bodies), 1 for curves (boundaries).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GroupDim {
    Curve,
    Surface,
}

/// A named physical group: a set of triangles (surface) or of lines (curve).
#[derive(Clone, Debug)]
pub struct Group {
    pub name: String,
    pub dim: GroupDim,
    /// gmsh physical tag.
    pub tag: i32,
    /// Indices into [`Mesh::triangles`] (surface) or [`Mesh::lines`] (curve).
    pub elements: Vec<usize>,
}

/// A 2-D mesh of quadratic triangles with named groups.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Where it was read from (for messages).
    pub source: PathBuf,
    /// Node coordinates (x, y).
    pub nodes: Vec<[f64; 2]>,
    /// gmsh node tags, parallel to `nodes` (for messages).
    pub node_tags: Vec<u64>,
    pub triangles: Vec<Tri6>,
    pub lines: Vec<Lin3>,
    pub groups: Vec<Group>,
    /// Triangles that were clockwise in the file and were reoriented on reading (gmsh tags).
    pub reoriented: Vec<u64>,
}

impl Mesh {
    /// The group with this name, if any.
    pub fn group(&self, name: &str) -> Option<&Group> {
        self.groups.iter().find(|g| g.name == name)
    }

    /// The bounding box (lower, upper corner) of a set of nodes.
    pub fn bounding_box(&self, nodes: impl IntoIterator<Item = usize>) -> ([f64; 2], [f64; 2]) {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for n in nodes {
            for i in 0..2 {
                lo[i] = lo[i].min(self.nodes[n][i]);
                hi[i] = hi[i].max(self.nodes[n][i]);
            }
        }
        (lo, hi)
    }

    /// The diagonal of the bounding box of all nodes: the model's size.
    pub fn diameter(&self) -> f64 {
        let (lo, hi) = self.bounding_box(0..self.nodes.len());
        (hi[0] - lo[0]).hypot(hi[1] - lo[1])
    }

    /// Node coordinates of triangle `e`.
    pub fn tri_coords(&self, e: usize) -> [[f64; 2]; 6] {
        self.triangles[e].nodes.map(|n| self.nodes[n])
    }

    /// Node coordinates of line `l`.
    pub fn line_coords(&self, l: usize) -> [[f64; 2]; 3] {
        self.lines[l].nodes.map(|n| self.nodes[n])
    }

    /// The sorted, de-duplicated node indices of a group.
    pub fn group_nodes(&self, g: &Group) -> Vec<usize> {
        let mut v: Vec<usize> = match g.dim {
            GroupDim::Surface => g
                .elements
                .iter()
                .flat_map(|&e| self.triangles[e].nodes)
                .collect(),
            GroupDim::Curve => g
                .elements
                .iter()
                .flat_map(|&l| self.lines[l].nodes)
                .collect(),
        };
        v.sort_unstable();
        v.dedup();
        v
    }
}
