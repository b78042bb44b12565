//! The job scheduler as a deterministic state machine: one method per thing that happens, each
//! returning its typed answer and the [`Note`]s of what happened meanwhile.
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

/// The answer to a worker's request for a job.
#[derive(Debug, Clone, PartialEq)]
pub enum Grant {
    /// Run `job`, leased until `deadline_s`.
    Lease { job: JobId, deadline_s: f64 },
    /// Nothing to hand out now, ask again later.
    Wait,
    /// The grid is complete, the worker may leave.
    Done,
}

/// What to do with a submitted result.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// The job's first result: store it durably, then acknowledge it.
    Store,
    /// Acknowledge without storing (a duplicate or late result of a job already stored).
    Duplicate,
    /// Refuse it: the job is not part of this grid.
    Unknown,
}

/// The answer to a lease renewal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Renewal {
    /// The lease now runs until `deadline_s`.
    Renewed { deadline_s: f64 },
    /// The job is not leased to this worker (requeued meanwhile, or already stored).
    NotLeased,
}

/// What happened meanwhile, for logs and progress.
#[derive(Debug, Clone, PartialEq)]
pub enum Note {
    /// A job went back to the queue.
    Requeued {
        job: JobId,
        worker: WorkerId,
        reason: RequeueReason,
    },
    /// Every job is stored.
    Finished,
}

/// An answer and the notes of what happened while it was made.
#[derive(Debug, Clone, PartialEq)]
pub struct Reply<T> {
    pub answer: T,
    pub notes: Vec<Note>,
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
    /// More jobs may be added (a sequential grid between batches): workers wait, not leave.
    more_to_come: bool,
    /// Stored jobs whose results are being verified: the grid is not finished before they are
    /// released (they may be reopened).
    held: BTreeSet<JobId>,
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
            more_to_come: false,
            held: BTreeSet::new(),
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
    /// Every job is stored, none is held and no more will come.
    pub fn is_finished(&self) -> bool {
        self.batch_complete() && !self.more_to_come && self.held.is_empty()
    }
    /// Every job added so far is stored.
    pub fn batch_complete(&self) -> bool {
        self.done.len() == self.all.len()
    }
    /// Whether more jobs may be added ([`Scheduler::add`]): until told otherwise, a worker
    /// without a job waits instead of leaving.
    pub fn expect_more(&mut self, more: bool) {
        self.more_to_come = more;
    }
    /// Adds jobs (in the order to hand them out); those in `already_done` count as stored.
    pub fn add(&mut self, jobs: Vec<JobId>, already_done: &BTreeSet<JobId>) {
        for j in jobs {
            if self.all.insert(j.clone()) {
                if already_done.contains(&j) {
                    self.done.insert(j);
                } else {
                    self.pending.push_back(j);
                }
            }
        }
    }
    /// Holds `job` (before its result is submitted): while its result is being verified, the
    /// grid does not finish and workers wait instead of leaving.
    pub fn hold(&mut self, job: &str) {
        self.held.insert(job.to_string());
    }
    /// Releases a held job (its result verified, or not stored after all).
    pub fn release(&mut self, job: &str) {
        self.held.remove(job);
    }
    /// Jobs being verified.
    pub fn held(&self) -> usize {
        self.held.len()
    }
    /// Stored jobs whose results were discarded: back to the front of the queue (released if
    /// held), to be run again.
    pub fn reopen(&mut self, jobs: &[JobId]) {
        for j in jobs.iter().rev() {
            if self.done.remove(j) {
                self.held.remove(j);
                self.pending.push_front(j.clone());
                self.finished_announced = false;
            }
        }
    }
    pub fn workers(&self) -> impl Iterator<Item = &WorkerId> {
        self.workers.iter()
    }
    /// The running jobs and who runs them.
    pub fn leases(&self) -> impl Iterator<Item = (&JobId, &WorkerId)> {
        self.leased.iter().map(|(j, l)| (j, &l.worker))
    }

    /// A worker joined.
    pub fn joined(&mut self, worker: WorkerId) {
        self.workers.insert(worker);
    }

