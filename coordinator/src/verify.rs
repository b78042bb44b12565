//! Results checked before they count. Runs are deterministic, so a result can be checked by
//! running its job again: the coordinator re-runs, on its own machine, the first result each
//! remote worker returns and then a random fraction of the others (`--verify-fraction`), and
//! compares them bit for bit, wall times aside. A difference means the worker computes
//! differently (another build, a broken machine) or forged its result: [`crate::run`] then
//! discards every result of that worker, stores this machine's, runs the others again elsewhere
//! and gives the worker no more jobs.
//!
//! Not verified: failed results (they are reported as failures anyway), jobs of external
//! strategies (a program of the user's may not be deterministic) and jobs that charge compute
//! time (their times depend on the machine).

use crate::grid::PlannedJob;
use crate::store::StoredResult;

/// Summary fields that differ between identical runs (measured wall-clock times).
const MEASURED: [&str; 3] = ["wall_time_s", "speedup", "strategy_compute_s"];

/// Whether `result` of `job` can be checked by running it again.
pub fn verifiable(job: &PlannedJob, result: &StoredResult) -> bool {
    result.status.is_ok() && job.program().is_none() && !job.settings.charge_compute
}

/// Compares a worker's row (`theirs`) with this machine's run of the same job (`ours`): the
/// status, error, progress curve and every field of the summary but the measured times. The
/// error names the first field that differs and both values.
pub fn compare(theirs: &StoredResult, ours: &StoredResult) -> Result<(), String> {
    let differ = |field: &str, a: &dyn std::fmt::Debug, b: &dyn std::fmt::Debug| {
        Err(format!("{field} is {a:?} there and {b:?} here"))
    };
    if theirs.status != ours.status {
        return differ("status", &theirs.status, &ours.status);
    }
    if theirs.error != ours.error {
        return differ("error", &theirs.error, &ours.error);
    }
    // Field by field, as the summary is written.
    let summary = |r: &StoredResult| -> Option<serde_json::Map<String, serde_json::Value>> {
        let serde_json::Value::Object(mut m) = serde_json::to_value(r.summary.as_ref()?).ok()?
        else {
            return None;
        };
        for k in MEASURED {
            m.remove(k);
        }
        Some(m)
    };
    match (summary(theirs), summary(ours)) {
        (Some(a), Some(b)) => {
            let keys: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
            for k in keys {
                if a.get(k) != b.get(k) {
                    return differ(&format!("summary field {k}"), &a.get(k), &b.get(k));
                }
            }
        }
        (a, b) if a.is_some() != b.is_some() => {
            return differ("the summary", &a.map(|_| "present"), &b.map(|_| "present"))
        }
        _ => {}
    }
    let (a, b) = (lines(&theirs.progress), lines(&ours.progress));
    if a != b {
        return Err(match a.iter().zip(&b).position(|(x, y)| x != y) {
            Some(i) => format!("the progress curve differs from its line {}", i + 1),
            None => "the progress curve differs in length".into(),
        });
    }
    Ok(())
}

/// The lines of a stored progress curve, as they are stored: its header (`None`), then each
/// sample by its values' bits (none without a curve).
fn lines(progress: &Option<Vec<floorcast_stats::progress::Sample>>) -> Vec<Option<[u64; 3]>> {
    progress.as_ref().map_or_else(Vec::new, |p| {
        std::iter::once(None)
            .chain(p.iter().map(|s| Some(s.bits())))
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::execute::tests::small_plan;
    use crate::execute::{execute, row};

    /// A rerun of the same job is identical; a changed field, progress line or status is
    /// named; measured times are not compared.
    #[test]
    fn a_rerun_matches_and_any_change_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let plan = small_plan(dir.path(), "[1]", 10, "");
        let job = &plan.jobs[0];
        let ours = row(&plan, job, "here", &execute(&plan, job));
        let theirs = row(&plan, job, "there", &execute(&plan, job));
        assert!(verifiable(job, &theirs));
        assert_eq!(compare(&theirs, &ours), Ok(()));
        let edit = |f: &dyn Fn(&mut floorcast_worker::RunSummary)| {
            let mut r = theirs.clone();
            f(r.summary.as_mut().unwrap());
            r
        };
        let cases: Vec<(StoredResult, Option<&str>)> = vec![
            (edit(&|s| s.wall_time_s = 99.0), None),
            (edit(&|s| s.speedup = 1.0), None),
            (
                edit(&|s| s.explored_fraction = 0.5),
                Some("summary field explored_fraction"),
            ),
            (
                edit(&|s| s.path_length_m += 1e-12),
                Some("summary field path_length_m"),
            ),
            (edit(&|s| s.decisions += 1), Some("summary field decisions")),
            (
                edit(&|s| s.rooms_unexplored = Some(1000)),
                Some("summary field rooms_unexplored"),
            ),
            (
                StoredResult {
                    progress: theirs.progress.as_ref().map(|p| {
                        let mut p = p.clone();
                        p[0].time_s = 0.1;
                        p
                    }),
                    ..theirs.clone()
                },
                Some("progress curve differs from its line 2"),
            ),
            (
                StoredResult {
                    progress: theirs.progress.as_ref().map(|p| p[1..].to_vec()),
                    ..theirs.clone()
                },
                Some("progress curve differs from its line 2"),
            ),
            (
                StoredResult {
                    progress: theirs.progress.as_ref().map(|p| {
                        let mut p = p.clone();
                        p.push(p[p.len() - 1]);
                        p
                    }),
                    ..theirs.clone()
                },
                Some("progress curve differs in length"),
            ),
            (
                StoredResult {
                    status: crate::store::JobStatus::Failed,
                    ..theirs.clone()
                },
                Some("status"),
            ),
        ];
        for (i, (row, want)) in cases.iter().enumerate() {
            match (compare(row, &ours), want) {
                (Ok(()), None) => {}
                (Err(e), Some(w)) => assert!(e.contains(w), "case {i}: {e}"),
                (got, _) => panic!("case {i}: {got:?}, expected {want:?}"),
            }
        }
        let failed = StoredResult {
            status: crate::store::JobStatus::Failed,
            ..theirs.clone()
        };
        assert!(!verifiable(job, &failed));
    }
}
