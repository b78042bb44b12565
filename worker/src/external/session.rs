//! A running external strategy: one process serves one run. [`ExternalStrategy::start`] spawns
//! the program and shakes hands, [`ExternalStrategy::begin`] announces the run, the explorer
//! asks it at every decision through [`Policy`], and [`ExternalStrategy::finish`] ends it and
//! says whether it kept to the protocol.
//!
//! Every reply is awaited for at most the program's timeout; a crash, a timeout, a line that is
//! not a protocol message or a reply naming no candidate offered fails the run with a message
//! that names the program and what it did. The program's stderr is kept (its last line goes
//! into such messages) and handed back, so that its logs are not lost.

use std::process::Child;
use std::sync::mpsc::RecvTimeoutError;
use std::time::{Duration, Instant};

use sim_core::explore::{DecisionView, Needs, Policy, Reply, RunEnd};

use super::child::{self, Line, Pipes, MAX_LINE};
use super::clip;
use super::groups::{end_strays, group_alive, kill_group, live_groups};
use super::program::StrategyProgram;
use super::protocol::{self, Hello, Received, RunMessage, Sent, ToStrategy};

/// A program that broke the protocol (or could not be run), and what it did.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("strategy '{command}': {what}")]
pub struct StrategyError {
    pub command: String,
    pub what: String,
    /// What the program wrote to stderr until then (its last MiB; empty if it wrote nothing or
    /// never started), so that its traceback is not lost with the run.
    pub stderr: String,
}

/// What a finished program leaves.
#[derive(Debug, Clone, PartialEq)]
pub struct StrategyStats {
    /// Wall seconds from sending each decision to reading its reply, summed.
    pub compute_s: f64,
    /// Decision messages answered.
    pub replies: u64,
    /// What it wrote to stderr (its last MiB).
    pub stderr: String,
    /// Whether it exited by itself within a second of its stdin closing (else it was killed).
    pub exited: bool,
    /// Whether processes it started were still running in its process group after it ended
    /// (they were killed).
    pub left_behind: bool,
}

/// A running external strategy.
pub struct ExternalStrategy {
    program: StrategyProgram,
    command: String,
    child: Child,
    /// The folder of floorcast's Python module, removed with the program.
    _python: tempfile::TempDir,
    /// The program's pipes, each served by a thread of its own: a program that stops reading
    /// blocks that thread, never the run (its reply then times out).
    pipes: Pipes,
    timeout: Duration,
    hello: Hello,
    /// The first protocol error; every later call fails at once.
    error: Option<String>,
    /// What the program was sent so far (for `map_changes` and `layout`).
    sent: Sent,
    charge: bool,
    compute_s: f64,
    replies: u64,
    /// The last exchange, for a line that arrives unasked ("its answer to decision 3").
    last_asked: String,
}

impl std::fmt::Debug for ExternalStrategy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ExternalStrategy")
            .field("command", &self.command)
            .field("hello", &self.hello)
            .field("error", &self.error)
            .finish()
    }
}

impl ExternalStrategy {
    /// Starts the program and shakes hands.
    pub fn start(program: &StrategyProgram) -> Result<Self, StrategyError> {
        let command = program.display();
        let fail = |what: String| StrategyError {
            command: command.clone(),
            what,
            stderr: String::new(),
        };
        let (child, python, pipes) = child::spawn(program).map_err(&fail)?;
        let mut s = Self {
            program: program.clone(),
            command: command.clone(),
            child,
            _python: python,
            pipes,
            timeout: Duration::from_secs_f64(program.timeout_s),
            hello: Hello::default(),
            error: None,
            sent: Sent::default(),
            charge: false,
            compute_s: 0.0,
            replies: 0,
            last_asked: "starting".into(),
        };
        let reply = s
            .exchange(&ToStrategy::hello(), "the hello message")
            .and_then(|r| protocol::hello_of(&r));
        match reply {
            Ok(hello) => {
                s.hello = hello;
                Ok(s)
            }
            Err(what) => Err(s.error(what)),
        }
    }

    /// What the program said of itself.
    pub fn hello(&self) -> &Hello {
        &self.hello
    }

    /// The first protocol error the program made, if any.
    pub(super) fn protocol_error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// Announces a run and waits for the program to be ready. With `charge`, each reply's wall
    /// time is charged to simulated time.
    pub fn begin(&mut self, run: RunMessage, charge: bool) -> Result<(), StrategyError> {
        self.charge = charge;
        let mut hello = self.hello.clone();
        let r = self
            .exchange(&ToStrategy::Run(run), "the run message")
            .and_then(|r| protocol::ready_of(&r, &mut hello));
        self.hello = hello;
        r.map_err(|what| self.error(what))
    }

