//! Simulation kernel: building geometry, robot, laser, occupancy mapping, frontiers,
//! layout reconstruction, information gain, exploration strategies.
//!
//! No IO, no threads, no clock, no global RNG, no async. Randomness arrives as a seed or an
//! `&mut impl Rng`; time is simulated (`sim_time_s`). The same (building, strategy, seed, config)
//! gives a bit-identical run.

pub mod building;
pub mod distance;
pub mod explore;
pub mod frontier;
pub mod gain;
pub mod generate;
pub mod geom;
pub mod grid;
pub mod layout;
pub mod layout_gain;
pub mod mapping;
pub mod plan;
pub mod scan;
pub mod sim;
pub mod tour;
pub mod tsp;
pub mod utility;

pub use building::{Building, Door, Geometry, Room};
pub use geom::{Aabb, Polygon, Pose, Segment, Vec2};
pub use grid::{Bitmap, Cell, Grid, GridFrame, Occupancy, OccupancyGrid};
pub use scan::Scan;
