//! The failed jobs of a results store, as `report --failures` lists them and `report --json`
//! holds them (`failures`): each job that failed, with its attempts (the store's `failures`
//! table) and the head and tail of its strategy program's stderr, and the earlier failures of
//! jobs that later succeeded (`run --retry-failed`), marked as such. Pure functions of the
//! store's rows.

use std::collections::BTreeMap;

use crate::store::{Failure, JobStatus, StoredResult};

/// Lines of a stored stderr shown from its beginning.
pub const HEAD_LINES: usize = 5;
/// Lines of a stored stderr shown from its end.
pub const TAIL_LINES: usize = 10;

/// Where a job that failed at least once stands now.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Now {
    /// Its stored row is a failure.
    Failed,
    /// It succeeded after failing (`run --retry-failed`).
    Succeeded,
    /// No row is stored for it (its worker's results were discarded).
    NotStored,
}

impl Now {
    pub fn as_str(self) -> &'static str {
        match self {
            Now::Failed => "failed",
            Now::Succeeded => "later succeeded",
            Now::NotStored => "not stored",
        }
    }
}

/// A job that failed at least once, and its failed attempts, first to last.
#[derive(Debug, Clone, PartialEq)]
pub struct FailedJob {
    pub job_id: String,
    pub building: String,
    pub label: String,
    pub strategy: String,
    pub seed: u64,
    pub now: Now,
    pub attempts: Vec<Failure>,
}

impl FailedJob {
    /// Its last failure.
    pub fn last(&self) -> &Failure {
        self.attempts.last().expect("a failed job has a failure")
    }
}

/// The jobs that failed at least once, by building, label, seed and job: every stored failed
/// row (with its recorded attempts; a row stored before failures were recorded stands for its
/// one attempt) and every job whose recorded failures a later attempt replaced.
pub fn failed_jobs(results: &[StoredResult], failures: &[Failure]) -> Vec<FailedJob> {
    let mut attempts: BTreeMap<&str, Vec<Failure>> = BTreeMap::new();
    for f in failures {
        attempts.entry(&f.job_id).or_default().push(f.clone());
    }
    let mut out = Vec::new();
    for r in results {
        let recorded = attempts.remove(r.job_id.as_str());
        let (now, attempts) = match (r.status, recorded) {
            (JobStatus::Ok, None) => continue,
            (JobStatus::Ok, Some(a)) => (Now::Succeeded, a),
            (JobStatus::Failed, Some(a)) => (Now::Failed, a),
            (JobStatus::Failed, None) => (Now::Failed, vec![failure_of_row(r)]),
        };
        out.push(FailedJob {
            job_id: r.job_id.clone(),
            building: r.building.clone(),
            label: r.label.clone(),
            strategy: r.strategy.clone(),
            seed: r.seed,
            now,
            attempts,
        });
    }
    for (_, a) in attempts {
        let f = &a[0];
        out.push(FailedJob {
            job_id: f.job_id.clone(),
            building: f.building.clone(),
            label: f.label.clone(),
            strategy: f.strategy.clone(),
            seed: f.seed,
            now: Now::NotStored,
            attempts: a,
        });
    }
    out.sort_by(|a, b| {
        (&a.building, &a.label, a.seed, &a.job_id).cmp(&(&b.building, &b.label, b.seed, &b.job_id))
    });
    out
}

/// A failed row of a store written before failures were recorded, as its one attempt.
fn failure_of_row(r: &StoredResult) -> Failure {
    Failure {
        job_id: r.job_id.clone(),
        attempt: 1,
        grid: r.grid.clone(),
        building: r.building.clone(),
        strategy: r.strategy.clone(),
        label: r.label.clone(),
        seed: r.seed,
        error: r.error.clone().unwrap_or_default(),
        stderr_tail: r.stderr_tail.clone(),
        worker: r.worker.clone(),
        wall_time_s: r.wall_time_s,
        floorcast_version: r.floorcast_version.clone(),
        stored_unix_s: 0.0,
    }
}

