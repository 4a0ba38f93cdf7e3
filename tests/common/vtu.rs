//! A reader of the `.vtu` files stickslip writes (VTK XML unstructured grid, every array
//! `format="appended"` in one `<AppendedData encoding="raw">` section, `header_type="UInt64"`,
//! little-endian; raw, or zlib blocks with `compressor="vtkZLibDataCompressor"`), written from
//! the VTK file-format documentation, independently of the writer. It checks the layout as it
//! reads: every array where its offset says, of the size its type, component count and the
//! piece's point or cell count imply, the arrays packed end to end, the file closed after them.

use std::path::Path;

/// The values of one data array.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    F64(Vec<f64>),
    U64(Vec<u64>),
    I64(Vec<i64>),
    U8(Vec<u8>),
}

/// One data array: the element it sits in (`PointData`, `CellData`, `Points`, `Cells`), its
/// attributes and values.
#[derive(Clone, Debug)]
pub struct Array {
    pub section: String,
    /// Empty for the points.
    pub name: String,
    pub vtk_type: String,
    pub ncomp: usize,
    /// Where its bytes (with their header) start and end in the file.
    pub bytes: std::ops::Range<usize>,
    pub values: Values,
}

/// A read `.vtu` file.
#[derive(Debug)]
pub struct Vtu {
    pub points: usize,
    pub cells: usize,
    pub compressed: bool,
    /// The XML before the appended data.
    pub header: String,
    pub arrays: Vec<Array>,
}

/// `key="value"` attributes of an XML start tag.
fn attributes(tag: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut rest = tag;
    while let Some(eq) = rest.find("=\"") {
        let key = rest[..eq].rsplit(char::is_whitespace).next().unwrap_or("");
        let after = &rest[eq + 2..];
        let end = after.find('"').expect("a closed attribute value");
        out.push((key.to_string(), after[..end].to_string()));
        rest = &after[end + 1..];
    }
    out
}

fn attr<'a>(attrs: &'a [(String, String)], key: &str) -> Option<&'a str> {
    attrs
        .iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
}