    /// Ends the program (it is killed if it does not exit within a second) and returns what it
    /// left, or the first protocol error it made.
    pub fn finish(mut self) -> Result<StrategyStats, StrategyError> {
        self.pipes.stdin = None;
        let deadline = Instant::now() + Duration::from_secs(1);
        let mut exited = false;
        while Instant::now() < deadline {
            if let Ok(Some(_)) = self.child.try_wait() {
                exited = true;
                break;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        // What it started and left running is ended with it (and said: `check_program`),
        // in its group or escaped from it (`end_strays`).
        let left_behind = exited && group_alive(self.child.id());
        kill_group(self.child.id());
        let _ = self.child.kill();
        let _ = self.child.wait();
        live_groups(|g| g.remove(&self.child.id()));
        let strays = end_strays();
        let left_behind = left_behind || (exited && strays > 0);
        self.pipes.join_stderr();
        if let Some(what) = self.error.take() {
            return Err(self.error(what));
        }
        Ok(StrategyStats {
            compute_s: self.compute_s,
            replies: self.replies,
            stderr: self.stderr_text(),
            exited,
            left_behind,
        })
    }

    /// What the program wrote to stderr so far (its last MiB).
    pub fn stderr_text(&self) -> String {
        self.pipes
            .stderr
            .lock()
            .map(|s| s.kept())
            .unwrap_or_default()
    }

    /// The error `what` with what the program wrote to stderr so far (all of it when it has
    /// ended: `ended` and `finish` wait for its stderr to be read).
    fn error(&self, what: String) -> StrategyError {
        StrategyError {
            command: self.command.clone(),
            what,
            stderr: self.stderr_text(),
        }
    }

    /// Sends `msg` and waits for one reply line, a JSON object, decoded. `what` names the
    /// message in errors ("decision 4").
    fn exchange(&mut self, msg: &ToStrategy, what: &str) -> Result<Received, String> {
        // A line waiting before `msg` is sent was not asked for (a second answer to the last
        // message, or one written ahead): taken as the answer to `msg`, it would be blamed on
        // the wrong message. (A program that ended is told by the `recv` below.)
        if let Some(early) = self.pipes.lines.try_recv_text() {
            return Err(format!(
                "sent a line before it was asked for (after {}, before {what}): '{}'; a strategy answers each message once, after reading it (logs go to stderr)",
                self.last_asked,
                clip(&early, 80)
            ));
        }
        self.last_asked = format!("its answer to {what}");
        self.send(msg)
            .map_err(|_| self.ended(&format!("before answering {what}")))?;
        let line = match self.await_line() {
            Ok(Line::Text(t)) => t,
            Ok(Line::TooLong) => {
                return Err(format!(
                    "answered {what} with a line longer than {} MiB",
                    MAX_LINE >> 20
                ))
            }
            Ok(Line::Eof) => {
                return Err(self.ended(&format!("before answering {what}")))
            }
            Ok(Line::Failed(e)) => return Err(format!("cannot read its answer to {what}: {e}")),
            Err(Awaited::Late) => {
                return Err(format!(
                    "did not answer {what} within {} s (the timeout: raise it with --strategy-timeout-s, or timeout_s in a grid)",
                    self.program.timeout_s
                ))
            }
            Err(Awaited::ExitedHeld(how)) => {
                return Err(format!(
                    "{how} before answering {what}, but its stdout is still held open by a process it started and left running (a forked child or a daemon); end what it starts before exiting, or start it with stdout redirected{}",
                    self.last_stderr_line()
                ))
            }
        };
        Received::decode(&line).ok_or_else(|| {
            format!(
                "answered {what} with a line that is not a protocol message: '{}' (a strategy writes only protocol lines to stdout; logs go to stderr)",
                clip(&line, 80)
            )
        })
    }

    /// The next line of the program, waited for at most its timeout; a program that exits
    /// while something it left behind holds its stdout open is told at once (after
    /// [`EXIT_GRACE`] for the lines it wrote before exiting), not as a timeout.
    fn await_line(&mut self) -> Result<Line, Awaited> {
        let deadline = Instant::now() + self.timeout;
        let mut exited_at: Option<(Instant, std::process::ExitStatus)> = None;
        loop {
            let now = Instant::now();
            if now >= deadline {
                return Err(Awaited::Late);
            }
            let slice = (deadline - now).min(EXIT_POLL);
            match self.pipes.lines.recv_timeout(slice) {
                Ok(line) => return Ok(line),
                Err(RecvTimeoutError::Disconnected) => return Ok(Line::Eof),
                Err(RecvTimeoutError::Timeout) => {}
            }
            match exited_at {
                Some((at, status)) if at.elapsed() >= EXIT_GRACE => {
                    return Err(Awaited::ExitedHeld(exit_words(status)))
                }
                Some(_) => {}
                None => {
                    if let Ok(Some(status)) = self.child.try_wait() {
                        exited_at = Some((Instant::now(), status));
                    }
                }
            }
        }
    }

    /// "; its last stderr line: '...'" as read so far, or "" (not waited for: what the program
    /// left may hold its stderr open too).
    fn last_stderr_line(&self) -> String {
        let last = self
            .pipes
            .stderr
            .lock()
            .map(|s| s.last_line.clone())
            .unwrap_or_default();
        if last.is_empty() {
            String::new()
        } else {
            format!(
                "; its last stderr line: '{}'",
                clip(&last, crate::text::MAX_ECHO_BYTES)
            )
        }
    }

    fn send(&mut self, msg: &ToStrategy) -> Result<(), ()> {
        let stdin = self.pipes.stdin.as_ref().ok_or(())?;
        let line = protocol::line(msg).map_err(|_| ())?;
        stdin.send(line).map_err(|_| ())
    }

    /// How the program ended, for a message: its exit status and last stderr line.
    fn ended(&mut self, when: &str) -> String {
        let deadline = Instant::now() + Duration::from_secs(1);
        let status = loop {
            match self.child.try_wait() {
                Ok(Some(s)) => break Some(s),
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(5))
                }
                _ => break None,
            }
        };
        if status.is_some() {
            self.pipes.join_stderr();
        }
        let how = match status {
            Some(s) => exit_words(s),
            None => "closed its stdout".to_string(),
        };
        format!("{how} {when}{}", self.last_stderr_line())
    }
}

