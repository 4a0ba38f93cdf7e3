//! The contents of a section: words to write, or read back.

use super::format::CHUNK;
use crate::la::DenseColumns;

/// The words of one section.
pub enum Words {
    U64(Vec<u64>),
    Usize(Vec<usize>),
    F64(Vec<f64>),
    /// Floats shared with the model (the factor values: written while the run goes on, or,
    /// when the entry has a draft, already in its file and only hashed).
    Shared(crate::la::SharedValues),
    /// Columns `(j, from)` of a dense matrix shared with the model, each from row `from` on,
    /// one after the other (the Delassus operator and its Cholesky factor: 130 and 65 MB at
    /// L7, which a copy would add to the run's peak memory).
    Columns(std::sync::Arc<dyn DenseColumns>, Vec<(usize, usize)>),
}

/// Calls `f` with the little-endian bytes of `pieces` (each at most `longest` floats), one after
/// the other, gathered into chunks of about [`CHUNK`] bytes.
#[cfg(all(target_endian = "little", target_pointer_width = "64"))]
fn in_chunks<'a>(
    pieces: impl Iterator<Item = &'a [f64]>,
    longest: usize,
    mut f: impl FnMut(&[u8]) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let mut buf = Vec::with_capacity(CHUNK + 8 * longest);
    for p in pieces {
        buf.extend_from_slice(bytemuck::cast_slice(p));
        if buf.len() >= CHUNK {
            f(&buf)?;
            buf.clear();
        }
    }
    if !buf.is_empty() {
        f(&buf)?;
    }
    Ok(())
}

impl Words {
    /// All the columns of `m`.
    pub fn all_columns(m: std::sync::Arc<dyn DenseColumns>, ncols: usize) -> Words {
        Words::Columns(m, (0..ncols).map(|j| (j, 0)).collect())
    }

    /// The lower triangle of `m` (order `n`), column by column.
    pub fn lower_columns(m: std::sync::Arc<dyn DenseColumns>, n: usize) -> Words {
        Words::Columns(m, (0..n).map(|j| (j, j)).collect())
    }
}

impl Words {
    pub fn len(&self) -> usize {
        match self {
            Words::U64(v) => v.len(),
            Words::Usize(v) => v.len(),
            Words::F64(v) => v.len(),
            Words::Shared(v) => v.len(),
            Words::Columns(m, c) => c.iter().map(|&(_, from)| m.rows() - from).sum(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub(super) fn kind(&self) -> u32 {
        match self {
            Words::U64(_) | Words::Usize(_) => 1,
            Words::F64(_) | Words::Shared(_) | Words::Columns(..) => 2,
        }
    }

    /// Calls `f` with the little-endian bytes of the words, a chunk at a time.
    pub(super) fn for_each_chunk(
        &self,
        mut f: impl FnMut(&[u8]) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        // The words' own memory is their little-endian bytes on a little-endian 64-bit
        // machine: no copy (the factor values are most of an entry, 165 MB on L5).
        #[cfg(all(target_endian = "little", target_pointer_width = "64"))]
        {
            let bytes: &[u8] = match self {
                Words::U64(v) => bytemuck::cast_slice(v),
                Words::Usize(v) => bytemuck::cast_slice(v),
                Words::F64(v) => bytemuck::cast_slice(v),
                Words::Shared(v) => bytemuck::cast_slice(&v[..]),
                Words::Columns(m, cols) => {
                    let pieces = cols.iter().map(|&(j, from)| m.column(j, from));
                    return in_chunks(pieces, m.rows(), f);
                }
            };
            for c in bytes.chunks(CHUNK) {
                f(c)?;
            }
            Ok(())
        }
        #[cfg(not(all(target_endian = "little", target_pointer_width = "64")))]
        self.for_each_converted_chunk(f)
    }

    /// [`Self::for_each_chunk`] by converting each word.
    #[cfg_attr(
        all(target_endian = "little", target_pointer_width = "64"),
        allow(dead_code)
    )]
    pub(super) fn for_each_converted_chunk(
        &self,
        mut f: impl FnMut(&[u8]) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        let mut buf = Vec::with_capacity(CHUNK);
        let per = CHUNK / 8;
        macro_rules! chunks {
            ($v:expr, $conv:expr) => {
                for c in $v.chunks(per) {
                    buf.clear();
                    for x in c {
                        buf.extend_from_slice(&$conv(*x).to_le_bytes());
                    }
                    f(&buf)?;
                }
            };
        }
        match self {
            Words::U64(v) => chunks!(v, |x: u64| x),
            Words::Usize(v) => chunks!(v, |x: usize| x as u64),
            Words::F64(v) => chunks!(v, |x: f64| x),
            Words::Shared(v) => chunks!(&v[..], |x: f64| x),
            Words::Columns(..) => {
                chunks!(self.gathered().expect("gathered words"), |x: f64| x)
            }
        }
        Ok(())
    }

    /// The words as unsigned integers (a section of kind 1).
    pub fn into_u64(self) -> Option<Vec<u64>> {
        match self {
            Words::U64(v) => Some(v),
            Words::Usize(v) => Some(v.into_iter().map(|x| x as u64).collect()),
            _ => None,
        }
    }

    /// The words as floats (a section of kind 2).
    pub fn into_f64(self) -> Option<Vec<f64>> {
        match self {
            Words::F64(v) => Some(v),
            Words::Shared(v) => Some(v.to_vec()),
            Words::Columns(..) => self.gathered(),
            _ => None,
        }
    }

    /// The floats of [`Words::Columns`], one column after the other.
    fn gathered(&self) -> Option<Vec<f64>> {
        match self {
            Words::Columns(m, cols) => Some(
                cols.iter()
                    .flat_map(|&(j, from)| m.column(j, from).iter().copied())
                    .collect(),
            ),
            _ => None,
        }
    }
}
