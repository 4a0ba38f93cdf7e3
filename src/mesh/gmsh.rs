//! Reading gmsh MSH 4.1 files (ASCII or binary) through `mshio`, plus the `$PhysicalNames`
//! section, which `mshio` skips; the nodes and elements of a well-formed binary file are read
//! directly ([`super::msh_binary`]).
//!
//! Only 6-node triangles (type 9) and 3-node lines (type 8) are kept as elements; points
//! (type 15) are ignored; any other type in a physical group is an error naming the element.

use super::{Group, GroupDim, Lin3, Mesh, Tri6};
use crate::shapes::tri6;
use std::collections::HashMap;
use std::path::Path;

/// What can go wrong reading a mesh file.
#[derive(Debug, thiserror::Error)]
pub enum MeshReadError {
    #[error("{path}: cannot read the file: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error(
        "{path}: MSH format {version} is not supported; re-export it as MSH 4.1, e.g. \
         `gmsh {path} -save -format msh41 -o new.msh`, or set `Mesh.MshFileVersion = 4.1;` in the .geo"
    )]
    OldFormat { path: String, version: String },
    #[error("{path}: not a gmsh mesh file (no $MeshFormat header)")]
    NotMsh { path: String },
    #[error("{path}: cannot parse the mesh: {detail}")]
    Parse { path: String, detail: String },
    #[error("{path}: malformed $PhysicalNames section at line {line}: {detail}")]
    PhysicalNames {
        path: String,
        line: usize,
        detail: String,
    },
    #[error(
        "{path}: element {tag} has gmsh type {kind} ({name}); only 6-node triangles (type 9) and \
         3-node lines (type 8) are supported{hint}"
    )]
    UnsupportedElement {
        path: String,
        tag: u64,
        kind: u8,
        name: String,
        hint: &'static str,
    },
    #[error("{path}: element {tag} refers to node {node}, which is not in the $Nodes section")]
    MissingNode { path: String, tag: u64, node: u64 },
    #[error("{path}: the file has no {what}")]
    Empty { path: String, what: &'static str },
}

/// Reads and parses a mesh file. The result is not yet checked: call [`super::check::check`].
pub fn read(path: &Path) -> Result<Mesh, MeshReadError> {
    let p = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| MeshReadError::Io {
        path: p.clone(),
        source,
    })?;
    parse(&bytes, path)
}

/// Parses the bytes of a mesh file; `path` is used for messages only.
///
/// The nodes and elements of a well-formed binary file are read directly
/// ([`super::msh_binary`]), the rest of it (and any other file) through `mshio`.
pub fn parse(bytes: &[u8], path: &Path) -> Result<Mesh, MeshReadError> {
    parse_with(bytes, path, true)
}

/// [`parse`], reading the nodes and elements directly when `direct` allows it.
fn parse_with(bytes: &[u8], path: &Path, allow_direct: bool) -> Result<Mesh, MeshReadError> {
    let p = path.display().to_string();
    check_header(bytes, &p)?;
    let names = physical_names(bytes, &p)?;
    let read = match allow_direct.then(|| direct(bytes, &p)).flatten() {
        Some(read) => read,
        None => through_mshio(bytes, &p)?,
    };
    let mut mesh = with_groups(read, &names);
    mesh.source = path.to_path_buf();
    reorient_clockwise(&mut mesh);
    Ok(mesh)
}

/// A mesh as read, before its physical groups: the elements of each block (by the block's
/// entity, `(dim, tag)`) and each entity's physical tags.
#[derive(Default)]
struct Read {
    mesh: Mesh,
    blocks: Vec<((i32, i32), Vec<usize>)>,
    entity_phys: HashMap<(i32, i32), Vec<i32>>,
}

