//! The nodes and element blocks of a mesh file: read through `mshio` ([`through_mshio`]), and
//! the element blocks of either reader added to a mesh ([`push_elements`]), each block's
//! elements kept with its entity for the physical groups.

use super::error::MeshReadError;
use super::text::{node_tags_in_file_order, short_parse_error};
use crate::mesh::{Lin3, Mesh, Tri6};
use std::collections::HashMap;

/// A mesh as read, before its physical groups: the elements of each block (by the block's
/// entity, `(dim, tag)`) and each entity's physical tags.
#[derive(Default)]
pub(super) struct Read {
    pub mesh: Mesh,
    pub blocks: Vec<((i32, i32), Vec<usize>)>,
    pub entity_phys: HashMap<(i32, i32), Vec<i32>>,
}

/// The whole file through `mshio`.
pub(super) fn through_mshio(bytes: &[u8], p: &str) -> Result<Read, MeshReadError> {
    let msh = mshio::parse_msh_bytes(bytes).map_err(|e| MeshReadError::Parse {
        path: p.into(),
        detail: short_parse_error(&format!("{e}")),
    })?;

    let NodeTable {
        nodes,
        node_tags,
        index_of,
    } = read_nodes(bytes, &msh, p)?;
    let mut read = Read {
        mesh: Mesh {
            nodes,
            node_tags,
            ..Default::default()
        },
        entity_phys: entity_physical_tags(&msh),
        ..Default::default()
    };
    let elements = msh.data.elements.as_ref().ok_or(MeshReadError::Empty {
        path: p.into(),
        what: "$Elements section",
    })?;
    for block in &elements.element_blocks {
        let kind = block.element_type as u8;
        let dim = block.entity_dim;
        if kind == 15 || dim == 0 {
            continue; // points carry no stiffness or load
        }
        check_block_type(block, p)?;
        let elements = block
            .elements
            .iter()
            .map(|e| (e.element_tag, e.nodes.as_slice()));
        let local = push_elements(&mut read.mesh, kind, elements, &index_of, p)?;
        read.blocks.push(((dim, block.entity_tag), local));
    }
    Ok(read)
}

/// The nodes of the `$Nodes` section in file order, their gmsh tags, and tag → index.
struct NodeTable {
    nodes: Vec<[f64; 2]>,
    node_tags: Vec<u64>,
    index_of: TagIndex,
}

/// Node tag → node index: a table when the tags are dense (gmsh numbers nodes 1..N), else a
/// hash map.
pub(super) enum TagIndex {
    Dense(Vec<usize>),
    Sparse(HashMap<u64, usize>),
}

impl TagIndex {
    pub(super) fn new(tags: &[u64]) -> TagIndex {
        let max = tags.iter().copied().max().unwrap_or(0);
        if max <= 2 * tags.len() as u64 + 1024 {
            let mut v = vec![usize::MAX; max as usize + 1];
            for (i, &t) in tags.iter().enumerate() {
                v[t as usize] = i;
            }
            TagIndex::Dense(v)
        } else {
            TagIndex::Sparse(tags.iter().enumerate().map(|(i, &t)| (t, i)).collect())
        }
    }

    fn get(&self, tag: u64) -> Option<usize> {
        match self {
            TagIndex::Dense(v) => v.get(tag as usize).copied().filter(|&i| i != usize::MAX),
            TagIndex::Sparse(m) => m.get(&tag).copied(),
        }
    }
}

/// Reads the `$Nodes` section (x, y and tag of every node); an empty section is an error.
fn read_nodes(
    bytes: &[u8],
    msh: &mshio::MshFile<u64, i32, f64>,
    p: &str,
) -> Result<NodeTable, MeshReadError> {
    let node_sec = msh.data.nodes.as_ref().ok_or(MeshReadError::Empty {
        path: p.into(),
        what: "$Nodes section",
    })?;
    let file_tags =
        node_tags_in_file_order(bytes, msh.header.file_type != 0, msh.header.size_t_size)
            .ok_or_else(|| MeshReadError::Parse {
                path: p.into(),
                detail: "cannot read the node tags of the $Nodes section".into(),
            })?;
    let mut nodes = Vec::new();
    let mut node_tags = Vec::new();
    for block in &node_sec.node_blocks {
        // mshio keeps the tags only when the whole section's tags are sparse; otherwise they
        // come from our own pass over the section (`file_tags`), in file order.
        let tags: Vec<u64> = match &block.node_tags {
            Some(map) => {
                let mut v = vec![0u64; block.nodes.len()];
                for (&tag, &i) in map {
                    v[i] = tag;
                }
                v
            }
            None => {
                let start = nodes.len();
                file_tags
                    .get(start..start + block.nodes.len())
                    .ok_or_else(|| MeshReadError::Parse {
                        path: p.into(),
                        detail: "node tags of the $Nodes section do not match its blocks".into(),
                    })?
                    .to_vec()
            }
        };
        for (node, tag) in block.nodes.iter().zip(tags) {
            nodes.push([node.x, node.y]);
            node_tags.push(tag);
        }
    }
    if nodes.is_empty() {
        return Err(MeshReadError::Empty {
            path: p.into(),
            what: "nodes",
        });
    }
    Ok(NodeTable {
        index_of: TagIndex::new(&node_tags),
        nodes,
        node_tags,
    })
}

