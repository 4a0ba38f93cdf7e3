//! Degrees of freedom: which nodal displacement components are prescribed, which are unknowns,
//! and which unknowns are *retained* for condensation.
//!
//! Unknowns are numbered interior first (`0..n_interior`), retained last
//! (`n_interior..n_free`). The retained set holds the two DOFs of the rigid pilot (every node of
//! the pilot face shares them, so the face translates without rotating) and, for contact runs,
//! the candidate contact DOFs. The stiffness is then factorised on the interior block only and
//! the problem is condensed onto the retained DOFs (see [`crate::condense`]).

/// What a nodal displacement component is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Dof {
    /// Prescribed: index into [`DofMap::prescribed`].
    Fixed(usize),
    /// Unknown: index into the free vector.
    Free(usize),
    /// The node is not part of any active body.
    Unused,
}

/// The numbering of all nodal DOFs.
#[derive(Clone, Debug)]
pub struct DofMap {
    /// Per mesh node, the x and y components.
    pub node: Vec<[Dof; 2]>,
    pub n_interior: usize,
    pub n_retained: usize,
    /// Prescribed values.
    pub prescribed: Vec<f64>,
    /// Free index of the pilot's (x, y) DOFs, if there is a pilot.
    pub pilot: Option<[usize; 2]>,
}

/// A DOF that cannot be numbered as asked.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum DofError {
    #[error(
        "node {node} is both supported (group `{support}`) and on the rigid pilot face (group `{pilot}`)"
    )]
    SupportOnPilot {
        node: u64,
        support: String,
        pilot: String,
    },
    #[error("node {node} gets two different prescribed values for u{comp} from the supports")]
    ConflictingSupport { node: u64, comp: char },
}

/// A support: prescribed values on components of a set of nodes.
pub struct SupportSpec<'a> {
    pub group: &'a str,
    pub nodes: &'a [usize],
    /// Prescribed value per component, or `None` where the component is free.
    pub value: [Option<f64>; 2],
}

impl DofMap {
    /// Numbers the DOFs of the `active` nodes (flags per mesh node).
    ///
    /// `pilot`: the group name and nodes of the rigid face; `retained`: further nodes whose two
    /// components are kept for condensation (contact candidates), in the order given.
    pub fn build(
        node_tags: &[u64],
        active: &[bool],
        supports: &[SupportSpec],
        pilot: Option<(&str, &[usize])>,
        retained: &[usize],
    ) -> Result<DofMap, DofError> {
        #[derive(Clone, Copy, PartialEq)]
        enum Kind {
            Unused,
            Interior,
            Fixed(usize),
            Pilot(usize),
            Retained,
        }
        let nn = active.len();
        let mut kind = vec![[Kind::Unused; 2]; nn];
        for n in 0..nn {
            if active[n] {
                kind[n] = [Kind::Interior; 2];
            }
        }
        let mut prescribed = Vec::new();
        let mut fixed_by: Vec<[Option<usize>; 2]> = vec![[None; 2]; nn];
        for (si, s) in supports.iter().enumerate() {
            for &n in s.nodes {
                if !active[n] {
                    continue;
                }
                for c in 0..2 {
                    if let Some(v) = s.value[c] {
                        if let Kind::Fixed(k) = kind[n][c] {
                            if prescribed[k] != v {
                                return Err(DofError::ConflictingSupport {
                                    node: node_tags[n],
                                    comp: if c == 0 { 'x' } else { 'y' },
                                });
                            }
                            continue;
                        }
                        kind[n][c] = Kind::Fixed(prescribed.len());
                        fixed_by[n][c] = Some(si);
                        prescribed.push(v);
                    }
                }
            }
        }
        if let Some((name, nodes)) = pilot {
            for &n in nodes {
                if !active[n] {
                    continue;
                }
                for c in 0..2 {
                    if let Some(si) = fixed_by[n][c] {
                        return Err(DofError::SupportOnPilot {
                            node: node_tags[n],
                            support: supports[si].group.to_string(),
                            pilot: name.to_string(),
                        });
                    }
                    kind[n][c] = Kind::Pilot(c);
                }
            }
        }
        let mut extra = Vec::new();
        for &n in retained {
            for c in 0..2 {
                if kind[n][c] == Kind::Interior {
                    kind[n][c] = Kind::Retained;
                    extra.push((n, c));
                }
            }
        }
        let mut node = vec![[Dof::Unused; 2]; nn];
        let mut next = 0;
        for n in 0..nn {
            for c in 0..2 {
                node[n][c] = match kind[n][c] {
                    Kind::Interior => {
                        next += 1;
                        Dof::Free(next - 1)
                    }
                    Kind::Fixed(k) => Dof::Fixed(k),
                    _ => Dof::Unused,
                };
            }
        }
        let n_interior = next;
        let pilot_dofs = pilot.map(|_| {
            next += 2;
            [n_interior, n_interior + 1]
        });
        for n in 0..nn {
            for c in 0..2 {
                if let Kind::Pilot(pc) = kind[n][c] {
                    node[n][c] = Dof::Free(pilot_dofs.expect("pilot given")[pc]);
                }
            }
        }
        for (n, c) in extra {
            node[n][c] = Dof::Free(next);
            next += 1;
        }
        Ok(DofMap {
            node,
            n_interior,
            n_retained: next - n_interior,
            prescribed,
            pilot: pilot_dofs,
        })
    }

    /// Number of unknowns.
    pub fn n_free(&self) -> usize {
        self.n_interior + self.n_retained
    }

    /// The 12 DOFs of a 6-node element, in element order.
    pub fn element_dofs(&self, nodes: &[usize; 6]) -> [Dof; 12] {
        std::array::from_fn(|i| self.node[nodes[i / 2]][i % 2])
    }

    /// The element vector `(ux, uy)` of each of a 6-node triangle's `nodes` from the free
    /// solution `u`.
    pub fn element_displacement(&self, nodes: &[usize; 6], u: &[f64]) -> [f64; 12] {
        let d = nodes.map(|n| self.displacement(n, u));
        std::array::from_fn(|i| d[i / 2][i % 2])
    }

    /// Nodal displacement (ux, uy) from the free solution `u`.
    pub fn displacement(&self, n: usize, u: &[f64]) -> [f64; 2] {
        self.node[n].map(|d| match d {
            Dof::Free(i) => u[i],
            Dof::Fixed(k) => self.prescribed[k],
            Dof::Unused => 0.0,
        })
    }
}
