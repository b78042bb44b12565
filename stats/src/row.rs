//! The plain data of a stored result: the row every statistic reads, whoever stored it (the
//! coordinator's SQLite store makes it from its rows).

use floorcast_worker::wire::JobStatus;
use floorcast_worker::{RunSummary, Settings};

use crate::progress::Sample;

/// One stored job: its identity (from the grid's plan), outcome and provenance; what every
/// statistic here reads. Its contents are typed: the results store (`floorcast_coordinator::store`)
/// decodes a row's text once, when it reads it, and encodes them when it writes it; no other
/// module reads that text.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredResult {
    pub job_id: String,
    pub grid: String,
    pub building: String,
    pub building_hash: String,
    pub strategy: String,
    pub label: String,
    pub seed: u64,
    /// The settings the job ran with: each setting a row written by an earlier version does
    /// not hold is at its default (the value that version ran with).
    pub settings: Settings,
    pub status: JobStatus,
    pub error: Option<String>,
    /// The run's record (a successful job's; checked against the row's seed and building).
    pub summary: Option<RunSummary>,
    /// The run's progress curve as stored ([`crate::progress`]: rounded as the store keeps it).
    pub progress: Option<Vec<Sample>>,
    pub worker: String,
    pub wall_time_s: f64,
    pub floorcast_version: String,
    /// The end of what an external strategy wrote to stderr (at most
    /// [`floorcast_worker::wire::MAX_STDERR_TAIL`] bytes), kept for failed jobs only: a
    /// successful run's stderr is not stored (`explore` writes it to `strategy-stderr.txt`).
    pub stderr_tail: Option<String>,
}