/// The mesh of `read` with its physical groups, in file order: each block's elements added to
/// the groups of its entity's physical tags (named by `$PhysicalNames`, else `surface_N` /
/// `curve_N`), then the named groups that have no elements at all (declared but empty), so
/// that a check can report them as empty rather than as missing.
fn with_groups(read: Read, names: &HashMap<(i32, i32), String>) -> Mesh {
    let Read {
        mut mesh,
        blocks,
        entity_phys,
    } = read;
    let group = |name: String, dim: i32, tag: i32| Group {
        name,
        dim: if dim == 2 {
            GroupDim::Surface
        } else {
            GroupDim::Curve
        },
        tag,
        elements: Vec::new(),
    };
    // Group of each (dim, physical tag).
    let mut index: HashMap<(i32, i32), usize> = HashMap::new();
    for ((dim, entity), local) in blocks {
        for ph in entity_phys.get(&(dim, entity)).into_iter().flatten() {
            let key = (dim, ph.abs());
            let gi = *index.entry(key).or_insert_with(|| {
                let name = names.get(&key).cloned().unwrap_or_else(|| {
                    let kind = if dim == 2 { "surface_" } else { "curve_" };
                    format!("{kind}{}", ph.abs())
                });
                mesh.groups.push(group(name, dim, ph.abs()));
                mesh.groups.len() - 1
            });
            mesh.groups[gi].elements.extend_from_slice(&local);
        }
    }
    for (&(dim, tag), name) in names {
        if (dim == 1 || dim == 2) && !index.contains_key(&(dim, tag)) {
            mesh.groups.push(group(name.clone(), dim, tag));
        }
    }
    mesh
}

/// The binary file `bytes` read directly: `mshio` for what comes before the `$Nodes` section
/// (header, entities), [`super::msh_binary`] for the nodes and elements. `None` when the file
/// is not one it reads (see there), and the whole file then goes through `mshio`.
fn direct(bytes: &[u8], p: &str) -> Option<Read> {
    let size_t = binary_little_endian(bytes)?;
    let start = super::msh_binary::nodes_start(bytes)?;
    let body = super::msh_binary::read(&bytes[start..], size_t)?;
    let head = mshio::parse_msh_bytes(&bytes[..start]).ok()?;
    if head.data.nodes.is_some() || head.data.elements.is_some() {
        return None;
    }
    let index_of = TagIndex::new(&body.node_tags);
    let mut read = Read {
        mesh: Mesh {
            nodes: body.nodes,
            node_tags: body.node_tags,
            ..Default::default()
        },
        entity_phys: entity_physical_tags(&head),
        ..Default::default()
    };
    for b in &body.blocks {
        // A node the file does not have: `mshio`'s path reports it.
        let local = push_elements(&mut read.mesh, b.kind, b.elements(), &index_of, p).ok()?;
        read.blocks.push(((b.dim, b.entity_tag), local));
    }
    Some(read)
}

/// The data size of a binary little-endian MSH 4.1 file (`$MeshFormat`, `4.1 1 <size>`, then
/// the integer 1 in the file's byte order); `None` for any other file.
fn binary_little_endian(bytes: &[u8]) -> Option<usize> {
    let first = bytes.iter().position(|&b| b == b'\n')? + 1;
    let second = first + bytes[first..].iter().position(|&b| b == b'\n')? + 1;
    if bytes[..first].trim_ascii() != b"$MeshFormat" {
        return None;
    }
    let line = std::str::from_utf8(&bytes[first..second]).ok()?;
    let mut it = line.split_ascii_whitespace();
    let (version, kind, size) = (it.next()?, it.next()?, it.next()?);
    if version != "4.1" || kind != "1" || it.next().is_some() {
        return None;
    }
    let size: usize = size.parse().ok()?;
    (bytes.get(second..second + 4)? == 1i32.to_le_bytes()).then_some(size)
}

