//! Path planning on the occupancy map: inflation, Dijkstra distance fields, waypoints.

pub mod coarse;
pub mod dijkstra;
pub mod inflate;
pub mod waypoints;
