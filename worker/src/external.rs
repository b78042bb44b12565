//! External strategies: a program, in any language, that speaks floorcast's strategy protocol
//! (`docs/strategy-protocol.md`) over its stdin and stdout, one JSON object per line. One
//! process serves one run: [`ExternalStrategy::start`] spawns it and shakes hands,
//! [`ExternalStrategy::begin`] announces the run, the explorer asks it at every decision through
//! [`Policy`], and [`ExternalStrategy::finish`] ends it and says whether it kept to the protocol.
//!
//! Every reply is awaited for at most the program's timeout; a crash, a timeout, a line that is
//! not protocol JSON or a reply naming no candidate offered fails the run with a message that
//! names the program and what it did. The program's stderr is kept (its last line goes into
//! such messages) and handed back, so that its logs are not lost.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};
use serde_json::{json, Map, Value};
use sim_core::explore::{DecisionView, Needs, Policy, Reply, RunEnd};
use sim_core::grid::{GridFrame, Occupancy};

/// The protocol version this floorcast speaks.
pub const PROTOCOL_VERSION: u64 = 1;
/// The default time a program has for each reply (s).
pub const DEFAULT_TIMEOUT_S: f64 = 10.0;
/// The longest reply line read (bytes).
const MAX_LINE: usize = 1 << 20;
/// The largest `params` object (bytes of its JSON).
pub const MAX_PARAMS_BYTES: usize = 64 << 10;
/// Stderr kept from a program (bytes; the rest is dropped).
const MAX_STDERR: usize = 1 << 20;

/// An external strategy's program: how to start it and what it is, as a job and its record
/// carry it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrategyProgram {
    /// The command, split into words (the first is the executable); words that name files
    /// are relative to `dir`.
    pub command: Vec<String>,
    /// Further files the program needs (relative to `dir`): hashed into its identity and sent
    /// to remote workers with the words of the command that name files.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub files: Vec<String>,
    /// SHA-256 (hex) over the program's files ([`StrategyProgram::file_names`]: their names as
    /// written and their contents): the program's identity (empty when it has none).
    pub files_sha256: String,
    /// Seconds the program has for each reply.
    pub timeout_s: f64,
    /// The strategy's own parameters, sent to it in the run message (`params`): part of its
    /// identity, so that one program with other parameters is another strategy.
    #[serde(default, skip_serializing_if = "Map::is_empty")]
    pub params: Map<String, Value>,
    /// Where the words and files are relative to (not part of the identity).
    #[serde(skip)]
    pub dir: PathBuf,
    /// Written from a remote job's contents, checked against `files_sha256` then (its words
    /// may have been moved: a file named by an absolute path is written inside the job's
    /// directory).
    #[serde(skip)]
    pub received: bool,
}

/// A program's files: each name as written and its bytes.
pub type ProgramFiles = Vec<(String, Vec<u8>)>;

/// Most files a program may have, and bytes in all (they travel with every remote job).
pub const MAX_PROGRAM_FILES: usize = 64;
pub const MAX_PROGRAM_BYTES: u64 = 8 << 20;

impl StrategyProgram {
    /// The program run by `command` (with further `files`), whose words that name files
    /// relative to `dir` are hashed into its identity with `files`. The command is not run.
    pub fn new(
        command: Vec<String>,
        files: Vec<String>,
        dir: &Path,
        timeout_s: f64,
    ) -> Result<Self, String> {
        if command.is_empty() || command[0].trim().is_empty() {
            return Err("the strategy command is empty (expected a program and its arguments, e.g. \"python3 my_strategy.py\")".into());
        }
        check_timeout(timeout_s)?;
        for f in &files {
            check_file(dir, f)?;
        }
        let mut p = Self {
            command,
            files,
            files_sha256: String::new(),
            timeout_s,
            params: Map::new(),
            dir: dir.to_path_buf(),
            received: false,
        };
        p.files_sha256 = p.hash_files()?;
        Ok(p)
    }

    /// The program with its own parameters (at most [`MAX_PARAMS_BYTES`] of JSON).
    pub fn with_params(mut self, params: Map<String, Value>) -> Result<Self, String> {
        let bytes = Value::Object(params.clone()).to_string().len();
        if bytes > MAX_PARAMS_BYTES {
            return Err(format!(
                "the strategy's params take {bytes} bytes of JSON (at most {MAX_PARAMS_BYTES}); pass large data as a file"
            ));
        }
        self.params = params;
        Ok(self)
    }

    /// The program from a command line split as a shell splits words.
    pub fn from_command_line(line: &str, dir: &Path, timeout_s: f64) -> Result<Self, String> {
        let words = shlex::split(line).ok_or_else(|| {
            format!(
                "cannot split the strategy command '{}' into words (an unclosed quote?)",
                crate::text::excerpt(line)
            )
        })?;
        Self::new(words, Vec::new(), dir, timeout_s)
    }

    /// The program's files, as written: the words of the command that name files (relative to
    /// `dir`), then `files`, each once.
    pub fn file_names(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        let words = self.command.iter().filter(|w| self.dir.join(w).is_file());
        for n in words.chain(&self.files) {
            if !names.contains(n) {
                names.push(n.clone());
            }
        }
        names
    }

    /// The files' contents, by name ([`StrategyProgram::file_names`]), size-checked.
    pub fn read_files(&self) -> Result<ProgramFiles, String> {
        let names = self.file_names();
        if names.len() > MAX_PROGRAM_FILES {
            return Err(format!(
                "the program has {} files, more than {MAX_PROGRAM_FILES}",
                names.len()
            ));
        }
        let mut total = 0u64;
        names
            .into_iter()
            .map(|n| {
                let path = self.dir.join(&n);
                total += std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
                if total > MAX_PROGRAM_BYTES {
                    return Err(format!(
                        "the program's files reach {} with more than the {} MiB a program may have",
                        path.display(),
                        MAX_PROGRAM_BYTES >> 20
                    ));
                }
                let bytes = std::fs::read(&path)
                    .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
                Ok((n, bytes))
            })
            .collect()
    }

    fn hash_files(&self) -> Result<String, String> {
        Ok(files_sha256(&self.read_files()?))
    }

    /// Checks that the files are still the ones the identity was made of (a program received
    /// with a remote job was checked as it was written).
    pub fn check_files(&self) -> Result<(), String> {
        if self.received {
            return Ok(());
        }
        let now = self.hash_files()?;
        if now != self.files_sha256 {
            return Err(format!(
                "the program's files changed since the grid was planned (sha256 {}, expected {})",
                &now[..now.len().min(12)],
                &self.files_sha256[..self.files_sha256.len().min(12)]
            ));
        }
        Ok(())
    }

