//! What can go wrong reading a mesh file.

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
