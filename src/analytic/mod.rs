//! Closed forms (placeholder, being written).