    /// The program with its files written under `root` (as a remote worker receives them),
    /// their relative layout kept; checked against `files_sha256`.
    pub fn materialize(
        command: Vec<String>,
        files: Vec<String>,
        contents: &[(String, Vec<u8>)],
        sha256: &str,
        timeout_s: f64,
        root: &Path,
    ) -> Result<Self, String> {
        if files_sha256(contents) != sha256 {
            return Err("the program's files arrived damaged (their hash differs)".into());
        }
        // A name may climb out of its directory ("../python/x.py"): the files go that many
        // levels below `root`, so that every name stays inside it. A file named by an absolute
        // path (on the coordinator's machine) goes to a directory of its own in `root`, and the
        // words naming it are moved there.
        let is_absolute = |name: &str| Path::new(name).is_absolute();
        let mut depth = 0;
        for (name, _) in contents.iter().filter(|(n, _)| !is_absolute(n)) {
            depth = depth.max(relative_parts(name)?.0);
        }
        let mut dir = root.to_path_buf();
        for i in 0..depth {
            dir.push(format!("d{i}"));
        }
        let mut moved: Vec<(String, String)> = Vec::new();
        for (i, (name, bytes)) in contents.iter().enumerate() {
            let path = if is_absolute(name) {
                let base = Path::new(name)
                    .file_name()
                    .ok_or_else(|| format!("file '{name}' names no file"))?;
                let p = root.join(format!("abs{i}")).join(base);
                moved.push((name.clone(), p.to_string_lossy().into_owned()));
                p
            } else {
                let (up, parts) = relative_parts(name)?;
                let mut path = dir.clone();
                for _ in 0..up {
                    path.pop();
                }
                path.extend(parts);
                path
            };
            if let Some(parent) = path.parent() {
                std::fs::create_dir_all(parent)
                    .map_err(|e| format!("cannot create {}: {e}", parent.display()))?;
            }
            std::fs::write(&path, bytes)
                .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        }
        std::fs::create_dir_all(&dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        let moved_word = |w: String| {
            moved
                .iter()
                .find(|(from, _)| *from == w)
                .map_or(w.clone(), |(_, to)| to.clone())
        };
        Ok(Self {
            command: command.into_iter().map(moved_word).collect(),
            files: files.into_iter().map(moved_word).collect(),
            files_sha256: sha256.to_string(),
            timeout_s,
            params: Map::new(),
            dir,
            received: true,
        })
    }

    /// The command with its words that name files made paths from here.
    fn resolved_command(&self) -> Vec<String> {
        self.command
            .iter()
            .map(|w| {
                let p = self.dir.join(w);
                if p.is_file() {
                    p.to_string_lossy().into_owned()
                } else {
                    w.clone()
                }
            })
            .collect()
    }

    /// The command as one line, for messages.
    pub fn display(&self) -> String {
        shlex::try_join(self.command.iter().map(String::as_str))
            .unwrap_or_else(|_| self.command.join(" "))
    }
}

fn shown_dir(dir: &Path) -> String {
    if dir.as_os_str().is_empty() || dir == Path::new(".") {
        "the current directory".into()
    } else {
        dir.display().to_string()
    }
}

/// A program's reply timeout must be within [0.01, 3600] s.
pub fn check_timeout(timeout_s: f64) -> Result<(), String> {
    if !(timeout_s.is_finite() && (0.01..=3600.0).contains(&timeout_s)) {
        return Err(format!(
            "the strategy timeout {} s is outside [0.01, 3600] s",
            crate::settings::fmt_num(timeout_s)
        ));
    }
    Ok(())
}

/// One of a program's further `files`: a regular file, named relative to `dir`.
pub fn check_file(dir: &Path, name: &str) -> Result<(), String> {
    if !dir.join(name).is_file() {
        return Err(format!(
            "file '{}' is not a file (files are relative to {})",
            crate::text::excerpt(name),
            shown_dir(dir)
        ));
    }
    relative_parts(name)?;
    Ok(())
}

/// A relative file name as the levels it climbs ("..") and the parts below: refused when
/// absolute or climbing after descending.
fn relative_parts(name: &str) -> Result<(usize, Vec<String>), String> {
    use std::path::Component;
    let (mut up, mut parts) = (0usize, Vec::new());
    for c in Path::new(name).components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir if parts.is_empty() => up += 1,
            Component::ParentDir => {
                parts.pop();
            }
            Component::Normal(p) => parts.push(p.to_string_lossy().into_owned()),
            Component::RootDir | Component::Prefix(_) => {
                return Err(format!(
                    "file '{}' is an absolute path (give it relative to the grid file, so that remote workers can receive it)",
                    crate::text::excerpt(name)
                ))
            }
        }
    }
    if parts.is_empty() {
        return Err(format!(
            "file '{}' names no file",
            crate::text::excerpt(name)
        ));
    }
    Ok((up, parts))
}

/// The identity of a program's files: SHA-256 over their names and contents.
fn files_sha256(files: &[(String, Vec<u8>)]) -> String {
    if files.is_empty() {
        return String::new();
    }
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    for (name, bytes) in files {
        h.update(name.as_bytes());
        h.update([0]);
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    }
    format!("{:x}", h.finalize())
}

/// floorcast's Python module for strategies (`python/floorcast_strategy.py`, built into the
/// binary): every strategy program finds it on its `PYTHONPATH`, so `import
/// floorcast_strategy` works wherever the program lives, remote workers included, and always
/// speaks this floorcast's protocol.
pub const PYTHON_MODULE: &str = include_str!("../../python/floorcast_strategy.py");

/// A new folder of this process's own in the temporary directory (`TMPDIR`): a name no one
/// else chose, mode 0700, removed when dropped. A folder with a name known in advance could be
/// made first by another user, with modules of theirs that our programs would import.
pub fn private_temp_dir(prefix: &str) -> Result<tempfile::TempDir, String> {
    use std::os::unix::fs::PermissionsExt;
    let tmp = std::env::temp_dir();
    tempfile::Builder::new()
        .prefix(prefix)
        .permissions(std::fs::Permissions::from_mode(0o700))
        .tempdir_in(&tmp)
        .map_err(|e| {
            format!(
                "cannot create a folder in the temporary directory {} ({e}); set TMPDIR to a directory you can write",
                tmp.display()
            )
        })
}

