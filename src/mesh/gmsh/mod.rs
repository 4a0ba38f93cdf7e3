//! Reading gmsh MSH 4.1 files (ASCII or binary) through `mshio`, plus the `$PhysicalNames`
//! section, which `mshio` skips; the nodes and elements of a well-formed binary file are read
//! directly (`binary`).
//!
//! Only 6-node triangles (type 9) and 3-node lines (type 8) are kept as elements; points
//! (type 15) are ignored; any other type in a physical group is an error naming the element.
//!
//! | module | content |
//! |---|---|
//! | this file | [`read`], [`parse`]: the file's parts put together, its physical groups, triangles made counter-clockwise |
//! | `text` | the header, `$PhysicalNames`, node tags in file order |
//! | `blocks` | nodes and element blocks through `mshio`; the element blocks of either reader added to a mesh |
//! | `binary` | the direct reader of a well-formed binary file's nodes and elements |
//! | `error` | [`MeshReadError`] |

mod binary;
mod blocks;
mod error;
mod text;

pub use error::MeshReadError;

use super::{Group, GroupDim, Mesh};
use crate::shapes::tri6;
use blocks::{Read, TagIndex, entity_physical_tags, push_elements, through_mshio};
use std::collections::HashMap;
use std::path::Path;
use text::{check_header, physical_names};

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
/// (`binary`), the rest of it (and any other file) through `mshio`.
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
/// (header, entities), [`binary`] for the nodes and elements. `None` when the file
/// is not one it reads (see there), and the whole file then goes through `mshio`.
fn direct(bytes: &[u8], p: &str) -> Option<Read> {
    let size_t = binary_little_endian(bytes)?;
    let start = binary::nodes_start(bytes)?;
    let body = binary::read(&bytes[start..], size_t)?;
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
