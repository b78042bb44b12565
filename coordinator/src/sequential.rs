//! A sequential grid's batches as planned jobs: [`floorcast_stats::sequential::Progress`] decides
//! which seeds and labels come next; this module plans their jobs from the grid and replays a
//! grid over its store.

use std::collections::BTreeSet;

use floorcast_stats::sequential::Progress;
use floorcast_stats::StoredResult;

use crate::grid::{Plan, PlannedJob};

/// The first batch of `plan` (whose `jobs` it is).
pub fn start(plan: &Plan) -> Progress {
    Progress::start(
        plan.sequential.as_ref(),
        &plan.labels,
        plan.jobs.iter().map(|j| j.id.clone()),
    )
}

/// Every job planned so far is stored (in `results`): tests the batch just completed
/// ([`Progress::advance`]), and returns the next batch's jobs, or none when the grid is
/// finished.
pub fn advance(progress: &mut Progress, plan: &Plan, results: &[StoredResult]) -> Vec<PlannedJob> {
    let Some(batch) = progress.advance(plan.sequential.as_ref(), &plan.labels, results) else {
        return Vec::new();
    };
    let jobs = plan.jobs_for(&batch.seeds, Some(&batch.labels));
    progress.plan(jobs.iter().map(|j| j.id.clone()));
    jobs
}

/// Replays a sequential grid over a store: the progress it had reached (every batch whose jobs
/// are all stored is tested, as the run did) and every job planned so far. A coordinator killed
/// mid-grid resumes from here.
pub fn replay(plan: &Plan, results: &[StoredResult]) -> (Progress, Vec<PlannedJob>) {
    let stored: BTreeSet<&str> = results.iter().map(|r| r.job_id.as_str()).collect();
    let mut progress = start(plan);
    let mut jobs = plan.jobs.clone();
    while !progress.finished
        && progress
            .planned
            .iter()
            .all(|id| stored.contains(id.as_str()))
    {
        jobs.extend(advance(&mut progress, plan, results));
    }
    (progress, jobs)
}