/// A stored stderr's first [`HEAD_LINES`] and last [`TAIL_LINES`] lines (the tail empty when
/// the head holds them all) and how many lines it has.
pub fn head_and_tail(stderr: &str) -> (Vec<&str>, Vec<&str>, usize) {
    let lines: Vec<&str> = stderr.lines().collect();
    let n = lines.len();
    if n <= HEAD_LINES + TAIL_LINES {
        return (lines, Vec::new(), n);
    }
    (
        lines[..HEAD_LINES].to_vec(),
        lines[n - TAIL_LINES..].to_vec(),
        n,
    )
}

/// The listing of `report --failures`: a summary line, then per job its identity, where it
/// stands and its attempts (each with its error), and its last failure's stderr, head and
/// tail (and how many earlier attempts left another stderr: the JSON holds every one's). Text from programs and workers is escaped ([`floorcast_worker::text::shown`]).
pub fn render(jobs: &[FailedJob]) -> String {
    use floorcast_worker::text::shown;
    use std::fmt::Write as _;
    let failing = jobs.iter().filter(|j| j.now != Now::Succeeded).count();
    let recovered = jobs.len() - failing;
    let attempts: usize = jobs.iter().map(|j| j.attempts.len()).sum();
    let mut out = String::new();
    if jobs.is_empty() {
        out.push_str("failures: none (no job failed)\n");
        return out;
    }
    let _ = writeln!(
        out,
        "failures: {failing} job(s) failing, {recovered} job(s) failed before they succeeded ({attempts} failed attempts in all)"
    );
    for j in jobs {
        let status = match j.now {
            Now::Succeeded => format!(
                "later succeeded (attempt {}); earlier failures:",
                j.attempts.len() + 1
            ),
            now => format!("{}, {} attempt(s):", now.as_str(), j.attempts.len()),
        };
        let _ = writeln!(
            out,
            "{} {} (strategy {}) seed {}: {status}",
            shown(&j.building, 200),
            shown(&j.label, 200),
            shown(&j.strategy, 200),
            j.seed
        );
        for f in &j.attempts {
            let _ = writeln!(
                out,
                "  attempt {} (worker {}, {:.1} s): {}",
                f.attempt,
                shown(&f.worker, 200),
                f.wall_time_s,
                shown(&f.error, 2000)
            );
        }
        let last = j.last();
        match last.stderr_tail.as_deref().filter(|t| !t.trim().is_empty()) {
            None => out.push_str("  stderr: none stored\n"),
            Some(text) => {
                let (head, tail, n) = head_and_tail(text);
                let _ = writeln!(out, "  stderr of attempt {} ({n} lines):", last.attempt);
                for l in &head {
                    let _ = writeln!(out, "    | {}", shown(l, 300));
                }
                if !tail.is_empty() {
                    let _ = writeln!(out, "    | ... ({} lines)", n - HEAD_LINES - TAIL_LINES);
                    for l in &tail {
                        let _ = writeln!(out, "    | {}", shown(l, 300));
                    }
                }
            }
        }
        let differing = j.attempts[..j.attempts.len() - 1]
            .iter()
            .filter(|f| f.stderr_tail != last.stderr_tail)
            .count();
        if differing > 0 {
            let _ = writeln!(
                out,
                "  (the stderr of {differing} earlier attempt(s) differs: `report --json FILE` holds each)"
            );
        }
    }
    out
}

