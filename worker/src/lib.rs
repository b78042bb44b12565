//! Runs floorcast jobs: one exploration of a building with a strategy, a seed and settings,
//! producing a versioned run record ([`record::RunSummary`]) plus the in-memory result.
//!
//! This crate measures wall time and knows the floorcast version; the simulation itself is
//! `sim-core`'s and stays pure. It does no file IO: the binary and the coordinator store what it
//! returns.

pub mod record;
pub mod settings;

use std::time::Instant;

use sim_core::building::StartSource;
use sim_core::explore::{explore_charged, ProgressSample, RunResult};
use sim_core::{Building, Pose};

pub use record::{RunSummary, SUMMARY_FORMAT, SUMMARY_VERSION};
pub use settings::{Settings, SettingsError};

/// The floorcast version recorded in every result.
pub const FLOORCAST_VERSION: &str = env!("CARGO_PKG_VERSION");

/// One exploration to run.
#[derive(Debug, Clone)]
pub struct Job<'a> {
    pub building: &'a Building,
    /// Name to record (usually the file stem or the building's name).
    pub building_name: String,
    pub strategy: String,
    pub seed: u64,
    pub settings: Settings,
    /// Overrides the building's start pose.
    pub start: Option<Pose>,
    /// Explored fractions at which to keep a copy of the map (see `ExploreConfig`).
    pub snapshot_fractions: Vec<f64>,
}

#[derive(Debug, thiserror::Error)]
pub enum JobError {
    #[error("building {0} has no free space to start in")]
    NoStart(String),
    #[error("start pose ({x:.2}, {y:.2}) is not in free space of building {name}")]
    StartInWall { name: String, x: f64, y: f64 },
    #[error("unknown strategy '{0}' (available: {list})", list = STRATEGIES.join(", "))]
    UnknownStrategy(String),
    #[error("strategy {strategy} takes its layout from the building's ground-truth rooms, and building {name} has none (a map without rooms); use it with a floorcast building file that lists rooms, or choose another strategy")]
    NoRooms { strategy: String, name: String },
    #[error(transparent)]
    Settings(#[from] SettingsError),
    #[error("building {name}: {problem}")]
    TooLarge { name: String, problem: String },
    #[error("the simulation failed (a bug in floorcast, please report it): {0}")]
    Panicked(String),
}

/// What a job produced.
#[derive(Debug, Clone)]
pub struct JobOutput {
    pub summary: RunSummary,
    pub result: RunResult,
}

/// The strategies this version implements.
pub const STRATEGIES: &[&str] = sim_core::explore::Strategy::NAMES;

/// Checks everything about a job that can be checked before it runs (strategy, settings, rooms
/// for the oracle strategies, the map's size against the cell budget, the start pose), so that
/// callers can refuse a bad job before they create any output. Returns the config and the start.
pub fn check_job(
    job: &Job<'_>,
) -> Result<(sim_core::explore::ExploreConfig, Pose, &'static str), JobError> {
    if !STRATEGIES.contains(&job.strategy.as_str()) {
        return Err(JobError::UnknownStrategy(job.strategy.clone()));
    }
    let mut config = job.settings.to_explore_config_for(&job.strategy)?;
    if config.strategy.layout_from_truth && job.building.rooms.is_empty() {
        return Err(JobError::NoRooms {
            strategy: job.strategy.clone(),
            name: job.building_name.clone(),
        });
    }
    config.snapshot_fractions = job.snapshot_fractions.clone();
    check_size(job.building, &job.building_name, config.map_resolution_m)?;
    let (start, source) = match job.start {
        Some(p) => (p, "command line"),
        None => match job.building.default_start() {
            Some((p, StartSource::File)) => (p, "building file"),
            Some((p, StartSource::LargestClearance)) => (p, "largest clearance"),
            None => return Err(JobError::NoStart(job.building_name.clone())),
        },
    };
    if !job.building.is_free(start.position()) {
        return Err(JobError::StartInWall {
            name: job.building_name.clone(),
            x: start.x_m,
            y: start.y_m,
        });
    }
    Ok((config, start, source))
}

/// The exploration grid of `building` at `resolution_m` must fit the cell budget
/// ([`floorcast_formats::limits`]).
fn check_size(building: &Building, name: &str, resolution_m: f64) -> Result<(), JobError> {
    floorcast_formats::limits::check_building(
        building,
        std::path::Path::new(name),
        "map_resolution_m",
        resolution_m,
    )
    .map_err(|e| JobError::TooLarge {
        name: name.to_string(),
        problem: e
            .to_string()
            .strip_prefix(&format!("{name}: "))
            .map(str::to_string)
            .unwrap_or_else(|| e.to_string()),
    })
}

/// Runs one job to completion. `on_progress` sees the exploration curve as it grows. A panic of
/// the simulation is caught and returned as [`JobError::Panicked`].
pub fn run_job(
    job: &Job<'_>,
    on_progress: &mut dyn FnMut(&ProgressSample),
) -> Result<JobOutput, JobError> {
    let (config, start, source) = check_job(job)?;
    let t0 = Instant::now();
    // With charge_compute, each layout costs the wall time it took (the robot waits for it).
    let mut timed = |work: &mut dyn FnMut()| {
        let t = Instant::now();
        work();
        t.elapsed().as_secs_f64()
    };
    let cost: Option<sim_core::explore::LayoutCost<'_>> = if job.settings.charge_compute {
        Some(&mut timed)
    } else {
        None
    };
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        explore_charged(job.building, start, &config, job.seed, on_progress, cost)
    }))
    .map_err(|p| JobError::Panicked(panic_message(&*p)))?;
    let wall_time_s = t0.elapsed().as_secs_f64();
    let summary = RunSummary::new(job, &result, source, wall_time_s);
    Ok(JobOutput { summary, result })
}

/// The message of a caught panic.
pub fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".to_string()
    }
}
