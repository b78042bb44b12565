//! Expands experiment grids into jobs, schedules them over workers, stores and aggregates
//! results.
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
//! - [`table`]: the paper's Table 1 for a grid, the comparisons of `report` (and `--json`), and
//!   CSV export.
//! - [`suite`]: suites named by grids (found by name or path), and the suites of a store's
//!   runs.
//! - [`verify`]: results of remote workers checked by running their jobs again here.
//! - [`progress`]: a run's progress curve as stored (the one codec of `progress.csv`).
//! - [`metric`]: the metrics `report` compares besides the exploration time (one enum).
//! - [`outcome`]: what a run achieved at a coverage level, and the pairs of two labels' runs
//!   (a run that did not achieve the outcome is a loss against one that did).
//! - [`stats`]: Wilcoxon, bootstrap, Holm, effect size of paired differences, the anytime-valid
//!   confidence sequence, the interquartile mean, the stratified bootstrap.
//! - [`aggregate`]: aggregates across buildings (IQM, probability of improvement, performance
//!   profiles).
//! - [`sprt`]: the sequential test (GSPRT) that decides a comparison from paired runs.
//! - [`sequential`]: a sequential grid's progress, batch by batch, replayed from the store.
//! - [`ranking`]: the report's leaderboard (labels by their aggregates, with efficiency).
//! - [`yardstick`]: the known-map tours a grid's runs are measured against, and their
//!   efficiency.
//! - [`failures`]: the failed jobs and their attempts, as `report --failures` lists them.
//! - [`live`]: a running grid's state for the live view; [`live_page`] its HTML page;
//!   [`http`] serves both (`run --http`; the only module that knows HTTP).

pub mod aggregate;
pub mod board;
pub mod execute;
pub mod failures;
pub mod grid;
pub mod http;
pub mod inbox;
pub mod live;
pub mod live_page;
pub mod measure;
pub mod metric;
pub mod names;
pub mod net;
pub mod outcome;
pub mod progress;
pub mod ranking;
pub mod run;
pub mod schedule;
pub mod sequential;
pub mod sprt;
pub mod stats;
pub mod store;
pub mod suite;
pub mod table;
pub mod verify;
pub mod yardstick;
