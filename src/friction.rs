//! Friction laws (placeholder, being written).