    /// A worker left: its jobs go back to the queue.
    pub fn left(&mut self, worker: &str) -> Vec<Note> {
        self.workers.remove(worker);
        let mut notes = Vec::new();
        self.requeue_where(
            |l| l.worker == worker,
            RequeueReason::WorkerLeft,
            &mut notes,
        );
        notes
    }

    /// A worker asks for one job at time `now_s` (a request also proves it is alive).
    pub fn request(&mut self, worker: WorkerId, now_s: f64) -> Reply<Grant> {
        let mut notes = Vec::new();
        self.workers.insert(worker.clone());
        self.expire(now_s, &mut notes);
        let answer = if let Some(job) = self.pending.pop_front() {
            let deadline_s = now_s + self.lease_s;
            self.leased
                .insert(job.clone(), Lease { worker, deadline_s });
            Grant::Lease { job, deadline_s }
        } else if self.is_finished() {
            Grant::Done
        } else {
            Grant::Wait
        };
        self.reply(answer, notes)
    }

    /// Leases `job` to `worker` too if it is still waiting (a job that shares its beginning with
    /// one the worker was just given: see `run::partners`). Returns whether it did.
    pub fn claim(&mut self, worker: &str, job: &str, now_s: f64) -> bool {
        let Some(k) = self.pending.iter().position(|j| j == job) else {
            return false;
        };
        let job = self.pending.remove(k).expect("found");
        let deadline_s = now_s + self.lease_s;
        self.leased.insert(
            job,
            Lease {
                worker: worker.to_string(),
                deadline_s,
            },
        );
        true
    }

    /// A worker returns the result of `job`.
    pub fn submit(&mut self, job: &str) -> Reply<Verdict> {
        let answer = if !self.all.contains(job) {
            Verdict::Unknown
        } else if self.done.contains(job) {
            Verdict::Duplicate
        } else {
            // First result of this job, from whoever ran it (results are deterministic).
            self.leased.remove(job);
            self.pending.retain(|j| j != job);
            self.done.insert(job.to_string());
            Verdict::Store
        };
        self.reply(answer, Vec::new())
    }

    /// A worker still runs `job` at time `now_s`: extend its lease if it holds it.
    pub fn renew(&mut self, worker: &str, job: &str, now_s: f64) -> Reply<Renewal> {
        let mut notes = Vec::new();
        self.expire(now_s, &mut notes);
        let answer = match self.leased.get_mut(job) {
            Some(l) if l.worker == worker => {
                l.deadline_s = now_s + self.lease_s;
                Renewal::Renewed {
                    deadline_s: l.deadline_s,
                }
            }
            _ => Renewal::NotLeased,
        };
        self.reply(answer, notes)
    }

    /// Time passes: leases past their deadline are requeued.
    pub fn tick(&mut self, now_s: f64) -> Vec<Note> {
        let mut notes = Vec::new();
        self.expire(now_s, &mut notes);
        self.reply((), notes).notes
    }

    /// `answer` with `notes` and, the first time every job is stored, [`Note::Finished`].
    fn reply<T>(&mut self, answer: T, mut notes: Vec<Note>) -> Reply<T> {
        if self.is_finished() && !self.finished_announced {
            self.finished_announced = true;
            notes.push(Note::Finished);
        }
        Reply { answer, notes }
    }

    fn expire(&mut self, now_s: f64, notes: &mut Vec<Note>) {
        self.requeue_where(
            |l| l.deadline_s <= now_s,
            RequeueReason::LeaseExpired,
            notes,
        );
    }

