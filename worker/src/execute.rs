//! Running one job into its report ([`JobReport`]: the run record and progress, or the error,
//! with the wall time): a job received from a coordinator ([`execute_wire`], what a remote worker
//! runs) or one given in memory ([`report`], which the coordinator's embedded workers use).

use std::time::Instant;

use sim_core::{Building, Pose};

use crate::wire::{JobOutcome, JobReport, WireJob};
use crate::{
    run_job, run_jobs_shared, GivenSource, GivenStart, Job, JobError, JobOutput, StrategyRef,
};

/// Runs a job received from the network (see [`crate::process`]) in its building (already
/// checked against the job's building hash).
pub fn execute_wire(job: &WireJob, building: &Building) -> JobReport {
    // An external strategy's files go to a new private directory of this job's own
    // (`private_temp_dir`: no one else can have made it), removed after it.
    let mut dir = None;
    let program = match &job.program {
        Some(p) => match crate::external::private_temp_dir("floorcast-job-")
            .and_then(|d| p.materialize(d.path()).map(|p| (d, p)))
        {
            Ok((d, p)) => {
                dir = Some(d);
                Some(p)
            }
            Err(e) => return JobReport::failed(format!("cannot run its strategy: {e}")),
        },
        None => None,
    };
    // The start's source is checked as the job comes in: a word of none is the job's error.
    let start = match &job.start {
        None => None,
        Some(s) => match GivenSource::from_name(&s.source) {
            Some(source) => Some(GivenStart {
                pose: Pose::new(s.pose[0], s.pose[1], s.pose[2]),
                source,
            }),
            None => {
                return JobReport::failed(format!(
                    "its start's source '{}' is not one of command line, random, grid",
                    crate::text::excerpt(&s.source)
                ))
            }
        },
    };
    // The wire names the strategy: resolved here, once.
    let strategy = match StrategyRef::resolve(&job.strategy, program) {
        Ok(s) => s,
        Err(e) => {
            let (outcome, stderr_tail) = outcome(Err(e));
            return JobReport {
                wall_time_s: 0.0,
                outcome,
                stderr_tail,
            };
        }
    };
    let out = report(&Job {
        building,
        building_name: job.building_name.clone(),
        strategy,
        seed: job.seed,
        settings: job.settings.clone(),
        start,
        snapshot_fractions: Vec::new(),
    });
    drop(dir);
    out
}

/// Runs `spec` and reports its outcome (success or the job's error) and wall time.
pub fn report(spec: &Job<'_>) -> JobReport {
    let t = Instant::now();
    let (outcome, stderr_tail) = outcome(run_job(spec, &mut |_| {}));
    JobReport {
        wall_time_s: t.elapsed().as_secs_f64(),
        outcome,
        stderr_tail,
    }
}

/// [`report`] for each of `specs`, run together where they can share their beginning
/// ([`run_jobs_shared`]); each report's wall time is its run's share.
pub fn reports_shared(specs: &[Job<'_>]) -> Vec<JobReport> {
    run_jobs_shared(specs)
        .into_iter()
        .map(|(r, wall_time_s)| {
            let (outcome, stderr_tail) = outcome(r);
            JobReport {
                wall_time_s,
                outcome,
                stderr_tail,
            }
        })
        .collect()
}

/// A job's outcome as reported, with the end of its strategy program's stderr if it failed
/// (a successful run's stderr is not reported: `explore` writes it to a file, a grid does not
/// keep it).
fn outcome(r: Result<JobOutput, JobError>) -> (JobOutcome, Option<String>) {
    let stderr_tail = match &r {
        Err(JobError::Strategy(e)) if !e.stderr.is_empty() => {
            Some(crate::text::tail(&e.stderr, crate::wire::MAX_STDERR_TAIL))
        }
        _ => None,
    };
    let outcome = match r {
        Ok(out) => JobOutcome::Ok {
            progress: out
                .result
                .progress
                .iter()
                .map(|p| [p.time_s, p.explored_area_m2, p.explored_fraction])
                .collect(),
            summary: Box::new(out.summary),
        },
        Err(e) => JobOutcome::Failed {
            error: e.to_string(),
        },
    };
    (outcome, stderr_tail)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::WireStart;
    use crate::Settings;

    /// A job whose start names no source it can have fails, saying so; the sources a grid
    /// sends are taken.
    #[test]
    fn a_wire_start_is_checked_as_it_comes_in() {
        let b = crate::small_building();
        let job = |source: &str| WireJob {
            job_id: "j".into(),
            grid: "g".into(),
            building_name: "small".into(),
            building_hash: b.content_hash(),
            strategy: "baseline".into(),
            label: "baseline".into(),
            seed: 1,
            settings: Settings {
                time_limit_s: 5.0,
                ..Settings::default()
            },
            start: Some(WireStart {
                pose: [1.2, 9.8, 0.0],
                source: source.into(),
            }),
            program: None,
        };
        let bad = execute_wire(&job("sideways"), &b);
        match &bad.outcome {
            JobOutcome::Failed { error } => {
                assert!(error.contains("start's source 'sideways'"), "{error}")
            }
            other => panic!("{other:?}"),
        }
        let good = execute_wire(&job("grid"), &b);
        assert!(matches!(good.outcome, JobOutcome::Ok { .. }), "{good:?}");
        // A strategy this build does not have is the job's error.
        let unknown = execute_wire(
            &WireJob {
                strategy: "nope".into(),
                ..job("grid")
            },
            &b,
        );
        match &unknown.outcome {
            JobOutcome::Failed { error } => {
                assert!(error.contains("unknown strategy 'nope'"), "{error}")
            }
            other => panic!("{other:?}"),
        }
    }
}
