//! The tuning of nested dissection.

/// Tuning of [`super::nested_dissection_with`].
#[derive(Clone, Debug, PartialEq)]
pub struct NdOptions {
    /// Subgraphs of at most this many vertices (compressed nodes) are ordered by AMD.
    pub leaf_size: usize,
    /// Largest part weight, as a fraction of the subgraph's weight (0.5 < f < 1).
    pub max_part_fraction: f64,
    /// Coarsening stops at this many vertices.
    pub coarsest: usize,
    /// Initial separators tried on the coarsest graph (level structures of as many roots).
    pub initial_tries: usize,
    /// The best this many initial separators are refined level by level …
    pub candidates: usize,
    /// … on the levels of at most this many vertices; beyond, only the best one.
    pub candidates_up_to: usize,
    /// At most this many Fiduccia–Mattheyses passes per level.
    pub fm_passes: usize,
    /// A pass stops after this many moves without a better separator.
    pub fm_patience: usize,
}

impl Default for NdOptions {
    fn default() -> Self {
        NdOptions {
            leaf_size: 128,
            max_part_fraction: 0.6,
            coarsest: 120,
            initial_tries: 8,
            candidates: 2,
            candidates_up_to: 2000,
            fm_passes: 6,
            fm_patience: 100,
        }
    }
}
