//! File formats at floorcast's edge.
pub mod error;
pub mod map_server;

pub use error::Error;
