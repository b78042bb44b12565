//! Frontier detection and goal blacklisting.

pub mod blacklist;
pub mod detect;
