//! The job scheduler as a deterministic state machine: `handle(event, now) -> actions`.
//!
//! Pull-based: a worker asks for a job when it has a free slot and gets one with a lease. A
//! worker that leaves (its liveliness token dropped) or whose lease expires gives its jobs back
//! to the queue. Delivery is at-least-once, so results are deduplicated by job id: the first
//! result of a job is stored, every later one is acknowledged and discarded.

use std::collections::{BTreeMap, BTreeSet, VecDeque};

/// A job's identity (a hash of everything that determines its result).
pub type JobId = String;
/// A worker's identity (its zenoh id or a local name).
pub type WorkerId = String;

/// Something that happened, as the transport saw it.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    WorkerJoined(WorkerId),
    WorkerLeft(WorkerId),
    /// A worker asks for one job.
    JobRequested(WorkerId),
    /// A worker returns the result of a job.
    ResultSubmitted {
        worker: WorkerId,
        job: JobId,
    },
    /// A worker still runs a job: extend its lease.
    LeaseRenewed {
        worker: WorkerId,
        job: JobId,
    },
    /// Time passes (check leases).
    Tick,
}

/// What the transport must do.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Answer the request of `worker` with `job`, leased until `deadline_s`.
    Lease {
        worker: WorkerId,
        job: JobId,
        deadline_s: f64,
    },
    /// Answer the request: nothing to hand out now, ask again later.
    Wait { worker: WorkerId },
    /// Answer the request: the grid is complete, the worker may leave.
    Done { worker: WorkerId },
    /// Store this result durably, then acknowledge it.
    Store { worker: WorkerId, job: JobId },
    /// Acknowledge without storing (duplicate or late result of a job already stored).
    AckDuplicate { worker: WorkerId, job: JobId },
    /// Refuse a result for a job that is not part of this grid.
    RejectUnknown { worker: WorkerId, job: JobId },
    /// A job went back to the queue (for logs and progress).
    Requeued {
        job: JobId,
        worker: WorkerId,
        reason: RequeueReason,
    },
    /// The lease of `job` now runs until `deadline_s`.
    Renewed {
        worker: WorkerId,
        job: JobId,
        deadline_s: f64,
    },
    /// `job` is not leased to `worker` (requeued meanwhile, or already stored).
    NotLeased { worker: WorkerId, job: JobId },
    /// Every job is stored.
    Finished,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RequeueReason {
    WorkerLeft,
    LeaseExpired,
}

#[derive(Debug, Clone, PartialEq)]
struct Lease {
    worker: WorkerId,
    deadline_s: f64,
}

/// Scheduler state.
#[derive(Debug, Clone)]
pub struct Scheduler {
    lease_s: f64,
    pending: VecDeque<JobId>,
    leased: BTreeMap<JobId, Lease>,
    done: BTreeSet<JobId>,
    all: BTreeSet<JobId>,
    workers: BTreeSet<WorkerId>,
    finished_announced: bool,
}

impl Scheduler {
    /// A scheduler for `jobs` (in the order to hand them out), of which `already_done` are stored
    /// from an earlier run. Leases last `lease_s` seconds.
    pub fn new(jobs: Vec<JobId>, already_done: &BTreeSet<JobId>, lease_s: f64) -> Self {
        let all: BTreeSet<JobId> = jobs.iter().cloned().collect();
        let mut seen = BTreeSet::new();
        let pending = jobs
            .into_iter()
            .filter(|j| !already_done.contains(j) && seen.insert(j.clone()))
            .collect();
        let done = already_done.intersection(&all).cloned().collect();
        Self {
            lease_s,
            pending,
            leased: BTreeMap::new(),
            done,
            all,
            workers: BTreeSet::new(),
            finished_announced: false,
        }
    }