/// The whole file through `mshio`.
fn through_mshio(bytes: &[u8], p: &str) -> Result<Read, MeshReadError> {
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

/// Refuses anything but MSH 4.1 with a data size of 4 or 8.
fn check_header(bytes: &[u8], p: &str) -> Result<(), MeshReadError> {
    let version = header_version(bytes).ok_or_else(|| MeshReadError::NotMsh { path: p.into() })?;
    if !version.starts_with('4') {
        return Err(MeshReadError::OldFormat {
            path: p.into(),
            version,
        });
    }
    if version != "4.1" {
        return Err(MeshReadError::OldFormat {
            path: p.into(),
            version,
        });
    }
    // mshio panics on a data size other than 1, 2, 4, 8, 16 or one that overflows; gmsh writes
    // sizeof(size_t), and the node-tag pass below reads 4 or 8.
    if let Some(size) = header_data_size(bytes)
        && !matches!(size.parse::<u64>(), Ok(4 | 8))
    {
        return Err(MeshReadError::Parse {
            path: p.into(),
            detail: format!(
                "the $MeshFormat data size is `{size}`; it must be 4 or 8 (sizeof(size_t))"
            ),
        });
    }
    Ok(())
}

/// The nodes of the `$Nodes` section in file order, their gmsh tags, and tag → index.
struct NodeTable {
    nodes: Vec<[f64; 2]>,
    node_tags: Vec<u64>,
    index_of: TagIndex,
}

/// Node tag → node index: a table when the tags are dense (gmsh numbers nodes 1..N), else a
/// hash map.
enum TagIndex {
    Dense(Vec<usize>),
    Sparse(HashMap<u64, usize>),
}

impl TagIndex {
    fn new(tags: &[u64]) -> TagIndex {
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
fn entity_physical_tags(msh: &mshio::MshFile<u64, i32, f64>) -> HashMap<(i32, i32), Vec<i32>> {
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
fn check_block_type(block: &mshio::ElementBlock<u64, i32>, p: &str) -> Result<(), MeshReadError> {
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
fn push_elements<'e>(
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

/// Clockwise triangles are reoriented so that every element is counter-clockwise; their tags
/// are recorded in `mesh.reoriented`.
fn reorient_clockwise(mesh: &mut Mesh) {
    for i in 0..mesh.triangles.len() {
        let xe = mesh.tri_coords(i);
        if tri6::vertex_area(&xe) < 0.0 {
            let t = &mut mesh.triangles[i];
            t.nodes = tri6::REVERSE.map(|k| t.nodes[k]);
            mesh.reoriented.push(t.tag);
        }
    }
}

/// The version string of the `$MeshFormat` header, e.g. "4.1" or "2.2".
fn header_version(bytes: &[u8]) -> Option<String> {
    let head = &bytes[..bytes.len().min(256)];
    let text = String::from_utf8_lossy(head);
    let mut lines = text.lines().map(str::trim);
    lines.find(|l| *l == "$MeshFormat")?;
    let v = lines.next()?.split_whitespace().next()?.to_string();
    Some(v)
}

/// The data-size field of the `$MeshFormat` line (`4.1 <file-type> <data-size>`), when it is
/// written as digits.
fn header_data_size(bytes: &[u8]) -> Option<String> {
    let head = &bytes[..bytes.len().min(256)];
    let text = String::from_utf8_lossy(head);
    let mut lines = text.lines().map(str::trim);
    lines.find(|l| *l == "$MeshFormat")?;
    let size = lines.next()?.split_whitespace().nth(2)?;
    size.bytes()
        .all(|b| b.is_ascii_digit())
        .then(|| size.to_string())
}

/// Parses the `$PhysicalNames` section (always ASCII, also in binary files):
/// `(dim, tag) → name`.
fn physical_names(bytes: &[u8], path: &str) -> Result<HashMap<(i32, i32), String>, MeshReadError> {
    let mut out = HashMap::new();
    let Some(start) = find(bytes, b"$PhysicalNames") else {
        return Ok(out);
    };
    let rest = &bytes[start..];
    let end = find(rest, b"$EndPhysicalNames").ok_or_else(|| MeshReadError::PhysicalNames {
        path: path.into(),
        line: 0,
        detail: "no $EndPhysicalNames".into(),
    })?;
    let text = String::from_utf8_lossy(&rest[..end]);
    let line0 = bytes[..start].iter().filter(|&&b| b == b'\n').count() + 1;
    let mut lines = text.lines().enumerate().skip(1);
    let bad = |line: usize, detail: String| MeshReadError::PhysicalNames {
        path: path.into(),
        line: line0 + line,
        detail,
    };
    let (ln, count) = lines.next().ok_or_else(|| bad(1, "missing count".into()))?;
    let count: usize = count
        .trim()
        .parse()
        .map_err(|_| bad(ln, format!("`{}` is not a count", count.trim())))?;
    for _ in 0..count {
        let (ln, l) = lines
            .next()
            .ok_or_else(|| bad(ln, "fewer names than the count says".into()))?;
        let mut it = l.trim().splitn(3, char::is_whitespace);
        let dim: i32 = it
            .next()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| bad(ln, format!("`{l}`: expected `dim tag \"name\"`")))?;
        let tag: i32 = it
            .next()
            .and_then(|s| s.trim().parse().ok())
            .ok_or_else(|| bad(ln, format!("`{l}`: expected `dim tag \"name\"`")))?;
        let name = it.next().unwrap_or("").trim().trim_matches('"').to_string();
        if name.is_empty() {
            return Err(bad(ln, format!("`{l}`: empty name")));
        }
        out.insert((dim, tag), name);
    }
    Ok(out)
}

/// All node tags of the `$Nodes` section in file order (MSH 4.1, ASCII or binary).
///
/// mshio drops node tags when they form a dense range, without saying how they map to
/// nodes; this reads them, so that element connectivity is resolved by tag, never by guess.
fn node_tags_in_file_order(bytes: &[u8], binary: bool, size_t: usize) -> Option<Vec<u64>> {
    let start = find(bytes, b"$Nodes")? + b"$Nodes".len();
    let mut pos = start + bytes[start..].iter().position(|&b| b == b'\n')? + 1;
    let mut tags = Vec::new();
    if binary {
        let rd = |pos: &mut usize, n: usize| -> Option<u64> {
            let s = bytes.get(*pos..*pos + n)?;
            *pos += n;
            Some(match n {
                4 => u32::from_le_bytes(s.try_into().ok()?) as u64,
                8 => u64::from_le_bytes(s.try_into().ok()?),
                _ => return None,
            })
        };
        let nblocks = rd(&mut pos, size_t)?;
        let _nnodes = rd(&mut pos, size_t)?;
        let _min = rd(&mut pos, size_t)?;
        let _max = rd(&mut pos, size_t)?;
        for _ in 0..nblocks {
            let _dim = rd(&mut pos, 4)?;
            let _tag = rd(&mut pos, 4)?;
            let parametric = rd(&mut pos, 4)?;
            let n = rd(&mut pos, size_t)? as usize;
            if parametric != 0 {
                return None;
            }
            for _ in 0..n {
                tags.push(rd(&mut pos, size_t)?);
            }
            pos = pos.checked_add(n.checked_mul(24)?)?;
        }
    } else {
        let end = pos + find(&bytes[pos..], b"$EndNodes")?;
        let text = std::str::from_utf8(&bytes[pos..end]).ok()?;
        let mut it = text.split_ascii_whitespace();
        let mut next = || it.next()?.parse::<f64>().ok();
        let nblocks = next()? as usize;
        next()?;
        next()?;
        next()?;
        for _ in 0..nblocks {
            next()?;
            next()?;
            let parametric = next()?;
            let n = next()? as usize;
            if parametric != 0.0 {
                return None;
            }
            for _ in 0..n {
                tags.push(next()? as u64);
            }
            for _ in 0..3 * n {
                next()?;
            }
        }
    }
    Some(tags)
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// mshio's errors print the whole remaining input; keep the first lines only.
fn short_parse_error(s: &str) -> String {
    let mut out: String = s.lines().take(4).collect::<Vec<_>>().join(" | ");
    if out.len() > 400 {
        out.truncate(400);
        out.push('…');
    }
    if out.is_empty() {
        "malformed or truncated file".into()
    } else {
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every mesh file in `meshes/` (the generated L6 and L7 too when they are there).
    fn mesh_files() -> Vec<std::path::PathBuf> {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes");
        let mut v: Vec<_> = std::fs::read_dir(dir)
            .expect("meshes/")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == "msh"))
            .collect();
        v.sort();
        v
    }

    #[test]
    fn both_readers_give_the_same_mesh() {
        let mut direct_files = 0;
        for path in mesh_files() {
            let bytes = std::fs::read(&path).expect("read");
            let p = path.display().to_string();
            let binary = binary_little_endian(&bytes).is_some();
            assert_eq!(
                direct(&bytes, &p).is_some(),
                binary,
                "{p}: the direct reader takes exactly the binary files"
            );
            direct_files += binary as usize;
            let a = parse_with(&bytes, &path, true).map(|m| format!("{m:?}"));
            let b = parse_with(&bytes, &path, false).map(|m| format!("{m:?}"));
            match (a, b) {
                (Ok(a), Ok(b)) => assert!(a == b, "{p}: the two readers differ"),
                (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string(), "{p}"),
                (a, b) => panic!("{p}: {:?} against {:?}", a.err(), b.err()),
            }
        }
        // L0-L5, block_hertz, pad_flat, pad_flat_lead.
        assert!(direct_files >= 9, "{direct_files} binary meshes");
    }

    /// Node tags that are not 1..N (gmsh writes them after a renumbering; `mshio` then keeps
    /// them itself): the file's tags rewritten to 7t + 100 in both sections, read both ways.
    #[test]
    fn sparse_node_tags_read_alike() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/vm272_L0.msh");
        let mut b = std::fs::read(&path).expect("read");
        let at = |b: &[u8], w: &[u8]| b.windows(w.len()).position(|x| x == w).expect("section");
        let word = |b: &[u8], k: usize| u64::from_le_bytes(b[k..k + 8].try_into().unwrap());
        let map = |t: u64| 7 * t + 100;
        let rewrite = |b: &mut Vec<u8>, k: usize| {
            let t = map(word(b, k));
            b[k..k + 8].copy_from_slice(&t.to_le_bytes());
        };
        // $Nodes: blocks, total, min, max; per block dim, entity, parametric, count, tags, xyz.
        let mut k = at(&b, b"$Nodes\n") + "$Nodes\n".len();
        let blocks = word(&b, k);
        for j in [16, 24] {
            rewrite(&mut b, k + j);
        }
        k += 32;
        for _ in 0..blocks {
            let n = word(&b, k + 12) as usize;
            k += 20;
            for i in 0..n {
                rewrite(&mut b, k + 8 * i);
            }
            k += 32 * n;
        }
        // $Elements: per block dim, entity, type, count, then tag and node tags per element.
        let mut k = at(&b, b"$Elements\n") + "$Elements\n".len();
        let blocks = word(&b, k);
        k += 32;
        for _ in 0..blocks {
            let kind = i32::from_le_bytes(b[k + 8..k + 12].try_into().unwrap());
            let n = word(&b, k + 12) as usize;
            let per = match kind {
                15 => 1,
                8 => 3,
                9 => 6,
                _ => panic!("type {kind}"),
            };
            k += 20;
            for e in 0..n {
                for v in 0..per {
                    rewrite(&mut b, k + 8 * (e * (per + 1) + 1 + v));
                }
            }
            k += 8 * n * (per + 1);
        }
        assert!(direct(&b, "x").is_some(), "the direct reader takes it");
        let a = parse_with(&b, &path, true).expect("direct");
        let m = parse_with(&b, &path, false).expect("mshio");
        assert_eq!(format!("{a:?}"), format!("{m:?}"));
        assert_eq!(a.node_tags.iter().min(), Some(&map(1)));
        // The same mesh as the file with its own tags, but for the tags.
        let plain = parse_with(&std::fs::read(&path).unwrap(), &path, true).unwrap();
        assert_eq!(plain.nodes, a.nodes);
        assert_eq!(
            plain.triangles.iter().map(|t| t.nodes).collect::<Vec<_>>(),
            a.triangles.iter().map(|t| t.nodes).collect::<Vec<_>>()
        );
    }

    /// A binary file cut short, or whose element names a node it does not have, is left to
    /// `mshio`'s path, and reported as before.
    #[test]
    fn damaged_binary_files_get_mshio_errors() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/vm272_L0.msh");
        let bytes = std::fs::read(&path).expect("read");
        let at = |w: &[u8]| {
            bytes
                .windows(w.len())
                .position(|x| x == w)
                .expect("section")
        };
        let elements = at(b"$Elements");
        let mut cases = vec![
            bytes[..elements + 200].to_vec(),
            bytes[..at(b"$EndNodes") - 8].to_vec(),
            [&bytes[..], b"$Junk\n"].concat(),
        ];
        // The first element's first node tag made one no node has.
        let mut missing = bytes.clone();
        let first = elements + "$Elements\n".len() + 32;
        let mut k = first;
        loop {
            // Block header: dim, entity, type (3 × 4 bytes), count (8 bytes).
            let kind = i32::from_le_bytes(missing[k + 8..k + 12].try_into().unwrap());
            let n = u64::from_le_bytes(missing[k + 12..k + 20].try_into().unwrap()) as usize;
            let per = match kind {
                15 => 1,
                8 => 3,
                9 => 6,
                _ => panic!("type {kind}"),
            };
            if kind == 9 {
                missing[k + 28..k + 36].copy_from_slice(&(1u64 << 40).to_le_bytes());
                break;
            }
            k += 20 + n * 8 * (per + 1);
        }
        cases.push(missing);
        for (i, b) in cases.iter().enumerate() {
            assert!(direct(b, "x").is_none(), "case {i}");
            let a = parse_with(b, &path, true)
                .map(|_| ())
                .expect_err("an error");
            let m = parse_with(b, &path, false)
                .map(|_| ())
                .expect_err("an error");
            assert_eq!(a.to_string(), m.to_string(), "case {i}");
        }
    }
}
