//! Running one job into the row that identifies it, with its outcome: a job received from the
//! network ([`execute_wire`], what a remote worker runs) or one the coordinator planned (through
//! [`execute_job`]).

use std::fmt::Write as _;
use std::time::Instant;

use sim_core::{Building, Pose};

use crate::wire::{StoredResult, WireJob};
use crate::{run_job, GivenStart, Job};

/// The store row of a job received from the network, before it ran (identity fields only).
pub fn wire_row(job: &WireJob, worker: &str) -> StoredResult {
    StoredResult {
        job_id: job.job_id.clone(),
        grid: job.grid.clone(),
        building: job.building_name.clone(),
        building_hash: job.building_hash.clone(),
        strategy: job.strategy.clone(),
        label: job.label.clone(),
        seed: job.seed,
        settings_json: serde_json::to_string(&job.settings).unwrap_or_default(),
        status: "ok".into(),
        error: None,
        summary_json: None,
        progress_csv: None,
        worker: worker.to_string(),
        wall_time_s: 0.0,
        floorcast_version: crate::FLOORCAST_VERSION.to_string(),
    }
}

/// A `failed` row for a network job that could not run (e.g. its building arrived damaged).
pub fn failed_wire_row(job: &WireJob, worker: &str, error: String) -> StoredResult {
    StoredResult {
        status: "failed".into(),
        error: Some(error),
        ..wire_row(job, worker)
    }
}

/// Runs a job received from the network (see [`crate::process`]) in its building (already checked
/// against the job's building hash).
pub fn execute_wire(job: &WireJob, building: &Building, worker: &str) -> StoredResult {
    // An external strategy's files go to a directory of this job's own, removed after it.
    let dir = std::env::temp_dir().join(format!(
        "floorcast-job-{}-{}",
        std::process::id(),
        job.job_id
    ));
    let program = match &job.program {
        Some(p) => match p.materialize(&dir) {
            Ok(p) => Some(p),
            Err(e) => {
                let _ = std::fs::remove_dir_all(&dir);
                return failed_wire_row(job, worker, format!("cannot run its strategy: {e}"));
            }
        },
        None => None,
    };
    let row = execute_job(
        wire_row(job, worker),
        &Job {
            building,
            building_name: job.building_name.clone(),
            strategy: job.strategy.clone(),
            program,
            seed: job.seed,
            settings: job.settings.clone(),
            start: job.start.as_ref().map(|s| GivenStart {
                pose: Pose::new(s.pose[0], s.pose[1], s.pose[2]),
                source: s.source.clone(),
            }),
            snapshot_fractions: Vec::new(),
        },
    );
    if job.program.is_some() {
        let _ = std::fs::remove_dir_all(&dir);
    }
    row
}

/// Runs `spec` and fills the outcome into `row` (which carries the job's identity).
pub fn execute_job(mut row: StoredResult, spec: &Job<'_>) -> StoredResult {
    let t = Instant::now();
    let outcome = run_job(spec, &mut |_| {});
    row.wall_time_s = t.elapsed().as_secs_f64();
    match outcome {
        Ok(out) => {
            row.summary_json = serde_json::to_string(&out.summary).ok();
            let mut csv = String::from("time_s,explored_area_m2,explored_fraction\n");
            for p in &out.result.progress {
                let _ = writeln!(
                    csv,
                    "{:.1},{:.3},{:.5}",
                    p.time_s, p.explored_area_m2, p.explored_fraction
                );
            }
            row.progress_csv = Some(csv);
        }
        Err(e) => {
            row.status = "failed".into();
            row.error = Some(e.to_string());
        }
    }
    row
}
