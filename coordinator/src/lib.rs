//! Expands experiment grids into jobs, schedules them over workers, stores and aggregates
//! results.
//!
//! - [`grid`]: a grid file as written, validated into a [`grid::Plan`] before anything runs.
//! - [`schedule`]: the scheduler, a state machine without IO or clock (events in, actions out).
//! - [`store`]: the SQLite results store (WAL), one row per job, resumable.
//! - [`local`]: runs a plan with embedded worker threads.
//! - [`table`]: the paper's Table 1 for a grid, and CSV export.

pub mod grid;
pub mod local;
pub mod schedule;
pub mod store;
pub mod table;