    pub fn total(&self) -> usize {
        self.all.len()
    }
    pub fn done(&self) -> usize {
        self.done.len()
    }
    pub fn running(&self) -> usize {
        self.leased.len()
    }
    pub fn pending(&self) -> usize {
        self.pending.len()
    }
    pub fn is_finished(&self) -> bool {
        self.done.len() == self.all.len()
    }
    pub fn workers(&self) -> impl Iterator<Item = &WorkerId> {
        self.workers.iter()
    }
    /// The running jobs and who runs them.
    pub fn leases(&self) -> impl Iterator<Item = (&JobId, &WorkerId)> {
        self.leased.iter().map(|(j, l)| (j, &l.worker))
    }

    /// Feeds one event at time `now_s`; returns what to do, in order.
    pub fn handle(&mut self, event: Event, now_s: f64) -> Vec<Action> {
        let mut out = Vec::new();
        match event {
            Event::WorkerJoined(w) => {
                self.workers.insert(w);
            }
            Event::WorkerLeft(w) => {
                self.workers.remove(&w);
                self.requeue_where(|l| l.worker == w, RequeueReason::WorkerLeft, &mut out);
            }
            Event::JobRequested(w) => {
                // A request also proves the worker is alive.
                self.workers.insert(w.clone());
                self.expire(now_s, &mut out);
                if let Some(job) = self.pending.pop_front() {
                    let deadline_s = now_s + self.lease_s;
                    self.leased.insert(
                        job.clone(),
                        Lease {
                            worker: w.clone(),
                            deadline_s,
                        },
                    );
                    out.push(Action::Lease {
                        worker: w,
                        job,
                        deadline_s,
                    });
                } else if self.is_finished() {
                    out.push(Action::Done { worker: w });
                } else {
                    out.push(Action::Wait { worker: w });
                }
            }
            Event::ResultSubmitted { worker, job } => {
                if !self.all.contains(&job) {
                    out.push(Action::RejectUnknown { worker, job });
                } else if self.done.contains(&job) {
                    out.push(Action::AckDuplicate { worker, job });
                } else {
                    // First result of this job, from whoever ran it (results are deterministic).
                    self.leased.remove(&job);
                    self.pending.retain(|j| j != &job);
                    self.done.insert(job.clone());
                    out.push(Action::Store { worker, job });
                }
            }
            Event::LeaseRenewed { worker, job } => {
                self.expire(now_s, &mut out);
                match self.leased.get_mut(&job) {
                    Some(l) if l.worker == worker => {
                        l.deadline_s = now_s + self.lease_s;
                        out.push(Action::Renewed {
                            worker,
                            job,
                            deadline_s: l.deadline_s,
                        });
                    }
                    _ => out.push(Action::NotLeased { worker, job }),
                }
            }
            Event::Tick => self.expire(now_s, &mut out),
        }
        if self.is_finished() && !self.finished_announced {
            self.finished_announced = true;
            out.push(Action::Finished);
        }
        out
    }

    fn expire(&mut self, now_s: f64, out: &mut Vec<Action>) {
        self.requeue_where(|l| l.deadline_s <= now_s, RequeueReason::LeaseExpired, out);
    }

