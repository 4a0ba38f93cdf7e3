//! `.vtu` (VTK XML unstructured grid) datasets through `vtkio`.

use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataArray, DataSet, ElementType, IOBuffer,
    UnstructuredGridPiece, Version, VertexNumbers, Vtk,
};

/// A field on points or cells: name, number of components, values (component-fastest).
pub struct Field {
    pub name: String,
    pub ncomp: u32,
    pub values: Vec<f64>,
}

impl Field {
    pub fn scalar(name: &str, values: Vec<f64>) -> Field {
        Field {
            name: name.into(),
            ncomp: 1,
            values,
        }
    }
    pub fn vector(name: &str, values: Vec<f64>) -> Field {
        Field {
            name: name.into(),
            ncomp: 3,
            values,
        }
    }
}

/// Cell kind of a dataset.
#[derive(Clone, Copy)]
pub enum Kind {
    /// 6-node triangles.
    Tri6,
    /// 3-node lines.
    Line3,
}

/// Serialises an unstructured grid of quadratic cells (points in 2-D, z = 0).
pub fn unstructured(
    title: &str,
    points: &[[f64; 2]],
    cells: &[Vec<usize>],
    kind: Kind,
    point_data: Vec<Field>,
    cell_data: Vec<Field>,
) -> Result<Vec<u8>, vtkio::Error> {
    let pts: Vec<f64> = points.iter().flat_map(|p| [p[0], p[1], 0.0]).collect();
    let mut connectivity = Vec::new();
    let mut offsets = Vec::new();
    for c in cells {
        connectivity.extend(c.iter().map(|&i| i as u64));
        offsets.push(connectivity.len() as u64);
    }
    let ct = match kind {
        Kind::Tri6 => CellType::QuadraticTriangle,
        Kind::Line3 => CellType::QuadraticEdge,
    };
    let arr = |f: Field| {
        Attribute::DataArray(DataArray {
            name: f.name,
            elem: if f.ncomp == 3 {
                ElementType::Vectors
            } else {
                ElementType::Scalars {
                    num_comp: f.ncomp,
                    lookup_table: None,
                }
            },
            data: IOBuffer::F64(f.values),
        })
    };
    let vtk = Vtk {
        version: Version { major: 1, minor: 0 },
        title: title.into(),
        byte_order: ByteOrder::LittleEndian,
        file_path: None,
        data: DataSet::inline(UnstructuredGridPiece {
            points: IOBuffer::F64(pts),
            cells: Cells {
                cell_verts: VertexNumbers::XML {
                    connectivity,
                    offsets,
                },
                types: vec![ct; cells.len()],
            },
            data: Attributes {
                point: point_data.into_iter().map(arr).collect(),
                cell: cell_data.into_iter().map(arr).collect(),
            },
        }),
    };
    let mut buf = Vec::new();
    vtk.write_xml(&mut buf)?;
    Ok(buf)
}
