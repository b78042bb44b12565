//! Running one planned job here (embedded workers) into the store row that identifies it, with
//! its outcome, and a planned job's wire form for remote workers (which run it with
//! [`floorcast_worker::execute::execute_wire`]).

use floorcast_worker::execute::{execute_job, wire_row};
use floorcast_worker::wire::{WireJob, WireProgram, WireStart};
use floorcast_worker::{GivenStart, Job};

use crate::grid::{Plan, PlannedJob};
use crate::store::StoredResult;

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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use floorcast_worker::execute::execute_wire;
    use floorcast_worker::wire::check_result_start;
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
