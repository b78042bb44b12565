//! File formats at floorcast's edge.
pub mod error;
pub mod map_server;
pub mod stage;

pub use error::Error;
