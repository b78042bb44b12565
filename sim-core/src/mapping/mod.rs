//! Occupancy mapping from laser scans: log-odds grid, obstacle distance field, scan matching,
//! and how well a map aligns with the truth.

pub mod alignment;
pub mod distance_field;
pub mod log_odds;
pub mod ray;
pub mod scan_match;
