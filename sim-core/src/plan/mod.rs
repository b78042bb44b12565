//! Path planning on the occupancy map: inflation, Dijkstra distance fields, waypoints.

pub mod dijkstra;
pub mod inflate;
pub mod waypoints;
