//! What is read from a mesh file as text: the header (`$MeshFormat`, refused unless MSH 4.1
//! with a data size of 4 or 8), the `$PhysicalNames` section, which `mshio` skips, the node
//! tags of the `$Nodes` section in file order, and `mshio`'s parse errors cut short.

use super::error::MeshReadError;
use std::collections::HashMap;

/// Refuses anything but MSH 4.1 with a data size of 4 or 8.
pub(super) fn check_header(bytes: &[u8], p: &str) -> Result<(), MeshReadError> {
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
pub(super) fn physical_names(
    bytes: &[u8],
    path: &str,
) -> Result<HashMap<(i32, i32), String>, MeshReadError> {
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
pub(super) fn node_tags_in_file_order(
    bytes: &[u8],
    binary: bool,
    size_t: usize,
) -> Option<Vec<u64>> {
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
pub(super) fn short_parse_error(s: &str) -> String {
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
