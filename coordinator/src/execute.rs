//! Running one planned job here (embedded workers), a planned job's wire form for remote workers
//! (which run it with [`floorcast_worker::execute::execute_wire`]), and the store row of a job
//! from its report: its identity always comes from the plan, never from the worker.

use floorcast_worker::wire::{JobOutcome, JobReport, WireJob, WireProgram, WireStart};
use floorcast_worker::Job;

use crate::grid::{Plan, PlannedJob};
use crate::store::StoredResult;
use floorcast_stats::progress::Sample;

/// A planned job as it is handed to a remote worker: [`identity`] with its program's files.
pub fn wire_job(plan: &Plan, job: &PlannedJob) -> WireJob {
    WireJob {
        program: job.program().map(|p| {
            let empty = Vec::new();
            let contents = plan
                .program_files
                .get(&p.files_sha256)
                .map_or(&empty, |c| c.as_ref());
            WireProgram::new(p, contents)
        }),
        ..identity(plan, job)
    }
}

/// A planned job's wire form without its program's files: what a report of it is checked
/// against ([`floorcast_worker::wire::check_report`]), for every result, without encoding the
/// files each time.
pub fn identity(plan: &Plan, job: &PlannedJob) -> WireJob {
    let b = &plan.buildings[job.building];
    WireJob {
        job_id: job.id.clone(),
        grid: plan.name.clone(),
        building_name: b.name.clone(),
        building_hash: b.hash.clone(),
        strategy: job.strategy().to_string(),
        label: job.label.clone(),
        seed: job.seed,
        settings: job.settings.clone(),
        start: job.start.as_ref().map(|s| WireStart {
            pose: [s.pose.x_m, s.pose.y_m, s.pose.theta_rad],
            source: s.source.as_str().to_string(),
        }),
        program: None,
    }
}

/// The store row a planned job produces, before it ran (identity fields only).
pub fn expected_row(plan: &Plan, job: &PlannedJob, worker: &str) -> StoredResult {
    let b = &plan.buildings[job.building];
    StoredResult {
        job_id: job.id.clone(),
        grid: plan.name.clone(),
        building: b.name.clone(),
        building_hash: b.hash.clone(),
        strategy: job.strategy().to_string(),
        label: job.label.clone(),
        seed: job.seed,
        settings: job.settings.clone(),
        status: crate::store::JobStatus::Ok,
        error: None,
        summary: None,
        progress: None,
        worker: worker.to_string(),
        wall_time_s: 0.0,
        floorcast_version: floorcast_worker::FLOORCAST_VERSION.to_string(),
        stderr_tail: None,
    }
}

/// The store row of `job` as `worker` reported it (the report checked with
/// [`floorcast_worker::wire::check_report`] if it came from the network).
pub fn row(plan: &Plan, job: &PlannedJob, worker: &str, report: &JobReport) -> StoredResult {
    let mut row = expected_row(plan, job, worker);
    row.wall_time_s = report.wall_time_s;
    match &report.outcome {
        JobOutcome::Ok { summary, progress } => {
            // The suite is the plan's label on the result (a worker's is never taken).
            let suite = plan.buildings[job.building].suite.as_ref();
            let mut summary = summary.clone();
            summary.suite = suite.map(|s| s.name.clone());
            summary.suite_hash = suite.map(|s| s.hash.clone());
            row.summary = Some(*summary);
            let samples: Vec<Sample> = progress.iter().copied().map(Sample::from).collect();
            row.progress = Some(floorcast_stats::progress::stored(&samples));
        }
        JobOutcome::Failed { error } => {
            row.status = crate::store::JobStatus::Failed;
            // A remote worker's or a program's text: no control characters, bounded.
            row.error = Some(floorcast_worker::text::shown(error, MAX_ERROR_BYTES));
            // Kept as the program wrote it (its lines; escaped when shown), its end only.
            row.stderr_tail = report
                .stderr_tail
                .as_deref()
                .map(|t| floorcast_worker::text::tail(t, floorcast_worker::wire::MAX_STDERR_TAIL));
        }
    }
    row
}

/// The longest error stored in a row (bytes).
pub const MAX_ERROR_BYTES: usize = 2000;
/// Runs one planned job here and reports its outcome (success or a job error).
pub fn execute(plan: &Plan, job: &PlannedJob) -> JobReport {
    floorcast_worker::execute::report(&spec(plan, job))
}

