//! Expands experiment grids into jobs, schedules them over workers, stores results and reports
//! them (the statistics are the `floorcast_stats` crate's: the store's row type,
//! [`store::StoredResult`], is its).
//!
//! - [`grid`]: a grid file as written, validated into a [`grid::Plan`] before anything runs.
//! - [`schedule`]: the scheduler, a state machine without IO or clock (events in, actions out).
//! - [`store`]: the SQLite results store (WAL), one row per job, resumable.
//! - [`run`]: the coordinator loop; runs a plan with embedded worker threads and/or remote
//!   workers through a transport its caller hands it.
//! - [`inbox`]: the contract between workers and the loop (messages, the transport trait).
//! - [`execute`]: runs one planned job here into a store row, and gives a planned job its wire
//!   form for remote workers (which run it with `floorcast_worker::execute`).
//! - [`net`]: the zenoh transport, both sides: the coordinator's queryables for remote workers,
//!   and the link a worker process (`floorcast_worker::process`) asks through (the only module
//!   that knows zenoh). Modules depend one way: `net` on `inbox` and `execute`, `run` on `inbox`,
//!   `execute` and `schedule`; `run` never names `net`.
//!
//! The messages between coordinator and workers are `floorcast_worker::wire`'s.
//! - [`suite`]: suites named by grids (found by name or path), and the suites of a store's
//!   runs.
//! - [`verify`]: results of remote workers checked by running their jobs again here.
//! - [`sequential`]: a sequential grid's batches as planned jobs, and its replay from the store
//!   (the test itself is `floorcast_stats::sequential`'s).
//! - [`tours`]: the known-map tours a grid's runs are measured against (their efficiency is
//!   `floorcast_stats::yardstick`'s).
//! - [`failures`]: the failed jobs and their attempts, as `report --failures` lists them.
//! - [`live`]: a running grid's state for the live view; [`live_page`] its HTML page;
//!   [`http`] serves both (`run --http`; the only module that knows HTTP).

pub mod board;
pub mod execute;
pub mod failures;
pub mod grid;
pub mod http;
pub mod inbox;
pub mod live;
pub mod live_page;
pub mod names;
pub mod net;
pub mod run;
pub mod schedule;
pub mod sequential;
pub mod store;
pub mod suite;
pub mod tours;
pub mod verify;
