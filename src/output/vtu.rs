//! `.vtu` (VTK XML unstructured grid) datasets, written directly: an XML header whose data
//! arrays all have `format="appended"`, then one `<AppendedData encoding="raw">` section with
//! the arrays' little-endian bytes, each preceded by its byte count (`header_type="UInt64"`).
//! With compression (`compressor="vtkZLibDataCompressor"`), each array is one zlib block
//! preceded by the header `[1, n, n, compressed n]` of VTK's block format.
//!
//! The arrays: `Float64` points (z = 0) and fields, `UInt64` connectivity and offsets,
//! `UInt8` cell types (22 quadratic triangle, 21 quadratic edge).

use std::borrow::Cow;
use std::fmt::Write as _;

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

impl Kind {
    /// The VTK cell type code.
    fn code(self) -> u8 {
        match self {
            Kind::Tri6 => 22,
            Kind::Line3 => 21,
        }
    }
}

/// The values of one data array.
enum Values<'a> {
    F64(&'a [f64]),
    U64(&'a [u64]),
    U8(&'a [u8]),
    /// The shape of a `Float64` array of this many values whose bytes are not given (for the
    /// layout of what follows it, [`raw_after_point_data`]).
    Shape(usize),
}

impl<'a> Values<'a> {
    fn vtk_type(&self) -> &'static str {
        match self {
            Values::F64(_) | Values::Shape(_) => "Float64",
            Values::U64(_) => "UInt64",
            Values::U8(_) => "UInt8",
        }
    }

    fn byte_len(&self) -> usize {
        match self {
            Values::F64(v) => 8 * v.len(),
            Values::U64(v) => 8 * v.len(),
            Values::U8(v) => v.len(),
            Values::Shape(n) => 8 * n,
        }
    }

    /// The values' little-endian bytes: the values' own memory on a little-endian machine
    /// (none for a [`Values::Shape`]).
    fn le_bytes(&self) -> Cow<'a, [u8]> {
        #[cfg(target_endian = "little")]
        {
            match *self {
                Values::F64(v) => Cow::Borrowed(bytemuck::cast_slice(v)),
                Values::U64(v) => Cow::Borrowed(bytemuck::cast_slice(v)),
                Values::U8(v) => Cow::Borrowed(v),
                Values::Shape(_) => Cow::Borrowed(&[]),
            }
        }
        #[cfg(not(target_endian = "little"))]
        {
            match *self {
                Values::F64(v) => Cow::Owned(v.iter().flat_map(|x| x.to_le_bytes()).collect()),
                Values::U64(v) => Cow::Owned(v.iter().flat_map(|x| x.to_le_bytes()).collect()),
                Values::U8(v) => Cow::Borrowed(v),
                Values::Shape(_) => Cow::Borrowed(&[]),
            }
        }
    }
}

/// One data array of the XML header.
struct Array<'a> {
    name: Option<&'a str>,
    ncomp: u32,
    values: Values<'a>,
}

/// zlib level of compressed output: the fastest, as a run writes many files.
const ZLIB_LEVEL: u8 = 1;

/// Escapes the characters XML does not allow in an attribute value.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The bytes of one compressed array in the appended section: the one-block header
/// `[1, n, n, compressed n]` (no blocks for no bytes) and the zlib stream.
fn zlib_block(values: &Values) -> Vec<u8> {
    assert!(
        !matches!(values, Values::Shape(_)),
        "an array without values is not compressed"
    );
    let n = values.byte_len();
    if n == 0 {
        // No blocks.
        return [0u64, 0, 0].iter().flat_map(|h| h.to_le_bytes()).collect();
    }
    let z = miniz_oxide::deflate::compress_to_vec_zlib(&values.le_bytes(), ZLIB_LEVEL);
    let mut out = Vec::with_capacity(32 + z.len());
    for h in [1, n as u64, n as u64, z.len() as u64] {
        out.extend_from_slice(&h.to_le_bytes());
    }
    out.extend_from_slice(&z);
    out
}

/// The points and cells of an unstructured grid of quadratic cells in the arrays VTK reads
/// (points in 3-D with z = 0): built once for a mesh that is written at many steps.
pub struct Topology {
    points: Vec<f64>,
    connectivity: Vec<u64>,
    offsets: Vec<u64>,
    types: Vec<u8>,
}