/// A private folder ([`private_temp_dir`]) holding [`PYTHON_MODULE`], for one program.
fn python_dir() -> Result<tempfile::TempDir, String> {
    let dir = private_temp_dir("floorcast-python-")?;
    let file = dir.path().join("floorcast_strategy.py");
    std::fs::write(&file, PYTHON_MODULE).map_err(|e| {
        format!(
            "cannot write {} ({e}); set TMPDIR to a directory you can write",
            file.display()
        )
    })?;
    Ok(dir)
}

/// What the program said of itself.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Hello {
    pub name: String,
    pub needs_layout_gain: bool,
    pub needs_layout: bool,
    pub needs_map: bool,
}

/// A program that broke the protocol (or could not be run), and what it did.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("strategy '{command}': {what}")]
pub struct StrategyError {
    pub command: String,
    pub what: String,
}

/// What a finished program leaves.
#[derive(Debug, Clone, PartialEq)]
pub struct StrategyStats {
    /// Wall seconds from sending each decision to reading its reply, summed.
    pub compute_s: f64,
    /// Decision messages answered.
    pub replies: u64,
    /// What it wrote to stderr (at most 1 MiB).
    pub stderr: String,
    /// Whether it exited by itself within a second of its stdin closing (else it was killed).
    pub exited: bool,
    /// Whether processes it started were still running in its process group after it ended
    /// (they were killed).
    pub left_behind: bool,
}

enum Line {
    Text(String),
    TooLong,
    Eof,
    Failed(String),
}

/// A running external strategy.
pub struct ExternalStrategy {
    program: StrategyProgram,
    command: String,
    child: Child,
    /// The folder of floorcast's Python module, removed with the program.
    _python: tempfile::TempDir,
    /// Lines to write to the program's stdin, written by a thread of their own: a program that
    /// stops reading blocks that thread, never the run (its reply then times out).
    stdin: Option<mpsc::Sender<String>>,
    stderr_reader: Option<std::thread::JoinHandle<()>>,
    lines: Receiver<Line>,
    stderr: Arc<Mutex<Stderr>>,
    timeout: Duration,
    hello: Hello,
    /// The first protocol error; every later call fails at once.
    error: Option<String>,
    /// The map's cells as last sent (for `map_changes`).
    sent_map: Vec<Occupancy>,
    /// The number of the last layout sent (0: none yet).
    sent_layout: u64,
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

#[derive(Default)]
struct Stderr {
    text: String,
    last_line: String,
}

/// The command that starts `program`: in a process group of its own, with floorcast's Python
/// module (in `python`) importable, its three pipes piped.
fn program_command(program: &StrategyProgram, python: &std::path::Path) -> Command {
    let command_words = program.resolved_command();
    let mut cmd = Command::new(&command_words[0]);
    cmd.args(&command_words[1..]);
    // A process group of its own, so that everything it starts (a wrapper script's
    // children, a daemon it forks) is ended with it: `kill_group`.
    std::os::unix::process::CommandExt::process_group(&mut cmd, 0);
    // No __pycache__ beside the programs (or in a repository's python/).
    cmd.env("PYTHONDONTWRITEBYTECODE", "1");
    // floorcast's Python module, importable by every strategy program, in a folder of
    // this program's own.
    let mut paths = vec![python.to_path_buf()];
    if let Some(old) = std::env::var_os("PYTHONPATH") {
        paths.extend(std::env::split_paths(&old));
    }
    if let Ok(joined) = std::env::join_paths(paths) {
        cmd.env("PYTHONPATH", joined);
    }
    cmd.stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    cmd
}

/// Starts `cmd` and registers its process group (under one lock, so that `end_strays` never
/// takes a program just started for a stray); an error says what to do.
fn spawn_registered(
    cmd: &mut Command,
    program: &StrategyProgram,
) -> Result<std::process::Child, String> {
    live_groups(|g| {
        let child = cmd.spawn()?;
        g.insert(child.id());
        Ok(child)
    })
    .map_err(|e: std::io::Error| match e.kind() {
        std::io::ErrorKind::NotFound => format!(
            "cannot start '{}': no such program (is it installed and on PATH?)",
            crate::text::excerpt(&program.command[0])
        ),
        _ => format!(
            "cannot start '{}': {e}",
            crate::text::excerpt(&program.command[0])
        ),
    })
}

impl ExternalStrategy {
    /// Starts the program and shakes hands.
    pub fn start(program: &StrategyProgram) -> Result<Self, StrategyError> {
        let command = program.display();
        let fail = |what: String| StrategyError {
            command: command.clone(),
            what,
        };
        let python = python_dir().map_err(&fail)?;
        let mut cmd = program_command(program, python.path());
        let mut child = spawn_registered(&mut cmd, program).map_err(&fail)?;
        // The pipes' threads. One the system refuses is an error, not a panic: the program is
        // stopped (the threads already started end with its pipes).
        let refused = |child: &mut std::process::Child, e: std::io::Error| {
            kill_group(child.id());
            live_groups(|g| g.remove(&child.id()));
            let _ = child.kill();
            let _ = child.wait();
            fail(format!(
                "cannot start a thread for the program's pipes ({e}): the system is out of threads or memory; run fewer jobs at once"
            ))
        };
        let stdin = match child.stdin.take() {
            Some(pipe) => {
                let (tx, rx) = mpsc::channel::<String>();
                crate::spawn_thread(move || write_lines(pipe, rx))
                    .map_err(|e| refused(&mut child, e))?;
                Some(tx)
            }
            None => None,
        };
        let stdout = child.stdout.take().expect("stdout is piped");
        let stderr_pipe = child.stderr.take().expect("stderr is piped");
        let (tx, lines) = mpsc::channel();
        crate::spawn_thread(move || read_lines(stdout, tx)).map_err(|e| refused(&mut child, e))?;
        let stderr = Arc::new(Mutex::new(Stderr::default()));
        let sink = Arc::clone(&stderr);
        let stderr_reader = Some(
            crate::spawn_thread(move || read_stderr(stderr_pipe, sink))
                .map_err(|e| refused(&mut child, e))?,
        );
        let mut s = Self {
            program: program.clone(),
            command: command.clone(),
            child,
            _python: python,
            stdin,
            stderr_reader,
            lines,
            stderr,
            timeout: Duration::from_secs_f64(program.timeout_s),
            hello: Hello {
                name: String::new(),
                needs_layout_gain: false,
                needs_layout: false,
                needs_map: false,
            },
            error: None,
            sent_map: Vec::new(),
            sent_layout: 0,
            charge: false,
            compute_s: 0.0,
            replies: 0,
            last_asked: "starting".into(),
        };
        let reply = s
            .exchange(
                &json!({"type": "hello", "protocol": PROTOCOL_VERSION, "floorcast": crate::FLOORCAST_VERSION}),
                "the hello message",
            )
            .and_then(|v| parse_hello(&v));
        match reply {
            Ok(hello) => {
                s.hello = hello;
                Ok(s)
            }
            Err(what) => Err(fail(what)),
        }
    }

