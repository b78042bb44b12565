//! The vector environment's threads. A step of the vector environment is a round: every
//! environment has one input (a seed, an action); the calling thread (the GIL released) and
//! `threads - 1` threads that live as long as the environment take the environments one at a
//! time from a shared counter until none is left, so that a slow environment does not hold up
//! a fixed share of the others, and the threads' caches stay warm from round to round. An
//! environment's result depends on its own state only, never on the thread that steps it.

use crate::core::{Core, Out};
use crate::observe::Action;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::{Arc, Mutex, MutexGuard};

/// One environment's input in a round.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Input {
    /// Reset with this seed.
    Reset(u64),
    /// Step with this action.
    Step(Action),
}

/// The work of one round.
#[derive(Debug)]
struct Round {
    inputs: Vec<Mutex<Option<Input>>>,
    outputs: Vec<Mutex<Option<Result<Out, String>>>>,
    next: AtomicUsize,
}

/// A lock whose holder cannot have panicked (a core's panics are caught inside it), taken even
/// if it had.
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Takes environments from the round's counter and runs their inputs until none is left.
fn work(cores: &[Mutex<Core>], round: &Round) {
    loop {
        let i = round.next.fetch_add(1, Ordering::Relaxed);
        if i >= cores.len() {
            return;
        }
        let Some(input) = lock(&round.inputs[i]).take() else {
            continue;
        };
        let mut core = lock(&cores[i]);
        let out = match input {
            Input::Reset(seed) => core.reset(seed, None, None),
            Input::Step(a) => core.step(a),
        };
        *lock(&round.outputs[i]) = Some(out);
    }
}

/// A thread of the pool: one round per message, a message back when its part is done.
#[derive(Debug)]
struct Worker {
    tx: Sender<Arc<Round>>,
    /// (In a mutex: a Python object must be shareable between threads.)
    done: Mutex<Receiver<()>>,
}

/// The environments of a vector environment and its threads.
#[derive(Debug)]
pub(crate) struct Pool {
    cores: Arc<Vec<Mutex<Core>>>,
    workers: Vec<Worker>,
}

const GONE: &str = "internal: a thread of the vector environment ended";

impl Pool {
    /// `cores` stepped by the calling thread and `threads - 1` threads of the pool's own.
    pub(crate) fn new(cores: Vec<Core>, threads: usize) -> Result<Pool, String> {
        let cores = Arc::new(cores.into_iter().map(Mutex::new).collect::<Vec<_>>());
        let mut workers = Vec::new();
        for _ in 1..threads.min(cores.len()) {
            let (tx, rx) = channel::<Arc<Round>>();
            let (done_tx, done_rx) = channel();
            let mine = Arc::clone(&cores);
            floorcast_worker::spawn_thread(move || {
                while let Ok(round) = rx.recv() {
                    work(&mine, &round);
                    if done_tx.send(()).is_err() {
                        return;
                    }
                }
            })
            .map_err(|e| format!("threads: the system refused a thread: {e}"))?;
            workers.push(Worker {
                tx,
                done: Mutex::new(done_rx),
            });
        }
        Ok(Pool { cores, workers })
    }

    /// Runs one input per environment: the outcomes in order.
    pub(crate) fn round(&self, inputs: Vec<Input>) -> Result<Vec<Result<Out, String>>, String> {
        let n = inputs.len();
        let round = Arc::new(Round {
            inputs: inputs.into_iter().map(|i| Mutex::new(Some(i))).collect(),
            outputs: (0..n).map(|_| Mutex::new(None)).collect(),
            next: AtomicUsize::new(0),
        });
        let mut sent = 0;
        for w in &self.workers {
            if w.tx.send(Arc::clone(&round)).is_ok() {
                sent += 1;
            }
        }
        work(&self.cores, &round);
        for w in self.workers.iter().take(sent) {
            lock(&w.done).recv().map_err(|_| GONE.to_string())?;
        }
        round
            .outputs
            .iter()
            .map(|o| lock(o).take().ok_or_else(|| GONE.to_string()))
            .collect()
    }

    /// Each action checked against its environment's pending decision (on the calling
    /// thread: a check is cheap).
    pub(crate) fn check(&self, actions: &[Action]) -> Vec<Result<(), String>> {
        self.cores
            .iter()
            .zip(actions)
            .map(|(c, a)| lock(c).check(*a))
            .collect()
    }
}