/// [`execute`] for jobs that share their beginning (see `run::partners`): run together, one
/// report each, in their order.
pub fn execute_shared(plan: &Plan, jobs: &[PlannedJob]) -> Vec<JobReport> {
    let specs: Vec<Job<'_>> = jobs.iter().map(|j| spec(plan, j)).collect();
    floorcast_worker::execute::reports_shared(&specs)
}

/// What a job runs, for the worker crate.
pub(crate) fn spec<'p>(plan: &'p Plan, job: &PlannedJob) -> Job<'p> {
    let b = &plan.buildings[job.building];
    Job {
        building: &b.building,
        building_name: b.name.clone(),
        strategy: job.reference.clone(),
        seed: job.seed,
        settings: job.settings.clone(),
        start: job.start.clone(),
        snapshot_fractions: Vec::new(),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use floorcast_worker::execute::execute_wire;
    use floorcast_worker::wire::check_report;
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
    /// a remote worker (through its wire form), to the same row; a report that is not the
    /// job's (started elsewhere, another seed, building, strategy, settings or version, numbers
    /// that are not finite, a failure without a reason) is refused, naming what differs.
    #[test]
    fn a_grid_start_crosses_the_wire_and_reports_are_checked_on_return() {
        let dir = tempfile::tempdir().unwrap();
        let plan = small_plan(dir.path(), "[1]", 5, "[starts]\nrandom = 2\nseed = 3\n");
        assert_eq!(plan.jobs.len(), 2);
        let (a, b) = (&plan.jobs[0], &plan.jobs[1]);
        assert_ne!(a.start, b.start);
        let wire = wire_job(&plan, a);
        let wire: WireJob = serde_json::from_str(&serde_json::to_string(&wire).unwrap()).unwrap();
        let building = &plan.buildings[a.building].building;
        let remote = execute_wire(&wire, building);
        let remote: JobReport =
            serde_json::from_str(&serde_json::to_string(&remote).unwrap()).unwrap();
        let local = execute(&plan, a);
        for r in [&remote, &local] {
            assert_eq!(r.status(), crate::store::JobStatus::Ok, "{r:?}");
            let JobOutcome::Ok { summary, .. } = &r.outcome else {
                unreachable!()
            };
            let planned = a.start.as_ref().unwrap();
            assert_eq!(
                summary.start.map(f64::to_bits),
                [planned.pose.x_m, planned.pose.y_m, planned.pose.theta_rad].map(f64::to_bits)
            );
            assert_eq!(summary.start_source, "random");
            assert_eq!(check_report(r, &wire), Ok(()));
        }
        assert_eq!(
            crate::verify::compare(&row(&plan, a, "w", &remote), &row(&plan, a, "l", &local)),
            Ok(())
        );
        // The other job's start is not this report's.
        let e = check_report(&remote, &wire_job(&plan, b)).unwrap_err();
        assert!(e.contains("the grid's job at"), "{e}");
        let edit = |f: &dyn Fn(&mut JobReport)| {
            let mut r = remote.clone();
            f(&mut r);
            r
        };
        let summary = |f: &dyn Fn(&mut floorcast_worker::RunSummary)| {
            edit(&|r: &mut JobReport| {
                if let JobOutcome::Ok { summary, .. } = &mut r.outcome {
                    f(summary);
                }
            })
        };
        let cases: Vec<(JobReport, &str)> = vec![
            (summary(&|s| s.seed += 1), "seed"),
            (
                summary(&|s| s.building_hash = "0".repeat(32)),
                "building_hash",
            ),
            (summary(&|s| s.strategy = "layout".into()), "strategy"),
            (summary(&|s| s.settings.alpha = 0.9), "settings"),
            (
                summary(&|s| s.floorcast_version = "0.0.1".into()),
                "floorcast_version",
            ),
            (summary(&|s| s.version = 9), "format"),
            (
                edit(&|r| {
                    if let JobOutcome::Ok { progress, .. } = &mut r.outcome {
                        progress[1][2] = f64::NAN;
                    }
                }),
                "progress sample",
            ),
            (edit(&|r| r.wall_time_s = f64::INFINITY), "wall_time_s"),
            (JobReport::failed(" "), "without an error message"),
        ];
        for (report, what) in &cases {
            let e = check_report(report, &wire).unwrap_err();
            assert!(e.contains(what), "{what}: {e}");
        }
        assert_eq!(check_report(&JobReport::failed("boom"), &wire), Ok(()));
    }
}
