//! The statistics of floorcast's reports, usable without the coordinator: no network transport,
//! async runtime or database in this crate's dependency tree (the workspace's
//! `tests/light_crates.rs` checks it). Everything here is a pure function of stored results ([`StoredResult`], the plain data
//! of one job) and the known-map tours; the coordinator stores them and calls in.
//!
//! - [`report`]: the typed [`Report`], the values `floorcast report` prints, and its text.
//! - [`table`]: the paper's Table 1 for a grid, the comparisons of `report` (and `--json`), and
//!   CSV export.
//! - [`progress`]: a run's progress curve as stored (the one codec of `progress.csv`).
//! - [`measure`]: the time a comparison measures, and a coverage level as text.
//! - [`metric`]: the metrics `report` compares besides the exploration time (one enum).
//! - [`outcome`]: what a run achieved at a coverage level, and the pairs of two labels' runs
//!   (a run that did not achieve the outcome is a loss against one that did).
//! - [`stats`]: Wilcoxon, bootstrap, Holm, effect size of paired differences, the anytime-valid
//!   confidence sequence, the interquartile mean, the stratified bootstrap.
//! - [`aggregate`]: aggregates across buildings (IQM, probability of improvement, performance
//!   profiles).
//! - [`sprt`]: the sequential test (GSPRT) that decides a comparison from paired runs.
//! - [`sequential`]: a sequential grid's progress, batch by batch, from stored results, and its
//!   text (the grid's jobs are the coordinator's).
//! - [`ranking`]: the report's leaderboard (labels by their aggregates, with efficiency).
//! - [`yardstick`]: a run's efficiency against the known-map tours of its building.

pub mod aggregate;
#[cfg(any(test, feature = "test-support"))]
pub mod fixtures;
pub mod measure;
pub mod metric;
pub mod outcome;
pub mod progress;
pub mod ranking;
pub mod report;
mod row;
pub mod sequential;
pub mod sprt;
pub mod stats;
pub mod table;
pub mod yardstick;

pub use report::Report;
pub use row::StoredResult;
