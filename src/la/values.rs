//! Where a factor's values live: a vector computed in this run, or memory a caller provides
//! and keeps (a model-cache entry's file, mapped), seen through one slice.

/// Memory that holds a factor's values for as long as it lives, read-only (a mapped
/// model-cache file, checked against its hash before it is handed over).
pub trait StoredValues: Send + Sync {
    fn as_f64(&self) -> &[f64];
}

/// Memory a numeric factorisation computes its values in instead of a fresh vector (a new
/// model-cache entry's file, mapped for writing), kept read-only afterwards.
pub trait ValuesDestination: Send {
    /// The values, `len` floats that read as zeros before the factorisation writes them.
    fn as_mut_f64(&mut self) -> &mut [f64];
    /// Faults its pages in on all cores; `false` where that cannot be done (the caller then
    /// writes the zeros itself).
    fn populate(&self) -> bool;
    /// The values as written, read-only from now on.
    fn into_stored(self: Box<Self>) -> Box<dyn StoredValues>;
}

/// The values of a numeric factorisation: computed in this run ([`FactorValues::Owned`]), or
/// in memory the caller keeps ([`FactorValues::Stored`], e.g. a model-cache file mapped in
/// place, which spares a cache hit the copy of hundreds of MB into fresh memory).
pub enum FactorValues {
    Owned(Vec<f64>),
    Stored(Box<dyn StoredValues>),
}

impl std::ops::Deref for FactorValues {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        match self {
            FactorValues::Owned(v) => v,
            FactorValues::Stored(m) => m.as_f64(),
        }
    }
}

/// Factor values shared between a factorisation and a model-cache writer.
pub type SharedValues = std::sync::Arc<FactorValues>;

/// A dense column-major matrix whose columns can be read by reference, to be written elsewhere (a model-cache entry) without a copy.
pub trait DenseColumns: Send + Sync {
    fn rows(&self) -> usize;
    /// Column `j` from row `from` on.
    fn column(&self, j: usize, from: usize) -> &[f64];
}

impl DenseColumns for faer::Mat<f64> {
    fn rows(&self) -> usize {
        self.nrows()
    }
    fn column(&self, j: usize, from: usize) -> &[f64] {
        &self
            .col(j)
            .try_as_col_major()
            .expect("the columns of a Mat are contiguous")
            .as_slice()[from..]
    }
}