/// The `failures` field of `report --json` (docs/report-json.md).
pub fn to_json(jobs: &[FailedJob]) -> serde_json::Value {
    let attempt = |f: &Failure| {
        let stderr = f.stderr_tail.as_deref().unwrap_or("");
        let (head, tail, n) = head_and_tail(stderr);
        serde_json::json!({
            "attempt": f.attempt,
            "error": f.error,
            "worker": f.worker,
            "wall_time_s": f.wall_time_s,
            "floorcast_version": f.floorcast_version,
            "stored_unix_s": f.stored_unix_s,
            "stderr_lines": n,
            "stderr_head": head,
            "stderr_tail": tail,
        })
    };
    serde_json::Value::Array(
        jobs.iter()
            .map(|j| {
                serde_json::json!({
                    "job_id": j.job_id,
                    "building": j.building,
                    "label": j.label,
                    "strategy": j.strategy,
                    "seed": j.seed,
                    "status": j.now.as_str(),
                    "later_succeeded": j.now == Now::Succeeded,
                    "failed_attempts": j.attempts.len(),
                    "attempts": j.attempts.iter().map(attempt).collect::<Vec<_>>(),
                })
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn failure(job: &str, attempt: u32, stderr: Option<&str>) -> Failure {
        Failure {
            job_id: job.into(),
            attempt,
            grid: "g".into(),
            building: "b".into(),
            strategy: "s".into(),
            label: job.into(),
            seed: 1,
            error: format!("boom {attempt}"),
            stderr_tail: stderr.map(str::to_string),
            worker: "local-0".into(),
            wall_time_s: 0.5,
            floorcast_version: "0".into(),
            stored_unix_s: 1.0,
        }
    }

    /// A failing job (its attempts), a job that succeeded after failing (marked), a failed row
    /// of an older store (its one attempt) and an ok job (not listed); the stderr's head and
    /// tail.
    #[test]
    fn failed_and_recovered_jobs_are_listed_with_their_attempts() {
        let mut ok = floorcast_stats::fixtures::stored("b", "ok", 1, 100.0);
        ok.job_id = "ok".into();
        let mut recovered = floorcast_stats::fixtures::stored("b", "recovered", 1, 100.0);
        recovered.job_id = "recovered".into();
        let mut failing = recovered.clone();
        failing.job_id = "failing".into();
        failing.label = "failing".into();
        failing.status = JobStatus::Failed;
        failing.error = Some("boom 2".into());
        let mut old = failing.clone();
        old.job_id = "old".into();
        old.label = "old".into();
        old.stderr_tail = None;
        let lines: Vec<String> = (1..=30).map(|i| format!("line {i}")).collect();
        let failures = vec![
            failure("failing", 1, None),
            failure("failing", 2, Some(&lines.join("\n"))),
            failure("recovered", 1, Some("Traceback\nValueError: x\n")),
        ];
        let mut rows = [ok, recovered, failing, old];
        for r in &mut rows {
            r.strategy = "baseline".into();
        }
        let jobs = failed_jobs(&rows, &failures);
        let got: Vec<(&str, Now, usize)> = jobs
            .iter()
            .map(|j| (j.job_id.as_str(), j.now, j.attempts.len()))
            .collect();
        assert_eq!(
            got,
            [
                ("failing", Now::Failed, 2),
                ("old", Now::Failed, 1),
                ("recovered", Now::Succeeded, 1)
            ]
        );
        let text = render(&jobs);
        assert!(text.starts_with("failures: 2 job(s) failing, 1 job(s) failed before they succeeded (4 failed attempts in all)"), "{text}");
        for want in [
            "b failing (strategy baseline) seed 1: failed, 2 attempt(s):",
            "  attempt 2 (worker local-0, 0.5 s): boom 2",
            "    | line 5\n    | ... (15 lines)\n    | line 21\n",
            "    | line 30\n",
            "    | line 30\n  (the stderr of 1 earlier attempt(s) differs: `report --json FILE` holds each)\n",
            "b recovered (strategy baseline) seed 1: later succeeded (attempt 2); earlier failures:",
            "    | ValueError: x\n",
            "b old (strategy baseline) seed 1: failed, 1 attempt(s):\n  attempt 1 (worker w, 1.0 s): boom 2\n  stderr: none stored",
        ] {
            assert!(text.contains(want), "{want:?} missing from:\n{text}");
        }
        assert!(!text.contains("line 6\n"), "{text}");
        assert_eq!(
            text.matches("earlier attempt(s) differs").count(),
            1,
            "{text}"
        );
        let json = to_json(&jobs);
        assert_eq!(json[0]["attempts"][1]["stderr_lines"], 30);
        assert_eq!(json[0]["attempts"][1]["stderr_tail"][9], "line 30");
        assert_eq!(json[2]["later_succeeded"], true);
        assert_eq!(render(&[]), "failures: none (no job failed)\n");
    }
}