fn u64s(b: &[u8]) -> Vec<u64> {
    b.chunks_exact(8)
        .map(|c| u64::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

impl Vtu {
    pub fn read(path: &Path) -> Result<Vtu, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Vtu::parse(&bytes).map_err(|e| format!("{}: {e}", path.display()))
    }

    pub fn parse(bytes: &[u8]) -> Result<Vtu, String> {
        let find = |from: usize, pat: &[u8]| {
            bytes[from..]
                .windows(pat.len())
                .position(|w| w == pat)
                .map(|i| i + from)
        };
        let app = find(0, b"<AppendedData").ok_or("no <AppendedData>")?;
        let underscore = find(app, b"_").ok_or("no `_` opening the appended data")?;
        let header = std::str::from_utf8(&bytes[..underscore])
            .map_err(|e| format!("header not UTF-8: {e}"))?
            .to_string();
        let app_tag = &header[app..header[app..].find('>').map_or(header.len(), |i| app + i)];
        if attr(&attributes(app_tag), "encoding") != Some("raw") {
            return Err(format!("not raw appended data: {app_tag}"));
        }
        if !header[app..].trim_end().ends_with('>') {
            return Err("text between <AppendedData> and `_`".into());
        }
        let data = underscore + 1;
        let root = &header[header.find("<VTKFile").ok_or("no <VTKFile>")?..];
        let root = attributes(&root[..root.find('>').unwrap()]);
        for (k, v) in [
            ("type", "UnstructuredGrid"),
            ("byte_order", "LittleEndian"),
            ("header_type", "UInt64"),
        ] {
            if attr(&root, k) != Some(v) {
                return Err(format!("VTKFile {k} is {:?}, not {v}", attr(&root, k)));
            }
        }
        let compressed = match attr(&root, "compressor") {
            None => false,
            Some("vtkZLibDataCompressor") => true,
            Some(c) => return Err(format!("compressor {c}")),
        };
        let piece = &header[header.find("<Piece").ok_or("no <Piece>")?..];
        let piece = attributes(&piece[..piece.find('>').unwrap()]);
        let count = |k: &str| -> Result<usize, String> {
            attr(&piece, k)
                .and_then(|v| v.parse().ok())
                .ok_or(format!("Piece {k}"))
        };
        let (points, cells) = (count("NumberOfPoints")?, count("NumberOfCells")?);

        // The data arrays in header order, with the element each is in.
        let mut arrays = Vec::new();
        let mut section = String::new();
        let mut expect_offset = 0usize;
        for tag in header.split('<').skip(1) {
            let tag = &tag[..tag.find('>').ok_or("unclosed tag")?];
            let tname = tag.split([' ', '/', '\n']).next().unwrap_or("");
            if ["PointData", "CellData", "Points", "Cells"].contains(&tname) {
                section = tname.to_string();
            }
            if tname != "DataArray" {
                continue;
            }
            let a = attributes(tag);
            let get = |k: &str| attr(&a, k).ok_or(format!("DataArray {tag}: no {k}"));
            if get("format")? != "appended" {
                return Err(format!("DataArray {tag} is not appended"));
            }
            let offset: usize = get("offset")?.parse().map_err(|_| "bad offset")?;
            if offset != expect_offset {
                return Err(format!(
                    "DataArray {tag}: offset {offset}, the arrays before end at {expect_offset}"
                ));
            }
            let vtk_type = get("type")?.to_string();
            let size = match vtk_type.as_str() {
                "Float64" | "UInt64" | "Int64" => 8,
                "UInt8" => 1,
                t => return Err(format!("type {t}")),
            };
            let ncomp: usize = attr(&a, "NumberOfComponents").map_or(Ok(1), |v| {
                v.parse().map_err(|_| "bad NumberOfComponents".to_string())
            })?;
            let name = attr(&a, "Name").unwrap_or("").to_string();
            let start = data + offset;
            let head = |n: usize| {
                bytes
                    .get(start..start + 8 * n)
                    .map(u64s)
                    .ok_or(format!("{name}: the file ends in its header"))
            };
            let (raw, len) = if compressed {
                let h = head(3)?;
                let nblocks = h[0] as usize;
                let sizes = head(3 + nblocks)?[3..].to_vec();
                let mut raw = Vec::new();
                let mut at = start + 8 * (3 + nblocks);
                for (i, &c) in sizes.iter().enumerate() {
                    let block = bytes
                        .get(at..at + c as usize)
                        .ok_or(format!("{name}: the file ends in block {i}"))?;
                    let out = miniz_oxide::inflate::decompress_to_vec_zlib(block)
                        .map_err(|e| format!("{name}: block {i}: {e:?}"))?;
                    let want = if i + 1 == nblocks && h[2] != 0 {
                        h[2]
                    } else {
                        h[1]
                    };
                    if out.len() as u64 != want {
                        return Err(format!("{name}: block {i} holds {} bytes", out.len()));
                    }
                    raw.extend(out);
                    at += c as usize;
                }
                (raw, at - start)
            } else {
                let n = head(1)?[0] as usize;
                let raw = bytes
                    .get(start + 8..start + 8 + n)
                    .ok_or(format!("{name}: the file ends in its data"))?
                    .to_vec();
                (raw, 8 + n)
            };
            if raw.len() % (size * ncomp) != 0 {
                return Err(format!("{name}: {} bytes", raw.len()));
            }
            let values = match vtk_type.as_str() {
                "Float64" => Values::F64(
                    raw.chunks_exact(8)
                        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                        .collect(),
                ),
                "UInt64" => Values::U64(u64s(&raw)),
                "Int64" => Values::I64(
                    raw.chunks_exact(8)
                        .map(|c| i64::from_le_bytes(c.try_into().unwrap()))
                        .collect(),
                ),
                _ => Values::U8(raw.clone()),
            };
            let tuples = raw.len() / (size * ncomp);
            let expected = match (section.as_str(), name.as_str()) {
                ("PointData" | "Points", _) => Some(points),
                ("CellData", _) | ("Cells", "offsets" | "types") => Some(cells),
                _ => None,
            };
            if let Some(e) = expected
                && e != tuples
            {
                return Err(format!("{section} {name}: {tuples} tuples, not {e}"));
            }
            arrays.push(Array {
                section: section.clone(),
                name,
                vtk_type,
                ncomp,
                bytes: start..start + len,
                values,
            });
            expect_offset += len;
        }
        let rest = String::from_utf8_lossy(&bytes[data + expect_offset..]);
        if rest.split_whitespace().collect::<String>() != "</AppendedData></VTKFile>" {
            return Err(format!("after the last array: {rest:?}"));
        }
        Ok(Vtu {
            points,
            cells,
            compressed,
            header,
            arrays,
        })
    }

    pub fn array(&self, section: &str, name: &str) -> Option<&Array> {
        self.arrays
            .iter()
            .find(|a| a.section == section && a.name == name)
    }

    /// The `Float64` values of a named array.
    pub fn f64s(&self, section: &str, name: &str) -> &[f64] {
        match self.array(section, name).map(|a| &a.values) {
            Some(Values::F64(v)) => v,
            other => panic!("{section} {name}: {other:?}"),
        }
    }

    /// The integer values of a `Cells` array (connectivity, offsets, types).
    pub fn ints(&self, name: &str) -> Vec<i64> {
        match self.array("Cells", name).map(|a| &a.values) {
            Some(Values::U64(v)) => v.iter().map(|&x| x as i64).collect(),
            Some(Values::I64(v)) => v.clone(),
            Some(Values::U8(v)) => v.iter().map(|&x| x as i64).collect(),
            other => panic!("Cells {name}: {other:?}"),
        }
    }

    /// What holds byte `pos` of the file: the XML header, or the data array (its name, and its
    /// element).
    pub fn what_holds(&self, pos: usize) -> String {
        match self.arrays.iter().find(|a| a.bytes.contains(&pos)) {
            Some(a) if a.name.is_empty() => format!("data array `(points)` of {}", a.section),
            Some(a) => format!("data array `{}` of {}", a.name, a.section),
            None if pos < self.header.len() => "the XML header".into(),
            None => "the end of the file".into(),
        }
    }
}
