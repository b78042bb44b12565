//! Running one job: a planned job here (embedded workers) or a job received from the network
//! (remote workers), each turned into the store row that identifies it, with its outcome.

use std::fmt::Write as _;
use std::time::Instant;

use floorcast_worker::{run_job, GivenStart, Job};
use sim_core::{Building, Pose};

use crate::grid::{Plan, PlannedJob};
use crate::store::StoredResult;
use crate::wire::{WireJob, WireProgram, WireStart};

/// A planned job as it is handed to a remote worker.
pub fn wire_job(plan: &Plan, job: &PlannedJob) -> WireJob {
    let b = &plan.buildings[job.building];
    WireJob {
        job_id: job.id.clone(),
        grid: plan.name.clone(),
        building_name: b.name.clone(),
        building_hash: b.hash.clone(),
        strategy: job.strategy.clone(),
        label: job.label.clone(),
        seed: job.seed,
        settings: job.settings.clone(),
        start: job.start.as_ref().map(|s| WireStart {
            pose: [s.pose.x_m, s.pose.y_m, s.pose.theta_rad],
            source: s.source.clone(),
        }),
        program: job.program.as_ref().map(|p| {
            let empty = Vec::new();
            let contents = plan
                .program_files
                .get(&p.files_sha256)
                .map_or(&empty, |c| c.as_ref());
            WireProgram::new(p, contents)
        }),
    }
}

/// The store row a planned job produces, before it ran (identity fields only).
pub fn expected_row(plan: &Plan, job: &PlannedJob, worker: &str) -> StoredResult {
    wire_row(&wire_job(plan, job), worker)
}

/// Runs one planned job and turns its outcome (success or a job error) into a store row.
pub fn execute(plan: &Plan, job: &PlannedJob, worker: &str) -> StoredResult {
    let b = &plan.buildings[job.building];
    execute_job(
        expected_row(plan, job, worker),
        &Job {
            building: &b.building,
            building_name: b.name.clone(),
            strategy: job.strategy.clone(),
            program: job.program.clone(),
            seed: job.seed,
            settings: job.settings.clone(),
            start: job.start.as_ref().map(|s| GivenStart {
                pose: s.pose,
                source: s.source.clone(),
            }),
            snapshot_fractions: Vec::new(),
        },
    )
}

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
        floorcast_version: floorcast_worker::FLOORCAST_VERSION.to_string(),
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

/// Runs a job received from the network (see `net.rs`) in its building (already checked
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
pub(crate) fn execute_job(mut row: StoredResult, spec: &Job<'_>) -> StoredResult {
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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::wire::check_result_start;
    use std::path::Path;

    /// A plan of `baseline` on the small building with `seeds`, `time_limit_s` and `extra`
    /// lines, its results in `dir`.
    pub(crate) fn small_plan(dir: &Path, seeds: &str, time_limit_s: u32, extra: &str) -> Plan {
        let small = Path::new(env!("CARGO_MANIFEST_DIR")).join("../buildings/small.toml");
        let text = format!(
            "format = \"floorcast-grid\"\nversion = 1\nname = \"p\"\nbuildings = [\"{}\"]\nseeds = {seeds}\n[[strategies]]\nname = \"baseline\"\n[settings]\ntime_limit_s = {time_limit_s}\n{extra}",
            small.display()
        );
        Plan::parse(&text, &dir.join("grid.toml"), Some(&dir.join("r"))).unwrap()
    }

    /// A job of a grid with `[starts]` runs from its planned pose whether it runs here or on
    /// a remote worker (through its wire form), and a result that started elsewhere is refused.
    #[test]
    fn a_grid_start_crosses_the_wire_and_is_checked_on_return() {
        let dir = tempfile::tempdir().unwrap();
        let plan = small_plan(dir.path(), "[1]", 5, "[starts]\nrandom = 2\nseed = 3\n");
        assert_eq!(plan.jobs.len(), 2);
        let (a, b) = (&plan.jobs[0], &plan.jobs[1]);
        assert_ne!(a.start, b.start);
        let wire = wire_job(&plan, a);
        let wire: WireJob = serde_json::from_str(&serde_json::to_string(&wire).unwrap()).unwrap();
        let building = &plan.buildings[a.building].building;
        let remote = execute_wire(&wire, building, "w");
        let local = execute(&plan, a, "local");
        for r in [&remote, &local] {
            assert_eq!(r.status, "ok", "{:?}", r.error);
            let s = floorcast_worker::RunSummary::from_json(r.summary_json.as_deref().unwrap())
                .unwrap();
            let planned = a.start.as_ref().unwrap();
            assert_eq!(
                s.start.map(f64::to_bits),
                [planned.pose.x_m, planned.pose.y_m, planned.pose.theta_rad].map(f64::to_bits)
            );
            assert_eq!(s.start_source, "random");
            assert!(check_result_start(r, wire.start.as_ref()).is_ok());
        }
        // The other job's start is not this result's.
        let e = check_result_start(&remote, wire_job(&plan, b).start.as_ref()).unwrap_err();
        assert!(e.contains("the grid's job at"), "{e}");
    }
}
