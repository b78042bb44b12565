//! A running grid's state for the live view (`run --http`): the coordinator loop reports what
//! happens ([`Live`]'s methods, each a short lock); the HTTP thread takes a [`Status`] snapshot
//! whenever a page or `status.json` is asked for. Nothing here blocks the loop for longer than
//! a copy of a few counters.

use std::collections::{BTreeMap, VecDeque};
use std::sync::Mutex;
use std::time::{Instant, SystemTime, UNIX_EPOCH};

use serde::{Deserialize, Serialize};

use floorcast_stats::sprt::LabelTest;

/// `status.json`'s format name and version (docs/live-view.md).
pub const STATUS_FORMAT: &str = "floorcast-status";
pub const STATUS_VERSION: u32 = 1;
/// Failures kept for the view (the store keeps them all).
pub const MAX_FAILURES: usize = 100;
/// Log lines kept for the view.
pub const MAX_LOG: usize = 50;

/// A snapshot of a running grid, as `GET /status.json` serves it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Status {
    pub format: String,
    pub version: u32,
    pub grid: String,
    /// `running`, `making tours`, `complete` or `interrupted`.
    pub state: String,
    /// When the run started, seconds since 1970 (UTC).
    pub started_unix_s: f64,
    pub elapsed_s: f64,
    pub jobs: JobCounts,
    /// Seconds until the jobs planned now are done at this run's rate so far (none before the
    /// first result; a sequential grid may plan more).
    pub eta_s: Option<f64>,
    pub workers: Vec<WorkerStatus>,
    /// Jobs that failed in this run, newest last (at most [`MAX_FAILURES`]).
    pub failures: Vec<FailureStatus>,
    pub failures_total: usize,
    /// A sequential grid's tests, each label's LLR at every look.
    pub sequential: Vec<TestStatus>,
    /// The run's last log lines (workers joining and leaving, requeued jobs, failures).
    pub log: Vec<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct JobCounts {
    /// Jobs planned so far (a sequential grid adds batches).
    pub total: usize,
    /// Stored, this run's and earlier ones.
    pub done: usize,
    pub running: usize,
    /// Failed in this run.
    pub failed: usize,
    /// Neither stored nor running.
    pub left: usize,
    /// Stored before this run started.
    pub stored_before: usize,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorkerStatus {
    pub name: String,
    /// `local` (a thread of the coordinator) or `remote`.
    pub kind: String,
    /// Remote workers: connected now (left, or lost, otherwise).
    pub connected: bool,
    /// Results stored from it in this run, failed ones among them.
    pub jobs_done: usize,
    pub jobs_failed: usize,
    /// Results per hour since it was first seen.
    pub jobs_per_hour: f64,
    /// Seconds since its last message.
    pub last_contact_s: f64,
    /// The jobs it holds now.
    pub running: Vec<RunningJob>,
}

/// A job a worker holds.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunningJob {
    pub job_id: String,
    pub building: String,
    pub label: String,
    pub seed: u64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FailureStatus {
    pub job_id: String,
    pub building: String,
    pub label: String,
    pub seed: u64,
    pub worker: String,
    pub error: String,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TestStatus {
    pub label: String,
    pub reference: String,
    /// `H0`, `H1` or `undecided` (the last look's).
    pub decision: String,
    /// The LLR's bounds: H0 accepted at or below `lower`, H1 at or above `upper`.
    pub lower: f64,
    pub upper: f64,
    pub points: Vec<LlrPoint>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LlrPoint {
    pub through_seed: u64,
    pub pairs: usize,
    /// None before the test has enough pairs, or when infinite (outcomes without variance).
    pub llr: Option<f64>,
}

#[derive(Debug)]
struct Worker {
    kind: &'static str,
    connected: bool,
    first_seen: Instant,
    last_contact: Instant,
    done: usize,
    failed: usize,
}

#[derive(Debug)]
struct Inner {
    state: String,
    counts: Option<JobCounts>,
    done_at_start: Option<usize>,
    leases: Vec<(String, RunningJob)>,
    workers: BTreeMap<String, Worker>,
    failures: VecDeque<FailureStatus>,
    failures_total: usize,
    tests: Vec<LabelTest>,
    log: VecDeque<String>,
}

/// What the coordinator loop tells the live view.
#[derive(Debug)]
pub struct Live {
    grid: String,
    started: Instant,
    started_unix_s: f64,
    inner: Mutex<Inner>,
}

impl Live {
    pub fn new(grid: &str) -> Live {
        Live {
            grid: grid.to_string(),
            started: Instant::now(),
            started_unix_s: SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0.0, |d| d.as_secs_f64()),
            inner: Mutex::new(Inner {
                state: "running".into(),
                counts: None,
                done_at_start: None,
                leases: Vec::new(),
                workers: BTreeMap::new(),
                failures: VecDeque::new(),
                failures_total: 0,
                tests: Vec::new(),
                log: VecDeque::new(),
            }),
        }
    }

    fn with<R>(&self, f: impl FnOnce(&mut Inner) -> R) -> R {
        // A panic elsewhere while holding the lock leaves counters, never a broken invariant.
        let mut g = self.inner.lock().unwrap_or_else(|p| p.into_inner());
        f(&mut g)
    }

    /// The run's state word (`running`, `making tours`, `complete`, `interrupted`).
    pub fn set_state(&self, state: &str) {
        self.with(|i| i.state = state.to_string());
    }

    /// The loop's counts and the jobs leased now, as (worker, job).
    pub fn counts(&self, counts: JobCounts, leases: Vec<(String, RunningJob)>) {
        self.with(|i| {
            i.done_at_start.get_or_insert(counts.done);
            i.counts = Some(counts);
            i.leases = leases;
        });
    }

    /// A message from `worker` (`local` true for the coordinator's own threads).
    pub fn contact(&self, worker: &str, local: bool) {
        let now = Instant::now();
        self.with(|i| {
            let w = i.workers.entry(worker.to_string()).or_insert(Worker {
                kind: if local { "local" } else { "remote" },
                connected: true,
                first_seen: now,
                last_contact: now,
                done: 0,
                failed: 0,
            });
            w.last_contact = now;
            w.connected = true;
        });
    }

    /// A remote worker left (or was lost).
    pub fn left(&self, worker: &str) {
        self.with(|i| {
            if let Some(w) = i.workers.get_mut(worker) {
                w.connected = false;
            }
        });
    }

    /// A result of `worker` was stored; `failure` when the job failed.
    pub fn stored(&self, worker: &str, failure: Option<FailureStatus>) {
        self.with(|i| {
            if let Some(w) = i.workers.get_mut(worker) {
                w.done += 1;
                w.failed += usize::from(failure.is_some());
            }
            if let Some(f) = failure {
                i.failures_total += 1;
                i.failures.push_back(f);
                if i.failures.len() > MAX_FAILURES {
                    i.failures.pop_front();
                }
            }
        });
    }

    /// A sequential grid's tests so far (every look of every label).
    pub fn tests(&self, path: &[LabelTest]) {
        self.with(|i| {
            if i.tests.len() != path.len() {
                i.tests = path.to_vec();
            }
        });
    }

    pub fn log(&self, line: &str) {
        self.with(|i| {
            i.log.push_back(line.to_string());
            if i.log.len() > MAX_LOG {
                i.log.pop_front();
            }
        });
    }

    /// The state now.
    pub fn snapshot(&self) -> Status {
        let now = Instant::now();
        let elapsed_s = now.duration_since(self.started).as_secs_f64();
        self.with(|i| {
            let c = i.counts.unwrap_or_default();
            let done_now = c.done.saturating_sub(i.done_at_start.unwrap_or(c.done));
            let eta_s = (done_now > 0 && elapsed_s > 0.0)
                .then(|| (c.left + c.running) as f64 * elapsed_s / done_now as f64);
            let workers = i
                .workers
                .iter()
                .map(|(name, w)| {
                    let seen = now.duration_since(w.first_seen).as_secs_f64().max(1.0);
                    WorkerStatus {
                        name: name.clone(),
                        kind: w.kind.to_string(),
                        connected: w.connected,
                        jobs_done: w.done,
                        jobs_failed: w.failed,
                        jobs_per_hour: w.done as f64 * 3600.0 / seen,
                        last_contact_s: now.duration_since(w.last_contact).as_secs_f64(),
                        running: i
                            .leases
                            .iter()
                            .filter(|(lw, _)| lw == name)
                            .map(|(_, j)| j.clone())
                            .collect(),
                    }
                })
                .collect();
            Status {
                format: STATUS_FORMAT.into(),
                version: STATUS_VERSION,
                grid: self.grid.clone(),
                state: i.state.clone(),
                started_unix_s: self.started_unix_s,
                elapsed_s,
                jobs: c,
                eta_s,
                workers,
                failures: i.failures.iter().cloned().collect(),
                failures_total: i.failures_total,
                sequential: test_status(&i.tests),
                log: i.log.iter().cloned().collect(),
            }
        })
    }
}

/// Each label's looks, in the order the labels were first tested.
fn test_status(path: &[LabelTest]) -> Vec<TestStatus> {
    let mut out: Vec<TestStatus> = Vec::new();
    for t in path {
        let point = LlrPoint {
            through_seed: t.through_seed,
            pairs: t.state.pairs,
            llr: t.state.llr_if_any().filter(|l| l.is_finite()),
        };
        match out.iter_mut().find(|s| s.label == t.label) {
            Some(s) => {
                s.points.push(point);
                s.decision = t.state.decision.as_str().to_string();
                (s.lower, s.upper) = (t.state.lower, t.state.upper);
            }
            None => out.push(TestStatus {
                label: t.label.clone(),
                reference: t.reference.clone(),
                decision: t.state.decision.as_str().to_string(),
                lower: t.state.lower,
                upper: t.state.upper,
                points: vec![point],
            }),
        }
    }
    out
}

/// A stored result as a failure for the view, if it failed.
pub fn failure_of(r: &crate::store::StoredResult) -> Option<FailureStatus> {
    (!r.status.is_ok()).then(|| FailureStatus {
        job_id: r.job_id.clone(),
        building: r.building.clone(),
        label: r.label.clone(),
        seed: r.seed,
        worker: r.worker.clone(),
        error: floorcast_worker::text::shown(r.error.as_deref().unwrap_or(""), 2000),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use floorcast_stats::sprt::{Decision, SprtState};

    fn look(label: &str, seed: u64, pairs: usize, llr: f64, decision: Decision) -> LabelTest {
        LabelTest {
            label: label.into(),
            reference: "baseline".into(),
            through_seed: seed,
            state: SprtState {
                pairs,
                mean: 0.1,
                variance: 0.01,
                llr,
                lower: -2.9,
                upper: 2.9,
                decision,
            },
        }
    }

    fn counts(total: usize, done: usize, running: usize, failed: usize) -> JobCounts {
        JobCounts {
            total,
            done,
            running,
            failed,
            left: total - done - running,
            stored_before: 2,
        }
    }

    #[test]
    fn a_snapshot_counts_jobs_workers_failures_and_tests() {
        let live = Live::new("g");
        live.counts(counts(10, 2, 0, 0), vec![]);
        live.contact("local0", true);
        live.contact("w1", false);
        live.stored("local0", None);
        let f = FailureStatus {
            job_id: "j9".into(),
            building: "b".into(),
            label: "x".into(),
            seed: 9,
            worker: "w1".into(),
            error: "boom".into(),
        };
        live.stored("w1", Some(f.clone()));
        live.left("w1");
        let job = |id: &str| RunningJob {
            job_id: id.into(),
            building: "b".into(),
            label: "x".into(),
            seed: 5,
        };
        live.counts(
            counts(10, 4, 2, 1),
            vec![("local0".into(), job("j5")), ("local0".into(), job("j6"))],
        );
        live.tests(&[
            look("a", 10, 10, 0.5, Decision::Undecided),
            look("b", 10, 10, f64::INFINITY, Decision::H1),
            look("a", 20, 20, -3.0, Decision::H0),
        ]);
        for i in 0..MAX_LOG + 5 {
            live.log(&format!("line {i}"));
        }
        let s = live.snapshot();
        assert_eq!(
            s.jobs,
            JobCounts {
                total: 10,
                done: 4,
                running: 2,
                failed: 1,
                left: 4,
                stored_before: 2
            }
        );
        // 2 results in this run so far, 6 jobs to go.
        let eta = s.eta_s.unwrap();
        assert!(
            (eta - 3.0 * s.elapsed_s).abs() < 1e-9 * eta.max(1.0),
            "{eta}"
        );
        assert_eq!(s.workers.len(), 2);
        let (l, r) = (&s.workers[0], &s.workers[1]);
        assert_eq!(
            (l.name.as_str(), l.kind.as_str(), l.connected),
            ("local0", "local", true)
        );
        assert_eq!(l.running, [job("j5"), job("j6")]);
        assert_eq!(
            (r.name.as_str(), r.kind.as_str(), r.connected),
            ("w1", "remote", false)
        );
        assert_eq!(
            (r.jobs_done, r.jobs_failed, l.jobs_done, l.jobs_failed),
            (1, 1, 1, 0)
        );
        assert!(r.running.is_empty());
        assert_eq!((s.failures.clone(), s.failures_total), (vec![f], 1));
        assert_eq!(s.sequential.len(), 2);
        let a = &s.sequential[0];
        assert_eq!((a.label.as_str(), a.decision.as_str()), ("a", "H0"));
        let pts: Vec<(u64, usize, Option<f64>)> = a
            .points
            .iter()
            .map(|p| (p.through_seed, p.pairs, p.llr))
            .collect();
        assert_eq!(pts, [(10, 10, Some(0.5)), (20, 20, Some(-3.0))]);
        // An infinite LLR is no number in JSON: none.
        assert_eq!(s.sequential[1].points[0].llr, None);
        assert_eq!(s.log.len(), MAX_LOG);
        assert_eq!(s.log[0], "line 5");
        let json = serde_json::to_string(&s).unwrap();
        let back: Status = serde_json::from_str(&json).unwrap();
        assert_eq!(back, s);
    }

    #[test]
    fn no_eta_before_a_result_and_failures_are_bounded() {
        let live = Live::new("g");
        live.counts(counts(500, 3, 1, 0), vec![]);
        assert_eq!(live.snapshot().eta_s, None);
        live.contact("w", false);
        for i in 0..MAX_FAILURES + 7 {
            live.stored(
                "w",
                Some(FailureStatus {
                    job_id: format!("j{i}"),
                    building: "b".into(),
                    label: "x".into(),
                    seed: i as u64,
                    worker: "w".into(),
                    error: "e".into(),
                }),
            );
        }
        let s = live.snapshot();
        assert_eq!(
            (s.failures.len(), s.failures_total),
            (MAX_FAILURES, MAX_FAILURES + 7)
        );
        assert_eq!(s.failures[0].job_id, "j7");
        assert_eq!(s.workers[0].jobs_failed, MAX_FAILURES + 7);
    }
}