/// How often a wait for a reply looks whether the program has exited.
const EXIT_POLL: Duration = Duration::from_millis(50);
/// After the program exited, how long its last lines may take to come through its stdout.
const EXIT_GRACE: Duration = Duration::from_millis(300);

/// Why no line came.
enum Awaited {
    /// Not within the program's timeout.
    Late,
    /// The program exited (how, in words) but its stdout stays open: held by a process it left.
    ExitedHeld(String),
}

/// "exited with status 3" or "was ended by a signal (...)".
fn exit_words(s: std::process::ExitStatus) -> String {
    match s.code() {
        Some(c) => format!("exited with status {c}"),
        None => format!("was ended by a signal ({s})"),
    }
}

impl Drop for ExternalStrategy {
    fn drop(&mut self) {
        kill_group(self.child.id());
        let _ = self.child.kill();
        let _ = self.child.wait();
        live_groups(|g| g.remove(&self.child.id()));
        end_strays();
    }
}

impl Policy for ExternalStrategy {
    fn needs(&self) -> Needs {
        Needs {
            layout_gain: self.hello.needs_layout_gain,
            layout: self.hello.needs_layout,
            paths_between: false,
            mate_paths: false,
        }
    }

    fn decide(&mut self, view: &DecisionView<'_>) -> (Reply, f64) {
        if self.error.is_some() {
            return (Reply::Fail, 0.0);
        }
        let msg = ToStrategy::Decide(self.sent.decide(view, &self.hello));
        let what = if view.attempt == 0 {
            format!("decision {}", view.decision)
        } else {
            format!("decision {} (attempt {})", view.decision, view.attempt)
        };
        let t0 = Instant::now();
        let reply = self.exchange(&msg, &what);
        let took_s = t0.elapsed().as_secs_f64();
        self.compute_s += took_s;
        self.replies += 1;
        match reply.and_then(|r| protocol::reply_to(&r, view, &what)) {
            Ok(r) => (r, if self.charge { took_s } else { 0.0 }),
            Err(e) => {
                self.error = Some(e);
                (Reply::Fail, 0.0)
            }
        }
    }

    fn end(&mut self, end: &RunEnd) {
        if self.error.is_some() {
            return;
        }
        // No reply is awaited; a program that has already gone is no error.
        let _ = self.send(&ToStrategy::end(end));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn a_refused_pipe_thread_stops_the_program_and_is_an_error() {
        // A program that would run for a minute: stopped as soon as a thread for its pipes is
        // refused (the first, the second or the third), not waited for, and the error says what
        // to do.
        for started in 0..3 {
            let p = StrategyProgram::from_command_line("sleep 60", Path::new("."), 1.0).unwrap();
            crate::refuse_threads_after(Some(started));
            let t0 = std::time::Instant::now();
            let e = ExternalStrategy::start(&p).map(|_| ()).unwrap_err();
            crate::refuse_threads_after(None);
            assert!(
                e.what
                    .contains("cannot start a thread for the program's pipes")
                    && e.what.contains("run fewer jobs at once"),
                "after {started} threads: {}",
                e.what
            );
            assert!(
                t0.elapsed() < std::time::Duration::from_secs(30),
                "after {started} threads: the program was not stopped ({:?})",
                t0.elapsed()
            );
        }
    }
}
