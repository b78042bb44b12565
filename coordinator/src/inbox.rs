//! The inbox contract: what workers, embedded threads or a network bridge alike, tell the
//! coordinator loop of [`crate::run`], and how remote workers are let in. The loop knows workers
//! only through these messages; a transport (`net.rs`, zenoh) implements [`RemoteWorkers`] and
//! is handed to [`crate::run::run_plan`] by its caller, so the loop never names a transport.

use std::sync::{mpsc, Arc};

use tokio::sync::oneshot;

use crate::grid::{Plan, PlannedJob};
use crate::store::StoredResult;
use floorcast_worker::wire::{JobReport, RenewReply, SubmitReply};

/// What workers (embedded threads or the network bridge) tell the coordinator loop.
#[derive(Debug)]
pub(crate) enum Inbox {
    /// A worker asks for a job.
    Request {
        worker: String,
        reply: oneshot::Sender<Answer>,
    },
    /// A worker reports what job `job_id` gave.
    Submit {
        worker: String,
        job_id: String,
        report: Box<JobReport>,
        reply: oneshot::Sender<SubmitReply>,
    },
    /// A worker still runs `job`.
    Renew {
        worker: String,
        job: String,
        reply: oneshot::Sender<RenewReply>,
    },
    /// This machine re-ran `job`, whose result `worker` returned (see [`crate::verify`]):
    /// `outcome` says whether the two are identical.
    Verified {
        job: String,
        worker: String,
        ours: Box<StoredResult>,
        outcome: Result<(), String>,
    },
    Joined(String),
    Left(String),
    /// Something to show the user (a refused worker, a dropped message).
    Log(String),
}

/// The coordinator's answer to a request.
#[derive(Debug)]
pub(crate) enum Answer {
    Run(Box<PlannedJob>),
    /// Run these jobs together, the runs sharing their beginning (embedded workers only; see
    /// `run::partners`).
    RunShared(Vec<PlannedJob>),
    Wait,
    Done,
    /// The worker gets no more jobs (its results were found wrong): why.
    Refused(String),
}

/// Prefix of embedded workers' ids (refused for remote workers: embedded workers' leases are
/// renewed by the coordinator itself).
pub(crate) const LOCAL: &str = "local-";

/// The sending end of the coordinator loop's inbox, handed to a transport when it opens.
#[derive(Debug, Clone)]
pub struct InboxSender(pub(crate) mpsc::Sender<Inbox>);

/// A transport that lets remote workers take part in a run (`net.rs`: zenoh).
pub trait RemoteWorkers: Send + Sync {
    /// Starts accepting remote workers for `plan` (leases of `lease_s` seconds); what they say
    /// goes into `inbox`. The session lasts until [`RemoteSession::close`].
    fn open(
        &self,
        plan: Arc<Plan>,
        lease_s: f64,
        inbox: InboxSender,
    ) -> Result<Box<dyn RemoteSession>, Box<dyn std::error::Error + Send + Sync>>;
}

/// An open transport session (see [`RemoteWorkers::open`]).
pub trait RemoteSession {
    /// Where remote workers can connect, for the user.
    fn describe(&self) -> String;
    /// Ends the session; remote workers still connected see the coordinator leave.
    fn close(self: Box<Self>);
}