/// Entity → physical tags, for curves `(1, tag)` and surfaces `(2, tag)`.
pub(super) fn entity_physical_tags(
    msh: &mshio::MshFile<u64, i32, f64>,
) -> HashMap<(i32, i32), Vec<i32>> {
    let mut entity_phys: HashMap<(i32, i32), Vec<i32>> = HashMap::new();
    if let Some(ent) = &msh.data.entities {
        for c in &ent.curves {
            entity_phys.insert((1, c.tag), c.physical_tags.clone());
        }
        for s in &ent.surfaces {
            entity_phys.insert((2, s.tag), s.physical_tags.clone());
        }
    }
    entity_phys
}

/// Refuses an element block that is not of 6-node triangles or 3-node lines, or whose type
/// does not match the dimension of its entity.
pub(super) fn check_block_type(
    block: &mshio::ElementBlock<u64, i32>,
    p: &str,
) -> Result<(), MeshReadError> {
    let kind = block.element_type as u8;
    let dim = block.entity_dim;
    if kind != 9 && kind != 8 {
        let tag = block.elements.first().map_or(0, |e| e.element_tag);
        let hint = match kind {
            2 | 1 => {
                "; this is a first-order mesh: set `Mesh.ElementOrder = 2;` (and \
                 `Mesh.SecondOrderLinear = 0;` for curved edges) and mesh again"
            }
            _ => "",
        };
        return Err(MeshReadError::UnsupportedElement {
            path: p.into(),
            tag,
            kind,
            name: format!("{:?}", block.element_type),
            hint,
        });
    }
    // A group's element indices point into `triangles` or `lines` by its dimension, so the
    // block's element type must match the dimension of its entity.
    if dim != if kind == 9 { 2 } else { 1 } {
        return Err(MeshReadError::Parse {
            path: p.into(),
            detail: format!(
                "element block of gmsh type {kind} (first element {}) is on an entity of \
                 dimension {dim}; 6-node triangles belong to surfaces (2), 3-node lines to \
                 curves (1)",
                block.elements.first().map_or(0, |e| e.element_tag)
            ),
        });
    }
    Ok(())
}

/// Appends the elements `(tag, node tags)` of a (checked) block of gmsh type `kind` (9 or 8)
/// to `mesh.triangles` or `mesh.lines`, resolving node tags to indices; returns their indices
/// in that list.
pub(super) fn push_elements<'e>(
    mesh: &mut Mesh,
    kind: u8,
    elements: impl Iterator<Item = (u64, &'e [u64])>,
    index_of: &TagIndex,
    p: &str,
) -> Result<Vec<usize>, MeshReadError> {
    let mut local = Vec::with_capacity(elements.size_hint().0);
    for (tag, nodes) in elements {
        let idx = |t: u64| {
            index_of.get(t).ok_or_else(|| MeshReadError::MissingNode {
                path: p.into(),
                tag,
                node: t,
            })
        };
        // The element's nodes as mesh indices, checking the count.
        let resolve = |want: usize| -> Result<[usize; 6], MeshReadError> {
            if nodes.len() != want {
                return Err(MeshReadError::Parse {
                    path: p.into(),
                    detail: format!("element {tag} has {} nodes, {want} expected", nodes.len()),
                });
            }
            let mut n = [0usize; 6];
            for (k, &t) in nodes.iter().enumerate() {
                n[k] = idx(t)?;
            }
            Ok(n)
        };
        if kind == 9 {
            let n = resolve(6)?;
            local.push(mesh.triangles.len());
            mesh.triangles.push(Tri6 {
                nodes: std::array::from_fn(|k| n[k]),
                tag,
            });
        } else {
            let n = resolve(3)?;
            local.push(mesh.lines.len());
            mesh.lines.push(Lin3 {
                nodes: std::array::from_fn(|k| n[k]),
                tag,
            });
        }
    }
    Ok(local)
}