impl Topology {
    /// The grid of `points` (2-D) and `cells` (indices into `points`) of one `kind`.
    pub fn new<C: AsRef<[usize]>>(points: &[[f64; 2]], cells: &[C], kind: Kind) -> Topology {
        let points = points.iter().flat_map(|p| [p[0], p[1], 0.0]).collect();
        let mut connectivity = Vec::new();
        let mut offsets = Vec::with_capacity(cells.len());
        for c in cells {
            connectivity.extend(c.as_ref().iter().map(|&i| i as u64));
            offsets.push(connectivity.len() as u64);
        }
        Topology {
            points,
            connectivity,
            offsets,
            types: vec![kind.code(); cells.len()],
        }
    }

    fn n_points(&self) -> usize {
        self.points.len() / 3
    }

    fn n_cells(&self) -> usize {
        self.types.len()
    }
}

/// A serialised `.vtu` file as the byte strings that follow each other in it (the XML header,
/// each array's block, the closing tags): the arrays of raw output are borrowed, not copied.
pub struct Encoded<'a> {
    parts: Vec<Cow<'a, [u8]>>,
}

impl Encoded<'_> {
    /// The file's byte strings, in order.
    pub fn parts(&self) -> Vec<&[u8]> {
        self.parts.iter().map(|p| &p[..]).collect()
    }

    /// The whole file.
    pub fn to_vec(&self) -> Vec<u8> {
        self.parts.concat()
    }
}

/// Serialises an unstructured grid: `point_data` and `cell_data` on `topology`; `compress`
/// writes every array as one zlib block.
pub fn unstructured<'a>(
    topology: &'a Topology,
    point_data: &'a [Field],
    cell_data: &'a [Field],
    compress: bool,
) -> Encoded<'a> {
    encode(
        topology,
        point_data.iter().map(field).collect(),
        cell_data,
        compress,
    )
    .0
}

/// The arrays of a [`Field`].
fn field(f: &Field) -> Array<'_> {
    Array {
        name: Some(&f.name),
        ncomp: f.ncomp,
        values: Values::F64(&f.values),
    }
}

/// What follows the point data in a raw (uncompressed) dataset: the same bytes at every step
/// of a series on one mesh whose point fields keep their names and shapes.
pub struct AfterPointData<'a> {
    /// The byte offset in the file where it begins.
    pub offset: usize,
    /// The length of the whole file.
    pub len: usize,
    parts: Vec<Cow<'a, [u8]>>,
}

impl AfterPointData<'_> {
    /// Its byte strings, in order.
    pub fn parts(&self) -> Vec<&[u8]> {
        self.parts.iter().map(|p| &p[..]).collect()
    }
}

/// The bytes of a raw dataset of [`unstructured`] that follow its point data, whose fields
/// have the names and component counts `point_shapes` (their values are not needed: only
/// their sizes set the header and the offsets), and where they begin.
pub fn raw_after_point_data<'a>(
    topology: &'a Topology,
    point_shapes: &[(&'a str, u32)],
    cell_data: &'a [Field],
) -> AfterPointData<'a> {
    let n = topology.n_points();
    let arrays = point_shapes
        .iter()
        .map(|&(name, ncomp)| Array {
            name: Some(name),
            ncomp,
            values: Values::Shape(ncomp as usize * n),
        })
        .collect();
    let (encoded, sizes) = encode(topology, arrays, cell_data, false);
    let mut parts = encoded.parts.into_iter();
    let xml = parts.next().expect("the header");
    // Each raw array is two parts (its byte count, its bytes).
    let parts: Vec<_> = parts.skip(2 * point_shapes.len()).collect();
    let offset = xml.len() + sizes[..point_shapes.len()].iter().sum::<usize>();
    let len = offset + parts.iter().map(|p| p.len()).sum::<usize>();
    AfterPointData { offset, len, parts }
}