    fn requeue_where(
        &mut self,
        pred: impl Fn(&Lease) -> bool,
        reason: RequeueReason,
        out: &mut Vec<Action>,
    ) {
        let gone: Vec<JobId> = self
            .leased
            .iter()
            .filter(|(_, l)| pred(l))
            .map(|(j, _)| j.clone())
            .collect();
        // Requeued jobs go to the front, in id order, so they finish soon.
        for job in gone.into_iter().rev() {
            let lease = self.leased.remove(&job).expect("listed above");
            self.pending.push_front(job.clone());
            out.push(Action::Requeued {
                job,
                worker: lease.worker,
                reason,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    fn ids(n: usize) -> Vec<JobId> {
        (0..n).map(|i| format!("job{i:03}")).collect()
    }

    #[test]
    fn hands_out_each_job_once_and_finishes() {
        let mut s = Scheduler::new(ids(2), &BTreeSet::new(), 60.0);
        let a = s.handle(Event::JobRequested("w1".into()), 0.0);
        assert!(matches!(&a[..], [Action::Lease { job, .. }] if job == "job000"));
        let b = s.handle(Event::JobRequested("w2".into()), 0.0);
        assert!(matches!(&b[..], [Action::Lease { job, .. }] if job == "job001"));
        assert!(matches!(
            &s.handle(Event::JobRequested("w3".into()), 0.0)[..],
            [Action::Wait { .. }]
        ));
        let r = s.handle(
            Event::ResultSubmitted {
                worker: "w1".into(),
                job: "job000".into(),
            },
            1.0,
        );
        assert!(matches!(&r[..], [Action::Store { .. }]));
        let r = s.handle(
            Event::ResultSubmitted {
                worker: "w2".into(),
                job: "job001".into(),
            },
            1.0,
        );
        assert!(matches!(&r[..], [Action::Store { .. }, Action::Finished]));
        assert!(matches!(
            &s.handle(Event::JobRequested("w1".into()), 2.0)[..],
            [Action::Done { .. }]
        ));
    }

    #[test]
    fn a_worker_leaving_requeues_its_job_and_late_results_are_discarded() {
        let mut s = Scheduler::new(ids(1), &BTreeSet::new(), 60.0);
        s.handle(Event::JobRequested("w1".into()), 0.0);
        let a = s.handle(Event::WorkerLeft("w1".into()), 1.0);
        assert!(matches!(
            &a[..],
            [Action::Requeued {
                reason: RequeueReason::WorkerLeft,
                ..
            }]
        ));
        let a = s.handle(Event::JobRequested("w2".into()), 2.0);
        assert!(matches!(&a[..], [Action::Lease { worker, .. }] if worker == "w2"));
        s.handle(
            Event::ResultSubmitted {
                worker: "w2".into(),
                job: "job000".into(),
            },
            3.0,
        );
        // The first worker comes back and submits too: acknowledged, not stored.
        let a = s.handle(
            Event::ResultSubmitted {
                worker: "w1".into(),
                job: "job000".into(),
            },
            4.0,
        );
        assert!(matches!(&a[..], [Action::AckDuplicate { .. }]));
        let a = s.handle(
            Event::ResultSubmitted {
                worker: "w1".into(),
                job: "nope".into(),
            },
            4.0,
        );
        assert!(matches!(&a[..], [Action::RejectUnknown { .. }]));
    }

    #[test]
    fn expired_leases_are_requeued() {
        let mut s = Scheduler::new(ids(1), &BTreeSet::new(), 10.0);
        s.handle(Event::JobRequested("w1".into()), 0.0);
        assert!(s.handle(Event::Tick, 9.0).is_empty());
        let a = s.handle(Event::Tick, 10.0);
        assert!(matches!(
            &a[..],
            [Action::Requeued {
                reason: RequeueReason::LeaseExpired,
                ..
            }]
        ));
        assert_eq!(s.pending(), 1);
    }

    #[test]
    fn renewals_keep_a_lease_alive_only_for_its_holder() {
        let mut s = Scheduler::new(ids(1), &BTreeSet::new(), 10.0);
        s.handle(Event::JobRequested("w1".into()), 0.0);
        let renew = |s: &mut Scheduler, w: &str, now| {
            s.handle(
                Event::LeaseRenewed {
                    worker: w.into(),
                    job: "job000".into(),
                },
                now,
            )
        };
        assert!(
            matches!(&renew(&mut s, "w1", 8.0)[..], [Action::Renewed { deadline_s, .. }] if *deadline_s == 18.0)
        );
        assert!(
            s.handle(Event::Tick, 15.0).is_empty(),
            "renewed lease holds"
        );
        assert!(matches!(
            &renew(&mut s, "w2", 16.0)[..],
            [Action::NotLeased { .. }]
        ));
        // Not renewed in time: requeued, and a late renewal is refused.
        let a = renew(&mut s, "w1", 30.0);
        assert!(
            matches!(&a[..], [Action::Requeued { .. }, Action::NotLeased { .. }]),
            "{a:?}"
        );
    }

    #[test]
    fn resumes_from_stored_results() {
        let done: BTreeSet<JobId> = ["job000".to_string()].into();
        let mut s = Scheduler::new(ids(2), &done, 10.0);
        assert_eq!((s.total(), s.done(), s.pending()), (2, 1, 1));
        let a = s.handle(Event::JobRequested("w".into()), 0.0);
        assert!(matches!(&a[..], [Action::Lease { job, .. }] if job == "job001"));
    }

    #[derive(Debug, Clone)]
    enum Step {
        Request(u8),
        Submit(u8),
        Leave(u8),
        Renew(u8),
        Tick(u8),
    }

    fn step() -> impl Strategy<Value = Step> {
        prop_oneof![
            4 => (0u8..4).prop_map(Step::Request),
            4 => (0u8..4).prop_map(Step::Submit),
            1 => (0u8..4).prop_map(Step::Leave),
            2 => (0u8..4).prop_map(Step::Renew),
            1 => (0u8..30).prop_map(Step::Tick),
        ]
    }

    proptest! {
        /// Under any interleaving of requests, results, departures and lease expiries, every job
        /// is stored exactly once, and the grid completes once workers keep working.
        #[test]
        fn every_job_is_stored_exactly_once(n in 1usize..12, steps in proptest::collection::vec(step(), 0..200)) {
            let mut s = Scheduler::new(ids(n), &BTreeSet::new(), 20.0);
            let mut now = 0.0;
            // What each worker holds (it may keep holding a job after it "left": a late result).
            let mut held: BTreeMap<u8, Vec<JobId>> = BTreeMap::new();
            let mut stored: BTreeMap<JobId, usize> = BTreeMap::new();
            let mut apply = |s: &mut Scheduler, e: Event, now: f64, held: &mut BTreeMap<u8, Vec<JobId>>| {
                for a in s.handle(e, now) {
                    match a {
                        Action::Lease { worker, job, .. } => {
                            held.entry(worker[1..].parse().unwrap()).or_default().push(job)
                        }
                        Action::Store { job, .. } => *stored.entry(job).or_default() += 1,
                        _ => {}
                    }
                }
            };
            for st in steps {
                now += 1.0;
                match st {
                    Step::Request(w) => apply(&mut s, Event::JobRequested(format!("w{w}")), now, &mut held),
                    Step::Submit(w) => {
                        if let Some(job) = held.get_mut(&w).and_then(|v| v.pop()) {
                            apply(&mut s, Event::ResultSubmitted { worker: format!("w{w}"), job }, now, &mut held);
                        }
                    }
                    Step::Leave(w) => apply(&mut s, Event::WorkerLeft(format!("w{w}")), now, &mut held),
                    Step::Renew(w) => {
                        if let Some(job) = held.get(&w).and_then(|v| v.last()).cloned() {
                            apply(&mut s, Event::LeaseRenewed { worker: format!("w{w}"), job }, now, &mut held);
                        }
                    }
                    Step::Tick(dt) => { now += dt as f64; apply(&mut s, Event::Tick, now, &mut held) }
                }
            }
            // Then the other workers hang (their leases expire) and one reliable worker drains
            // the grid.
            now += 100.0;
            apply(&mut s, Event::Tick, now, &mut held);
            for _ in 0..(3 * n + 3) {
                now += 1.0;
                apply(&mut s, Event::JobRequested("w9".into()), now, &mut held);
                if let Some(job) = held.get_mut(&9).and_then(|v| v.pop()) {
                    apply(&mut s, Event::ResultSubmitted { worker: "w9".into(), job }, now, &mut held);
                }
            }
            prop_assert!(s.is_finished());
            prop_assert_eq!(stored.len(), n);
            prop_assert!(stored.values().all(|&c| c == 1), "{:?}", stored);
        }
    }
}