    /// What the program said of itself.
    pub fn hello(&self) -> &Hello {
        &self.hello
    }

    /// Announces a run (`run` is the message's content besides its type) and waits for the
    /// program to be ready. With `charge`, each reply's wall time is charged to simulated time.
    pub fn begin(&mut self, mut run: Value, charge: bool) -> Result<(), StrategyError> {
        self.charge = charge;
        run["type"] = json!("run");
        let r = self.exchange(&run, "the run message").and_then(|v| {
            match v.get("type").and_then(Value::as_str) {
                Some("ready") => Ok(()),
                _ => Err(format!(
                    "answered the run message with {} (expected {{\"type\":\"ready\"}})",
                    quote_json(&v)
                )),
            }
        });
        r.map_err(|what| self.error(what))
    }

    /// Ends the program (it is killed if it does not exit within a second) and returns what it
    /// left, or the first protocol error it made.
    pub fn finish(mut self) -> Result<StrategyStats, StrategyError> {
        self.stdin = None;
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
        self.join_stderr();
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

    /// What the program wrote to stderr so far.
    pub fn stderr_text(&self) -> String {
        self.stderr
            .lock()
            .map(|s| s.text.clone())
            .unwrap_or_default()
    }

    fn error(&self, what: String) -> StrategyError {
        StrategyError {
            command: self.command.clone(),
            what,
        }
    }

    /// Sends `msg` and waits for one reply line, parsed as JSON. `what` names the message in
    /// errors ("decision 4").
    fn exchange(&mut self, msg: &Value, what: &str) -> Result<Value, String> {
        // A line waiting before `msg` is sent was not asked for (a second answer to the last
        // message, or one written ahead): taken as the answer to `msg`, it would be blamed on
        // the wrong message. (A program that ended is told by the `recv` below.)
        if let Ok(Line::Text(early)) = self.lines.try_recv() {
            return Err(format!(
                "sent a line before it was asked for (after {}, before {what}): '{}'; a strategy answers each message once, after reading it (logs go to stderr)",
                self.last_asked,
                clip(&early, 80)
            ));
        }
        self.last_asked = format!("its answer to {what}");
        self.send(msg)
            .map_err(|_| self.ended(&format!("before answering {what}")))?;
        let line = match self.lines.recv_timeout(self.timeout) {
            Ok(Line::Text(t)) => t,
            Ok(Line::TooLong) => {
                return Err(format!(
                    "answered {what} with a line longer than {} MiB",
                    MAX_LINE >> 20
                ))
            }
            Ok(Line::Eof) | Err(RecvTimeoutError::Disconnected) => {
                return Err(self.ended(&format!("before answering {what}")))
            }
            Ok(Line::Failed(e)) => return Err(format!("cannot read its answer to {what}: {e}")),
            Err(RecvTimeoutError::Timeout) => {
                return Err(format!(
                    "did not answer {what} within {} s (the timeout: raise it with --strategy-timeout-s, or timeout_s in a grid)",
                    self.program.timeout_s
                ))
            }
        };
        serde_json::from_str::<Value>(&line)
            .ok()
            .filter(Value::is_object)
            .ok_or_else(|| {
                format!(
                    "answered {what} with a line that is not a protocol message: '{}' (a strategy writes only protocol lines to stdout; logs go to stderr)",
                    clip(&line, 80)
                )
            })
    }

    fn send(&mut self, msg: &Value) -> Result<(), ()> {
        let stdin = self.stdin.as_ref().ok_or(())?;
        let mut line = serde_json::to_string(msg).map_err(|_| ())?;
        line.push('\n');
        stdin.send(line).map_err(|_| ())
    }

    /// Waits (at most a second) for the stderr reader to take in what the program wrote before
    /// it ended.
    fn join_stderr(&mut self) {
        if let Some(h) = self.stderr_reader.take() {
            let deadline = Instant::now() + Duration::from_secs(1);
            while !h.is_finished() && Instant::now() < deadline {
                std::thread::sleep(Duration::from_millis(2));
            }
            if h.is_finished() {
                let _ = h.join();
            }
        }
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
            self.join_stderr();
        }
        let last = self
            .stderr
            .lock()
            .map(|s| s.last_line.clone())
            .unwrap_or_default();
        let how = match status {
            Some(s) => match s.code() {
                Some(c) => format!("exited with status {c}"),
                None => format!("was ended by a signal ({s})"),
            },
            None => "closed its stdout".to_string(),
        };
        if last.is_empty() {
            format!("{how} {when}")
        } else {
            format!(
                "{how} {when}; its last stderr line: '{}'",
                clip(&last, crate::text::MAX_ECHO_BYTES)
            )
        }
    }

