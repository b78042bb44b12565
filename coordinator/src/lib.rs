//! Expands experiment grids into jobs, schedules them over workers, stores and aggregates
//! results.
//!
//! - [`grid`]: a grid file as written, validated into a [`grid::Plan`] before anything runs.
//! - [`schedule`]: the scheduler, a state machine without IO or clock (events in, actions out).
//! - [`store`]: the SQLite results store (WAL), one row per job, resumable.
//! - [`run`]: the coordinator loop; runs a plan with embedded worker threads and/or remote
//!   workers.
//! - [`net`]: the zenoh transport for remote workers (the only module that knows zenoh).
//! - [`wire`]: the versioned messages between coordinator and workers.
//! - [`table`]: the paper's Table 1 for a grid, and CSV export.
//! - [`sequential`]: the sequential test (GSPRT) that decides a comparison from paired runs.

pub mod grid;
pub mod net;
pub mod run;
pub mod schedule;
pub mod sequential;
pub mod store;
pub mod table;
pub mod wire;