    fn requeue_where(
        &mut self,
        pred: impl Fn(&Lease) -> bool,
        reason: RequeueReason,
        notes: &mut Vec<Note>,
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
            notes.push(Note::Requeued {
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

    /// A held job keeps the grid open (workers wait); released, the grid finishes; a reopened
    /// job is handed out again and finishes the grid once more.
    #[test]
    fn held_jobs_keep_the_grid_open_and_reopened_ones_run_again() {
        let mut s = Scheduler::new(ids(2), &BTreeSet::new(), 60.0);
        for _ in 0..2 {
            let r = s.request("w1".into(), 0.0);
            assert!(matches!(r.answer, Grant::Lease { .. }));
        }
        s.hold("job001");
        assert_eq!(s.submit("job000").answer, Verdict::Store);
        let r = s.submit("job001");
        assert_eq!((r.answer, r.notes), (Verdict::Store, vec![]));
        assert_eq!(s.held(), 1);
        assert_eq!(s.request("w2".into(), 1.0).answer, Grant::Wait);
        s.reopen(&["job000".to_string()]);
        s.release("job001");
        assert!(!s.is_finished());
        let r = s.request("w2".into(), 1.0);
        assert!(matches!(&r.answer, Grant::Lease { job, .. } if job == "job000"));
        let r = s.submit("job000");
        assert_eq!((r.answer, r.notes), (Verdict::Store, vec![Note::Finished]));
        assert_eq!(s.request("w2".into(), 2.0).answer, Grant::Done);
    }

    #[test]
    fn hands_out_each_job_once_and_finishes() {
        let mut s = Scheduler::new(ids(2), &BTreeSet::new(), 60.0);
        let a = s.request("w1".into(), 0.0);
        assert!(matches!(&a.answer, Grant::Lease { job, .. } if job == "job000"));
        let b = s.request("w2".into(), 0.0);
        assert!(matches!(&b.answer, Grant::Lease { job, .. } if job == "job001"));
        assert_eq!(s.request("w3".into(), 0.0).answer, Grant::Wait);
        let r = s.submit("job000");
        assert_eq!((r.answer, r.notes), (Verdict::Store, vec![]));
        let r = s.submit("job001");
        assert_eq!((r.answer, r.notes), (Verdict::Store, vec![Note::Finished]));
        let r = s.request("w1".into(), 2.0);
        assert_eq!((r.answer, r.notes), (Grant::Done, vec![]));
    }

    #[test]
    fn a_worker_leaving_requeues_its_job_and_late_results_are_discarded() {
        let mut s = Scheduler::new(ids(1), &BTreeSet::new(), 60.0);
        s.request("w1".into(), 0.0);
        let notes = s.left("w1");
        assert!(matches!(
            &notes[..],
            [Note::Requeued {
                reason: RequeueReason::WorkerLeft,
                ..
            }]
        ));
        assert_eq!(s.workers().count(), 0);
        let a = s.request("w2".into(), 2.0);
        assert!(matches!(&a.answer, Grant::Lease { job, .. } if job == "job000"));
        assert_eq!(s.leases().next().map(|(_, w)| w.as_str()), Some("w2"));
        assert_eq!(s.submit("job000").answer, Verdict::Store);
        // The first worker comes back and submits too: acknowledged, not stored.
        assert_eq!(s.submit("job000").answer, Verdict::Duplicate);
        assert_eq!(s.submit("nope").answer, Verdict::Unknown);
    }

    #[test]
    fn expired_leases_are_requeued() {
        let mut s = Scheduler::new(ids(1), &BTreeSet::new(), 10.0);
        s.request("w1".into(), 0.0);
        assert!(s.tick(9.0).is_empty());
        assert!(matches!(
            &s.tick(10.0)[..],
            [Note::Requeued {
                reason: RequeueReason::LeaseExpired,
                ..
            }]
        ));
        assert_eq!(s.pending(), 1);
    }

    #[test]
    fn renewals_keep_a_lease_alive_only_for_its_holder() {
        let mut s = Scheduler::new(ids(1), &BTreeSet::new(), 10.0);
        s.request("w1".into(), 0.0);
        assert_eq!(
            s.renew("w1", "job000", 8.0).answer,
            Renewal::Renewed { deadline_s: 18.0 }
        );
        assert!(s.tick(15.0).is_empty(), "renewed lease holds");
        assert_eq!(s.renew("w2", "job000", 16.0).answer, Renewal::NotLeased);
        // Not renewed in time: requeued, and a late renewal is refused.
        let r = s.renew("w1", "job000", 30.0);
        assert_eq!(r.answer, Renewal::NotLeased);
        assert!(matches!(&r.notes[..], [Note::Requeued { .. }]), "{r:?}");
    }

    #[test]
    fn resumes_from_stored_results() {
        let done: BTreeSet<JobId> = ["job000".to_string()].into();
        let mut s = Scheduler::new(ids(2), &done, 10.0);
        assert_eq!((s.total(), s.done(), s.pending()), (2, 1, 1));
        let a = s.request("w".into(), 0.0);
        assert!(matches!(&a.answer, Grant::Lease { job, .. } if job == "job001"));
    }

    #[derive(Debug, Clone)]
    enum Step {
        Request(u8),
        Submit(u8),
        Leave(u8),
        Renew(u8),
        Tick(u8),
        /// A worker also takes a waiting job (one sharing its beginning with its own).
        Claim(u8, u8),
    }

    fn step() -> impl Strategy<Value = Step> {
        prop_oneof![
            4 => (0u8..4).prop_map(Step::Request),
            4 => (0u8..4).prop_map(Step::Submit),
            1 => (0u8..4).prop_map(Step::Leave),
            2 => (0u8..4).prop_map(Step::Renew),
            1 => (0u8..30).prop_map(Step::Tick),
            2 => (0u8..4, 0u8..12).prop_map(|(w, j)| Step::Claim(w, j)),
        ]
    }

    proptest! {
        /// Under any interleaving of requests, claims, results, departures and lease expiries,
        /// every job is stored exactly once, and the grid completes once workers keep working.
        #[test]
        fn every_job_is_stored_exactly_once(n in 1usize..12, steps in proptest::collection::vec(step(), 0..200)) {
            let mut s = Scheduler::new(ids(n), &BTreeSet::new(), 20.0);
            let mut now = 0.0;
            // What each worker holds (it may keep holding a job after it "left": a late result).
            let mut held: BTreeMap<u8, Vec<JobId>> = BTreeMap::new();
            let mut stored: BTreeMap<JobId, usize> = BTreeMap::new();
            let request = |s: &mut Scheduler, w: u8, now: f64, held: &mut BTreeMap<u8, Vec<JobId>>| {
                if let Grant::Lease { job, .. } = s.request(format!("w{w}"), now).answer {
                    held.entry(w).or_default().push(job);
                }
            };
            let mut submit = |s: &mut Scheduler, w: u8, held: &mut BTreeMap<u8, Vec<JobId>>| {
                if let Some(job) = held.get_mut(&w).and_then(|v| v.pop()) {
                    if s.submit(&job).answer == Verdict::Store {
                        *stored.entry(job).or_default() += 1;
                    }
                }
            };
            for st in steps {
                now += 1.0;
                match st {
                    Step::Request(w) => request(&mut s, w, now, &mut held),
                    Step::Submit(w) => submit(&mut s, w, &mut held),
                    Step::Leave(w) => { s.left(&format!("w{w}")); }
                    Step::Renew(w) => {
                        if let Some(job) = held.get(&w).and_then(|v| v.last()).cloned() {
                            s.renew(&format!("w{w}"), &job, now);
                        }
                    }
                    Step::Tick(dt) => { now += dt as f64; s.tick(now); }
                    Step::Claim(w, j) => {
                        let job = format!("job{:03}", j as usize % n);
                        if s.claim(&format!("w{w}"), &job, now) {
                            held.entry(w).or_default().push(job);
                        }
                    }
                }
            }
            // Then the other workers hang (their leases expire) and one reliable worker drains
            // the grid.
            now += 100.0;
            s.tick(now);
            for _ in 0..(3 * n + 3) {
                now += 1.0;
                request(&mut s, 9, now, &mut held);
                submit(&mut s, 9, &mut held);
            }
            prop_assert!(s.is_finished());
            prop_assert_eq!(stored.len(), n);
            prop_assert!(stored.values().all(|&c| c == 1), "{:?}", stored);
        }
    }
}