    fn decide_message(&mut self, view: &DecisionView<'_>) -> Value {
        let candidates: Vec<Value> = view
            .candidates
            .iter()
            .map(|c| {
                let mut v = json!({
                    "id": c.id,
                    "cell": [c.cell.x, c.cell.y],
                    "point": [c.point.x, c.point.y],
                    "goal": [c.goal.x, c.goal.y],
                    "frontier_cells": c.frontier_cells,
                    "distance_m": c.distance_m,
                    "path_m": c.path_m,
                    "straight_m": c.straight_m,
                    "gain_m2": c.gain_m2,
                });
                if self.hello.needs_layout_gain {
                    v["layout_gain_m2"] = json!(c.layout_gain_m2);
                }
                if self.hello.needs_layout {
                    v["room"] = json!(c.room);
                }
                v
            })
            .collect();
        let mut msg = json!({
            "type": "decide",
            "decision": view.decision,
            "attempt": view.attempt,
            "time_s": view.time_s,
            "pose": [view.pose.x_m, view.pose.y_m, view.pose.theta_rad],
            "candidates": candidates,
        });
        if let Some(p) = view.unreachable_goal {
            msg["unreachable_goal"] = json!([p.x, p.y]);
        }
        if let Some(layout) = view.layout.filter(|l| l.number != self.sent_layout) {
            self.sent_layout = layout.number;
            let rooms: Vec<Value> = layout
                .rooms
                .iter()
                .map(|r| {
                    json!({
                        "polygon": r.polygon.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>(),
                        "state": r.state.as_str(),
                        "predicted": r.predicted,
                        "area_m2": r.area_m2,
                        "observed_area_m2": r.observed_area_m2,
                        "unknown_area_m2": r.unknown_area_m2,
                    })
                })
                .collect();
            msg["layout"] = json!({"number": layout.number, "rooms": rooms});
        }
        if self.hello.needs_map {
            let data = &view.map.data;
            if self.sent_map.len() != data.len() {
                self.sent_map = vec![Occupancy::Unknown; data.len()];
            }
            let (mut free, mut occupied, mut unknown) = (Vec::new(), Vec::new(), Vec::new());
            for (i, (now, sent)) in data.iter().zip(self.sent_map.iter_mut()).enumerate() {
                if now != sent {
                    match now {
                        Occupancy::Free => free.push(i),
                        Occupancy::Occupied => occupied.push(i),
                        Occupancy::Unknown => unknown.push(i),
                    }
                    *sent = *now;
                }
            }
            msg["map_changes"] = json!({"free": free, "occupied": occupied, "unknown": unknown});
        }
        msg
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

/// Makes floorcast the reaper of its orphaned descendants (Linux's child subreaper): a process a
/// strategy program started in a session or process group of its own (`setsid`, a daemon) is
/// no longer ended with the program's group, but when its parent ends it becomes floorcast's
/// child instead of init's, and `end_strays` finds it. Called once at start.
pub fn adopt_orphans() {
    let _ = nix::sys::prctl::set_child_subreaper(true);
}

/// Ends (SIGKILL) and reaps every stray: a process that became floorcast's child by its parent
/// ending ([`adopt_orphans`]), in a process group of neither floorcast nor a program running
/// now, with the group it leads. Done after every program's end; returns how many it ended
/// (ended strays not yet reaped are reaped, not counted).
pub fn end_strays() -> usize {
    let me = std::process::id();
    let my_group = nix::unistd::getpgrp().as_raw() as u32;
    let mut ended = 0;
    // A stray's children become strays when it ends: a few rounds find them.
    for _ in 0..10 {
        let found = live_groups(|live| {
            let mut found = 0;
            for (pid, state, group) in children_of(me) {
                if group == my_group || live.contains(&group) || live.contains(&pid) {
                    continue;
                }
                let target = nix::unistd::Pid::from_raw(pid as i32);
                if state != 'Z' {
                    kill_group(group);
                    let _ = nix::sys::signal::kill(target, nix::sys::signal::Signal::SIGKILL);
                    found += 1;
                }
                let _ = nix::sys::wait::waitpid(target, None);
            }
            found
        });
        ended += found;
        if found == 0 {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    ended
}

/// The children of process `parent` (pid, state, process group), from `/proc` (none without it).
fn children_of(parent: u32) -> Vec<(u32, char, u32)> {
    processes()
        .unwrap_or_default()
        .into_iter()
        .filter(|p| p.parent == parent)
        .map(|p| (p.pid, p.state, p.group))
        .collect()
}

/// A process as `/proc/<pid>/stat` describes it.
struct ProcessStat {
    pid: u32,
    state: char,
    parent: u32,
    group: u32,
}

/// Every process of the system, from `/proc` (`None` without it).
fn processes() -> Option<Vec<ProcessStat>> {
    let mut out = Vec::new();
    for e in std::fs::read_dir("/proc").ok()?.flatten() {
        let Ok(pid) = e.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let Ok(stat) = std::fs::read_to_string(e.path().join("stat")) else {
            continue;
        };
        // "pid (comm) state ppid pgrp ...": the name may hold spaces and parentheses.
        let Some((_, rest)) = stat.rsplit_once(')') else {
            continue;
        };
        let fields: Vec<&str> = rest.split_whitespace().take(3).collect();
        if let [state, parent, group] = fields[..] {
            if let (Some(state), Ok(parent), Ok(group)) =
                (state.chars().next(), parent.parse(), group.parse())
            {
                out.push(ProcessStat {
                    pid,
                    state,
                    parent,
                    group,
                });
            }
        }
    }
    Some(out)
}

/// The process groups of the programs running now (each program's group is its process id).
fn live_groups<T>(f: impl FnOnce(&mut std::collections::BTreeSet<u32>) -> T) -> T {
    static GROUPS: Mutex<std::collections::BTreeSet<u32>> =
        Mutex::new(std::collections::BTreeSet::new());
    f(&mut GROUPS.lock().unwrap_or_else(|e| e.into_inner()))
}

/// Set when floorcast is being stopped ([`kill_all_programs`]).
static STOPPING: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether floorcast is being stopped by a signal (its programs killed): an error that follows
/// (a program's pipe closed) is the stop's doing, and the stop's handler sets the exit code.
pub fn stopping() -> bool {
    STOPPING.load(std::sync::atomic::Ordering::SeqCst)
}

/// Kills every process of every program running now, for a floorcast that must stop at once
/// (a second Ctrl-C): the programs' process groups do not get the terminal's signals.
pub fn kill_all_programs() {
    STOPPING.store(true, std::sync::atomic::Ordering::SeqCst);
    for g in live_groups(std::mem::take) {
        kill_group(g);
    }
    end_strays();
}

/// Kills (SIGKILL) every process of the process group `pgid`, a program's.
fn kill_group(pgid: u32) {
    if let Ok(pgid) = i32::try_from(pgid) {
        let _ = nix::sys::signal::killpg(
            nix::unistd::Pid::from_raw(pgid),
            nix::sys::signal::Signal::SIGKILL,
        );
    }
}

/// Whether a process of the group `pgid` is still running after its leader (the program)
/// ended, waiting up to 200 ms for processes on their way out. Ended processes not yet reaped
/// (zombies) do not count; without `/proc`, whether the group has any process.
fn group_alive(pgid: u32) -> bool {
    let deadline = Instant::now() + Duration::from_millis(200);
    loop {
        let alive = match running_in_group(pgid) {
            Some(n) => n > 0,
            None => i32::try_from(pgid).is_ok_and(|p| {
                nix::sys::signal::killpg(nix::unistd::Pid::from_raw(p), None).is_ok()
            }),
        };
        if !alive || Instant::now() >= deadline {
            return alive;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// How many processes of the group `pgid` run (zombies aside), from `/proc` (`None` without it).
fn running_in_group(pgid: u32) -> Option<usize> {
    Some(
        processes()?
            .iter()
            .filter(|p| p.state != 'Z' && p.group == pgid)
            .count(),
    )
}

impl Policy for ExternalStrategy {
    fn needs(&self) -> Needs {
        Needs {
            layout_gain: self.hello.needs_layout_gain,
            layout: self.hello.needs_layout,
            paths_between: false,
        }
    }

    fn decide(&mut self, view: &DecisionView<'_>) -> (Reply, f64) {
        if self.error.is_some() {
            return (Reply::Fail, 0.0);
        }
        let msg = self.decide_message(view);
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
        match reply.and_then(|v| parse_reply(&v, view, &what)) {
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
        let _ = self.send(&json!({
            "type": "end",
            "reason": end.reason.as_str(),
            "exploration_time_s": end.exploration_time_s,
            "explored_fraction": end.explored_fraction,
            "decisions": end.decisions,
        }));
    }
}

/// One check of [`check_program`]: what was checked, and what the program did (`Err`: how it
/// broke the protocol).
#[derive(Debug, Clone, PartialEq)]
pub struct Check {
    pub what: &'static str,
    pub outcome: Result<String, String>,
}

/// Runs a program through a scripted session that touches every message and rule of the
/// protocol (the handshake, a run, a decision and a second attempt at it, a decision with one
/// candidate whose id is not its position, the end, exiting when stdin closes) and returns
/// every check, stopping at the first the program fails: floorcast's compliance checker.
pub fn check_program(program: &StrategyProgram) -> Vec<Check> {
    use sim_core::explore::CandidateView;
    let mut checks = Vec::new();
    let mut push = |what, outcome: Result<String, String>| {
        let ok = outcome.is_ok();
        checks.push(Check { what, outcome });
        ok
    };
    let mut s = match ExternalStrategy::start(program) {
        Ok(s) => s,
        Err(e) => {
            push("hello", Err(e.what));
            return checks;
        }
    };
    let h = s.hello().clone();
    push("hello", Ok(hello_text(&h)));
    let map = check_room();
    let settings = crate::Settings::default();
    let start = sim_core::Pose::new(2.4, 0.7, 0.0);
    let begun = s.begin(
        run_message(
            "check",
            "0",
            1,
            start,
            &settings,
            &program.params,
            &map.frame,
        ),
        false,
    );
    if !push("run", begun.map(|_| "ready".into()).map_err(|e| e.what)) {
        return checks;
    }
    let candidate =
        |id, x, y, path_m, gain_m2| check_candidate(&map, start, &h, id, (x, y), path_m, gain_m2);
    let three = [
        candidate(0, 23, 3, 2.2, 4.0),
        candidate(2, 23, 4, 2.3, 3.5),
        candidate(5, 1, 3, 2.0, 1.0),
    ];
    let rooms = [check_room_view(&map)];
    let view = |decision, attempt, candidates| DecisionView {
        decision,
        attempt,
        time_s: 1.0 + decision as f64,
        pose: start,
        candidates,
        unreachable_goal: None,
        layout: h.needs_layout.then_some(sim_core::explore::LayoutView {
            number: 1,
            rooms: &rooms,
        }),
        map: &map,
        between_m: None,
    };
    let mut ask = |s: &mut ExternalStrategy, what, v: &DecisionView<'_>| {
        let (r, _) = s.decide(v);
        let outcome = match (&r, &s.error) {
            (_, Some(e)) => Err(e.clone()),
            (r, None) => Ok(reply_text(r)),
        };
        (push(what, outcome), r)
    };
    let (ok, first) = ask(&mut s, "decide", &view(0, 0, &three));
    if !ok {
        return checks;
    }
    // The chosen candidate "had no path": asked again without it.
    let rest: Vec<CandidateView> = match first {
        Reply::Choose(id) => three.iter().filter(|c| c.id != id).copied().collect(),
        _ => three[1..].to_vec(),
    };
    if !ask(&mut s, "decide again (attempt 1)", &view(0, 1, &rest)).0 {
        return checks;
    }
    let one = [candidate(7, 1, 2, 2.1, 0.5)];
    if !ask(
        &mut s,
        "decide with one candidate (id 7)",
        &view(1, 0, &one),
    )
    .0
    {
        return checks;
    }
    s.end(&RunEnd {
        reason: sim_core::explore::EndReason::Complete,
        exploration_time_s: 3.0,
        explored_fraction: 1.0,
        decisions: 2,
    });
    let (what, outcome) = exit_check(s.finish());
    push(what, outcome);
    checks
}

/// What the hello of a program says: its name and needs.
fn hello_text(h: &Hello) -> String {
    let mut needs: Vec<&str> = Vec::new();
    if h.needs_layout_gain {
        needs.push("layout_gain");
    }
    if h.needs_layout {
        needs.push("layout");
    }
    if h.needs_map {
        needs.push("map");
    }
    format!("name '{}', needs [{}]", h.name, needs.join(", "))
}

/// The check's map: a room of 4 x 2 m seen from its middle, unknown beyond its open ends.
fn check_room() -> sim_core::grid::OccupancyGrid {
    sim_core::grid::OccupancyGrid::from_ascii(
        "
        ????????????????????????
        ?######################?
        ?.......................
        ?.......................
        ?......................?
        ?......................?
        ?######################?
        ",
        0.2,
    )
}

/// A candidate of the check at cell `(x, y)` of `map`, with what the program's needs ask for.
fn check_candidate(
    map: &sim_core::grid::OccupancyGrid,
    start: sim_core::Pose,
    h: &Hello,
    id: usize,
    (x, y): (i32, i32),
    path_m: f64,
    gain_m2: f64,
) -> sim_core::explore::CandidateView {
    let point = map.frame.world_from_cell(sim_core::grid::Cell::new(x, y));
    sim_core::explore::CandidateView {
        id,
        cell: sim_core::grid::Cell::new(x, y),
        point,
        goal: point,
        frontier_cells: 4,
        distance_m: path_m,
        path_m,
        straight_m: (point - start.position()).norm(),
        gain_m2,
        layout_gain_m2: h.needs_layout_gain.then_some(gain_m2 * 0.5),
        // Room 0 below covers cells x >= 13 (2.6 m to 4.8 m at 0.2 m per cell).
        room: h.needs_layout.then_some(0).filter(|_| x > 12),
    }
}

/// With the need "layout": one predicted room, the right half of the check's room, open.
fn check_room_view(map: &sim_core::grid::OccupancyGrid) -> sim_core::explore::RoomView {
    sim_core::explore::RoomView {
        polygon: [(2.6, 0.4), (4.8, 0.4), (4.8, 1.2), (2.6, 1.2)]
            .iter()
            .map(|&(x, y)| map.frame.origin_m + sim_core::Vec2::new(x, y))
            .collect(),
        state: sim_core::explore::RoomState::Open,
        predicted: true,
        area_m2: 1.76,
        observed_area_m2: 1.6,
        unknown_area_m2: 0.16,
    }
}

/// A reply as the check prints it.
fn reply_text(r: &Reply) -> String {
    match r {
        Reply::Choose(id) => format!("choose {id}"),
        Reply::Rank(ids) => format!("rank {ids:?}"),
        Reply::Goal(p) => format!("goal [{}, {}]", p.x, p.y),
        Reply::Drop(ids) => format!("drop {ids:?}"),
        Reply::Stop => "stop".into(),
        Reply::Pass => "pass".into(),
        Reply::Fail => "failed".into(),
    }
}

/// The check's last step: the program exits when its stdin closes, leaving nothing running.
fn exit_check(
    finished: Result<StrategyStats, StrategyError>,
) -> (&'static str, Result<String, String>) {
    let what = "end, then exit when stdin closes";
    let outcome = match finished {
        Ok(stats) if stats.exited && stats.left_behind => Err("exited, but left processes it started running (floorcast killed them): a strategy ends every process it starts before it exits".into()),
        Ok(stats) if stats.exited => Ok("exited".into()),
        Ok(_) => Err("did not exit within 1 s of its stdin closing (it was killed)".into()),
        Err(e) => Err(e.what),
    };
    (what, outcome)
}

/// The run message's content (besides its type) for a run of a strategy with `params`.
pub fn run_message(
    building_name: &str,
    building_hash: &str,
    seed: u64,
    start: sim_core::Pose,
    settings: &crate::Settings,
    params: &Map<String, Value>,
    frame: &GridFrame,
) -> Value {
    json!({
        "building": building_name,
        "building_hash": building_hash,
        "seed": seed,
        "start": [start.x_m, start.y_m, start.theta_rad],
        "settings": every_setting(settings),
        "params": params,
        "map": {
            "resolution_m": frame.resolution_m,
            "width": frame.width,
            "height": frame.height,
            "origin": [frame.origin_m.x, frame.origin_m.y],
        },
    })
}

/// The settings with every key, those a summary leaves out at their defaults too.
fn every_setting(settings: &crate::Settings) -> Value {
    use crate::settings::{SettingKind, SettingValue, SETTINGS};
    let mut v = json!(settings);
    if let Value::Object(map) = &mut v {
        // The settings a record leaves out at their defaults.
        for info in SETTINGS {
            let value = match (settings.value(info.name), info.kind) {
                (Some(SettingValue::Number(x)), SettingKind::Integer { .. }) => json!(x as u64),
                (Some(SettingValue::Number(x)), _) => json!(x),
                (Some(SettingValue::Bool(b)), _) => json!(b),
                (Some(SettingValue::Word(w)), _) => json!(w),
                (None, _) => continue,
            };
            map.entry(info.name).or_insert(value);
        }
    }
    v
}

fn parse_hello(v: &Value) -> Result<Hello, String> {
    let what = || format!("answered the hello message with {}", quote_json(v));
    if v.get("type").and_then(Value::as_str) != Some("hello") {
        return Err(format!("{} (expected a hello message)", what()));
    }
    match v.get("protocol").and_then(Value::as_u64) {
        Some(PROTOCOL_VERSION) => {}
        Some(p) => {
            return Err(format!(
                "speaks protocol version {p}; this floorcast speaks version {PROTOCOL_VERSION} (docs/strategy-protocol.md)"
            ))
        }
        None => {
            return Err(format!(
                "{} (expected \"protocol\": {PROTOCOL_VERSION})",
                what()
            ))
        }
    }
    let name = v.get("name").and_then(Value::as_str).unwrap_or("");
    if name.trim().is_empty() || name.chars().count() > 100 || name.chars().any(char::is_control) {
        return Err(format!(
            "{} (expected \"name\": a non-empty string of at most 100 characters, no control characters)",
            what()
        ));
    }
    let mut hello = Hello {
        name: name.to_string(),
        needs_layout_gain: false,
        needs_layout: false,
        needs_map: false,
    };
    match v.get("needs") {
        None | Some(Value::Null) => {}
        Some(Value::Array(needs)) => {
            for n in needs {
                match n.as_str() {
                    Some("layout_gain") => hello.needs_layout_gain = true,
                    Some("layout") => hello.needs_layout = true,
                    Some("map") => hello.needs_map = true,
                    _ => {
                        return Err(format!(
                            "needs {} (floorcast offers \"layout_gain\", \"layout\" and \"map\")",
                            quote_json(n)
                        ))
                    }
                }
            }
        }
        Some(other) => {
            return Err(format!(
                "gave \"needs\": {} (expected a list such as [\"layout_gain\", \"map\"])",
                quote_json(other)
            ))
        }
    }
    Ok(hello)
}

fn parse_reply(v: &Value, view: &DecisionView<'_>, what: &str) -> Result<Reply, String> {
    let offered = |id: u64| view.candidates.iter().any(|c| c.id as u64 == id);
    let ids = || {
        let ids: Vec<String> = view.candidates.iter().map(|c| c.id.to_string()).collect();
        clip(&ids.join(", "), 80)
    };
    match v.get("type").and_then(Value::as_str) {
        Some("choose") => match v.get("id").and_then(Value::as_u64) {
            Some(id) if offered(id) => Ok(Reply::Choose(id as usize)),
            Some(id) => Err(format!(
                "chose candidate {id}, which {what} did not offer (it offered {})",
                ids()
            )),
            None => Err(format!(
                "answered {what} with {} (expected \"id\": one of the candidates' ids)",
                quote_json(v)
            )),
        },
        Some(kind @ ("rank" | "drop")) => {
            let verb = if kind == "rank" { "ranked" } else { "dropped" };
            let list = v.get("ids").and_then(Value::as_array);
            let parsed: Option<Vec<u64>> = list.and_then(|l| l.iter().map(Value::as_u64).collect());
            let Some(parsed) = parsed.filter(|p| !p.is_empty()) else {
                return Err(format!(
                    "answered {what} with {} (expected \"ids\": a non-empty list of candidate ids)",
                    quote_json(v)
                ));
            };
            let mut seen = std::collections::BTreeSet::new();
            for &id in &parsed {
                if !offered(id) {
                    return Err(format!(
                        "{verb} candidate {id}, which {what} did not offer (it offered {})",
                        ids()
                    ));
                }
                if !seen.insert(id) {
                    return Err(format!("{verb} candidate {id} twice in {what}"));
                }
            }
            let ids = parsed.into_iter().map(|i| i as usize).collect();
            Ok(if kind == "rank" {
                Reply::Rank(ids)
            } else {
                Reply::Drop(ids)
            })
        }
        Some("goal") => {
            let point = v.get("point").and_then(Value::as_array);
            let xy: Option<Vec<f64>> = point.and_then(|p| p.iter().map(Value::as_f64).collect());
            match xy.as_deref() {
                Some(&[x, y]) => Ok(Reply::Goal(sim_core::Vec2::new(x, y))),
                _ => Err(format!(
                    "answered {what} with {} (expected \"point\": [x, y], metres in the map frame)",
                    quote_json(v)
                )),
            }
        }
        Some("stop") => Ok(Reply::Stop),
        _ => Err(format!(
            "answered {what} with {} (expected a choose, rank, goal, drop or stop message)",
            quote_json(v)
        )),
    }
}

fn quote_json(v: &Value) -> String {
    clip(&v.to_string(), 80)
}

/// At most `n` bytes of `s` (a program's output, echoed in a message), its control characters
/// escaped ([`crate::text::shown`]).
fn clip(s: &str, n: usize) -> String {
    crate::text::shown(s, n)
}

fn write_lines(mut pipe: ChildStdin, lines: mpsc::Receiver<String>) {
    for line in lines {
        if pipe.write_all(line.as_bytes()).is_err() || pipe.flush().is_err() {
            return;
        }
    }
}

fn read_lines(stdout: impl Read, tx: mpsc::Sender<Line>) {
    let mut r = BufReader::new(stdout);
    loop {
        let mut buf = Vec::new();
        let line = match (&mut r)
            .take(MAX_LINE as u64 + 1)
            .read_until(b'\n', &mut buf)
        {
            Ok(0) => Line::Eof,
            Ok(_) if buf.last() != Some(&b'\n') && buf.len() > MAX_LINE => Line::TooLong,
            Ok(_) => {
                let text = String::from_utf8_lossy(&buf);
                Line::Text(text.trim_end_matches(['\n', '\r']).to_string())
            }
            Err(e) => Line::Failed(e.to_string()),
        };
        let done = !matches!(line, Line::Text(_));
        if tx.send(line).is_err() || done {
            return;
        }
    }
}

fn read_stderr(mut stderr: impl Read, sink: Arc<Mutex<Stderr>>) {
    let mut chunk = [0u8; 8192];
    let mut current = Vec::new();
    let last = |current: &[u8], s: &mut Stderr| {
        let line = String::from_utf8_lossy(current).trim().to_string();
        if !line.is_empty() {
            s.last_line = line;
        }
    };
    loop {
        let n = match stderr.read(&mut chunk) {
            Ok(0) | Err(_) => break,
            Ok(n) => n,
        };
        let Ok(mut s) = sink.lock() else { return };
        let text = String::from_utf8_lossy(&chunk[..n]);
        if s.text.len() + text.len() <= MAX_STDERR {
            s.text.push_str(&text);
        }
        for &b in &chunk[..n] {
            if b == b'\n' {
                last(&current, &mut s);
                current.clear();
            } else if current.len() < 4096 {
                current.push(b);
            }
        }
    }
    if let Ok(mut s) = sink.lock() {
        last(&current, &mut s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_run_message_carries_every_setting() {
        let v = every_setting(&crate::Settings::default());
        for s in crate::settings::SETTINGS {
            assert!(v.get(s.name).is_some(), "{} missing", s.name);
        }
    }

    #[test]
    fn relative_names_keep_their_layout_inside_the_root() {
        // (name, levels up, parts) or the error's words.
        type Want = Result<(usize, &'static [&'static str]), &'static str>;
        let cases: [(&str, Want); 6] = [
            ("a.py", Ok((0, &["a.py"]))),
            ("./lib/b.py", Ok((0, &["lib", "b.py"]))),
            ("../../python/m.py", Ok((2, &["python", "m.py"]))),
            ("lib/../c.py", Ok((0, &["c.py"]))),
            ("/etc/passwd", Err("absolute path")),
            ("..", Err("names no file")),
        ];
        for (name, want) in cases {
            match (relative_parts(name), want) {
                (Ok((up, parts)), Ok((u, p))) => {
                    assert_eq!(up, u, "{name}");
                    assert_eq!(parts, p, "{name}");
                }
                (Err(e), Err(needle)) => assert!(e.contains(needle), "{name}: {e}"),
                (got, want) => panic!("{name}: got {got:?}, want {want:?}"),
            }
        }
    }

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

    #[test]
    fn a_materialized_program_is_checked_by_hash() {
        let root = std::env::temp_dir().join(format!("fc-mat-{}", std::process::id()));
        let files = vec![
            ("../s/a.py".to_string(), b"print(1)\n".to_vec()),
            ("../python/m.py".to_string(), b"x = 2\n".to_vec()),
        ];
        let sha = files_sha256(&files);
        let command = vec!["python3".to_string(), "../s/a.py".to_string()];
        let p = StrategyProgram::materialize(
            command.clone(),
            vec!["../python/m.py".into()],
            &files,
            &sha,
            1.0,
            &root,
        )
        .unwrap();
        assert!(p.dir.starts_with(&root));
        assert_eq!(
            std::fs::read(p.dir.join("../python/m.py")).unwrap(),
            b"x = 2\n"
        );
        assert_eq!(p.file_names(), vec!["../s/a.py", "../python/m.py"]);
        let damaged = StrategyProgram::materialize(command, vec![], &files, "00", 1.0, &root);
        assert!(damaged.unwrap_err().contains("damaged"));
        // A file named by an absolute path on the coordinator's machine lands in the job's
        // directory, and the command names it there.
        let abs = vec![("/home/me/s.py".to_string(), b"print(3)\n".to_vec())];
        let p = StrategyProgram::materialize(
            vec!["python3".into(), "/home/me/s.py".into()],
            vec![],
            &abs,
            &files_sha256(&abs),
            1.0,
            &root,
        )
        .unwrap();
        let moved = Path::new(&p.command[1]);
        assert!(moved.starts_with(&root), "{moved:?}");
        assert_eq!(std::fs::read(moved).unwrap(), b"print(3)\n");
        let _ = std::fs::remove_dir_all(&root);
    }
}