/// [`unstructured`] of the arrays `point_arrays`, with each array's block size in the
/// appended section.
fn encode<'a>(
    topology: &'a Topology,
    point_arrays: Vec<Array<'a>>,
    cell_data: &'a [Field],
    compress: bool,
) -> (Encoded<'a>, Vec<usize>) {
    // The arrays in the order of the XML header, which is also their order in the appended
    // section.
    let cell_arrays: Vec<Array> = cell_data.iter().map(field).collect();
    let points_array = Array {
        name: None,
        ncomp: 3,
        values: Values::F64(&topology.points),
    };
    let cell_arrays_topology = [
        Array {
            name: Some("connectivity"),
            ncomp: 1,
            values: Values::U64(&topology.connectivity),
        },
        Array {
            name: Some("offsets"),
            ncomp: 1,
            values: Values::U64(&topology.offsets),
        },
        Array {
            name: Some("types"),
            ncomp: 1,
            values: Values::U8(&topology.types),
        },
    ];
    let sections: [(&str, &[Array]); 4] = [
        ("PointData", &point_arrays),
        ("CellData", &cell_arrays),
        ("Points", std::slice::from_ref(&points_array)),
        ("Cells", &cell_arrays_topology),
    ];
    let all: Vec<&Array<'a>> = sections.iter().flat_map(|(_, a)| a.iter()).collect();

    // Each array's block: the compressed ones are encoded first (their sizes give the
    // offsets), in parallel; a raw one is its byte count and its values' own bytes.
    let blocks: Vec<Cow<'a, [u8]>> = if compress {
        use rayon::prelude::*;
        all.par_iter()
            .map(|a| Cow::Owned(zlib_block(&a.values)))
            .collect()
    } else {
        all.iter()
            .flat_map(|a| {
                [
                    Cow::Owned((a.values.byte_len() as u64).to_le_bytes().to_vec()),
                    a.values.le_bytes(),
                ]
            })
            .collect()
    };
    let sizes: Vec<usize> = if compress {
        blocks.iter().map(|b| b.len()).collect()
    } else {
        all.iter().map(|a| 8 + a.values.byte_len()).collect()
    };

    let mut xml = String::new();
    xml += "<?xml version=\"1.0\"?>\n";
    xml += "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\"";
    if compress {
        xml += " compressor=\"vtkZLibDataCompressor\"";
    }
    xml += ">\n  <UnstructuredGrid>\n";
    let _ = writeln!(
        xml,
        "    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        topology.n_points(),
        topology.n_cells()
    );
    let (mut k, mut offset) = (0, 0usize);
    for (section, arrays) in sections {
        let _ = write!(xml, "      <{section}");
        if section.ends_with("Data") {
            // The active scalars and vectors: the first array of one and of three components.
            let first = |n: u32| arrays.iter().find(|a| a.ncomp == n).and_then(|a| a.name);
            if let Some(s) = first(1) {
                let _ = write!(xml, " Scalars=\"{}\"", escape(s));
            }
            if let Some(v) = first(3) {
                let _ = write!(xml, " Vectors=\"{}\"", escape(v));
            }
        }
        xml += ">\n";
        for a in arrays {
            let _ = write!(xml, "        <DataArray type=\"{}\"", a.values.vtk_type());
            if let Some(name) = a.name {
                let _ = write!(xml, " Name=\"{}\"", escape(name));
            }
            let _ = writeln!(
                xml,
                " NumberOfComponents=\"{}\" format=\"appended\" offset=\"{offset}\"/>",
                a.ncomp
            );
            offset += sizes[k];
            k += 1;
        }
        let _ = writeln!(xml, "      </{section}>");
    }
    xml += "    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _";
    let tail = "\n  </AppendedData>\n</VTKFile>\n";

    let mut parts = Vec::with_capacity(blocks.len() + 2);
    parts.push(Cow::Owned(xml.into_bytes()));
    parts.extend(blocks);
    parts.push(Cow::Borrowed(tail.as_bytes()));
    (Encoded { parts }, sizes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What [`raw_after_point_data`] gives from the fields' names and shapes alone is the
    /// file [`unstructured`] writes with their values, from its offset on.
    #[test]
    fn the_bytes_after_the_point_data_are_those_of_the_whole_file() {
        // One reference triangle.
        let points = crate::shapes::tri6::NODE_REF_COORDS;
        let topology = Topology::new(&points, &[[0usize, 1, 2, 3, 4, 5]], Kind::Tri6);
        let values = |k: usize, n: usize| (0..n).map(|i| (i * 7 + k) as f64 * 0.25).collect();
        let point_data = [
            Field::vector("displacement", values(1, 18)),
            Field::scalar("p & <q>", values(2, 6)),
        ];
        let cell_data = [Field::scalar("body_id", vec![1.0])];
        let whole = unstructured(&topology, &point_data, &cell_data, false).to_vec();
        let after = raw_after_point_data(
            &topology,
            &[("displacement", 3), ("p & <q>", 1)],
            &cell_data,
        );
        assert_eq!(after.len, whole.len());
        assert_eq!(after.parts().concat(), whole[after.offset..]);
        // The header and the point fields come before it.
        let header = whole.windows(4).position(|w| w == b"   _").unwrap() + 4;
        assert_eq!(after.offset, header + 2 * 8 + (18 + 6) * 8);
    }
}
