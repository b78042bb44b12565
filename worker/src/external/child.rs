//! A strategy program's process: started in a process group of its own with floorcast's Python
//! module importable ([`spawn`]), its stdin written and its stdout and stderr read by threads of
//! their own ([`Pipes`]), so that a program that stops reading or writing blocks a thread,
//! never the run.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::groups::{kill_group, live_groups};
use super::program::StrategyProgram;
use super::temp::private_temp_dir;

/// The longest reply line read (bytes).
pub(super) const MAX_LINE: usize = 1 << 20;
/// Stderr kept from a program (bytes): its end, the earlier bytes are dropped.
const MAX_STDERR: usize = 1 << 20;

/// floorcast's Python module for strategies (`python/floorcast_strategy.py`, built into the
/// binary): every strategy program finds it on its `PYTHONPATH`, so `import
/// floorcast_strategy` works wherever the program lives, remote workers included, and always
/// speaks this floorcast's protocol.
pub const PYTHON_MODULE: &str = include_str!("../../../python/floorcast_strategy.py");

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

/// A line of the program's stdout, as its reader thread passes it on.
pub(super) enum Line {
    Text(String),
    TooLong,
    Eof,
    Failed(String),
}

/// What the program wrote to stderr: the text kept (its last [`MAX_STDERR`] bytes, up to twice
/// that between two cuts), how many bytes before it were dropped, and its last line.
#[derive(Default)]
pub(super) struct Stderr {
    text: String,
    dropped: usize,
    pub(super) last_line: String,
}

impl Stderr {
    /// The end of what the program wrote, at most [`MAX_STDERR`] bytes, after a line saying
    /// how many bytes were left out before it, if any.
    pub(super) fn kept(&self) -> String {
        let mut cut = self.text.len().saturating_sub(MAX_STDERR);
        while !self.text.is_char_boundary(cut) {
            cut += 1;
        }
        match self.dropped + cut {
            0 => self.text.clone(),
            left_out => format!(
                "[floorcast: the first {left_out} bytes are left out]\n{}",
                &self.text[cut..]
            ),
        }
    }

    /// Adds what the program wrote, dropping the oldest bytes once twice [`MAX_STDERR`] are held
    /// (so that a program that writes a lot costs one copy per megabyte).
    fn push(&mut self, text: &str) {
        self.text.push_str(text);
        if self.text.len() > 2 * MAX_STDERR {
            let mut cut = self.text.len() - MAX_STDERR;
            while !self.text.is_char_boundary(cut) {
                cut += 1;
            }
            self.text.drain(..cut);
            self.dropped += cut;
        }
    }
}

/// The program's stdout as its reader passes it on: in batches of the lines that arrived
/// together (read from the pipe at once), so that a second line written with the first is
/// already here when the first is taken, never still on its way (a race that blamed an
/// unasked answer on the next message).
pub(super) struct Lines {
    rx: Receiver<Vec<Line>>,
    pending: VecDeque<Line>,
}

impl Lines {
    /// The next line if one has arrived and is text (an end of the pipe is left to be read).
    pub(super) fn try_recv_text(&mut self) -> Option<String> {
        if self.pending.is_empty() {
            self.pending.extend(self.rx.try_recv().ok()?);
        }
        match self.pending.pop_front()? {
            Line::Text(t) => Some(t),
            other => {
                self.pending.push_front(other);
                None
            }
        }
    }

    /// The next line, waiting at most `timeout` for it.
    pub(super) fn recv_timeout(&mut self, timeout: Duration) -> Result<Line, RecvTimeoutError> {
        if self.pending.is_empty() {
            self.pending.extend(self.rx.recv_timeout(timeout)?);
        }
        // A batch is never empty (`read_lines`); an empty one reads as the pipe closed.
        self.pending
            .pop_front()
            .ok_or(RecvTimeoutError::Disconnected)
    }
}

/// A started program's pipes, each served by a thread of its own.
pub(super) struct Pipes {
    /// Lines to write to the program's stdin (`None` once closed).
    pub(super) stdin: Option<mpsc::Sender<String>>,
    /// The program's stdout, line by line.
    pub(super) lines: Lines,
    pub(super) stderr: Arc<Mutex<Stderr>>,
    stderr_reader: Option<std::thread::JoinHandle<()>>,
}

impl Pipes {
    /// Waits (at most a second) for the stderr reader to take in what the program wrote before
    /// it ended.
    pub(super) fn join_stderr(&mut self) {
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
}

/// Starts `program` with floorcast's Python module importable (in the folder returned, removed
/// with it) and its pipes' threads; an error says what to do.
pub(super) fn spawn(
    program: &StrategyProgram,
) -> Result<(Child, tempfile::TempDir, Pipes), String> {
    let python = python_dir()?;
    let mut cmd = program_command(program, python.path());
    let mut child = spawn_registered(&mut cmd, program)?;
    match start_pipes(&mut child) {
        Ok(pipes) => Ok((child, python, pipes)),
        // One the system refuses is an error, not a panic: the program is stopped (the threads
        // already started end with its pipes).
        Err(e) => {
            kill_group(child.id());
            live_groups(|g| g.remove(&child.id()));
            let _ = child.kill();
            let _ = child.wait();
            Err(format!(
                "cannot start a thread for the program's pipes ({e}): the system is out of threads or memory; run fewer jobs at once"
            ))
        }
    }
}

/// The threads that serve `child`'s three pipes.
fn start_pipes(child: &mut Child) -> std::io::Result<Pipes> {
    let stdin = match child.stdin.take() {
        Some(pipe) => {
            let (tx, rx) = mpsc::channel::<String>();
            crate::spawn_thread(move || write_lines(pipe, rx))?;
            Some(tx)
        }
        None => None,
    };
    let stdout = child.stdout.take().expect("stdout is piped");
    let stderr_pipe = child.stderr.take().expect("stderr is piped");
    let (tx, rx) = mpsc::channel();
    crate::spawn_thread(move || read_lines(stdout, tx))?;
    let lines = Lines {
        rx,
        pending: VecDeque::new(),
    };
    let stderr = Arc::new(Mutex::new(Stderr::default()));
    let sink = Arc::clone(&stderr);
    let stderr_reader = Some(crate::spawn_thread(move || read_stderr(stderr_pipe, sink))?);
    Ok(Pipes {
        stdin,
        lines,
        stderr,
        stderr_reader,
    })
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

fn write_lines(mut pipe: ChildStdin, lines: mpsc::Receiver<String>) {
    for line in lines {
        if pipe.write_all(line.as_bytes()).is_err() || pipe.flush().is_err() {
            return;
        }
    }
}

/// Reads `stdout` line by line and passes the lines on in batches: a line and those that arrived
/// with it (already in the reader's buffer, complete) go together.
fn read_lines(stdout: impl Read, tx: mpsc::Sender<Vec<Line>>) {
    let mut r = BufReader::new(stdout);
    loop {
        let mut batch = Vec::new();
        let done = loop {
            let line = read_line(&mut r);
            let done = !matches!(line, Line::Text(_));
            batch.push(line);
            if done || !r.buffer().contains(&b'\n') {
                break done;
            }
        };
        if tx.send(batch).is_err() || done {
            return;
        }
    }
}

/// One line of at most [`MAX_LINE`] bytes.
fn read_line(r: &mut BufReader<impl Read>) -> Line {
    let mut buf = Vec::new();
    match r.take(MAX_LINE as u64 + 1).read_until(b'\n', &mut buf) {
        Ok(0) => Line::Eof,
        Ok(_) if buf.last() != Some(&b'\n') && buf.len() > MAX_LINE => Line::TooLong,
        Ok(_) => {
            let text = String::from_utf8_lossy(&buf);
            Line::Text(text.trim_end_matches(['\n', '\r']).to_string())
        }
        Err(e) => Line::Failed(e.to_string()),
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
        s.push(&String::from_utf8_lossy(&chunk[..n]));
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

    /// A program's stderr is kept to its end: up to [`MAX_STDERR`] bytes as written, more cut
    /// from the front (at a character boundary) after a line saying how much was left out.
    #[test]
    fn stderr_keeps_its_end() {
        let line = "é".repeat(1000) + "\n"; // 2001 bytes
                                            // Lines written: within the bound, at it, just past it.
        for lines in &[1, 524, 525] {
            let mut s = Stderr::default();
            for _ in 0..*lines {
                s.push(&line);
            }
            let kept = s.kept();
            let written = 2001 * lines;
            if written <= MAX_STDERR {
                assert_eq!(kept, line.repeat(*lines), "{lines} lines");
                continue;
            }
            let (note, rest) = kept.split_once('\n').unwrap();
            let left_out = written - rest.len();
            assert_eq!(
                note,
                format!("[floorcast: the first {left_out} bytes are left out]")
            );
            assert!(
                rest.len() <= MAX_STDERR && rest.len() + 1 >= MAX_STDERR,
                "{lines}"
            );
            assert!(line.repeat(*lines).ends_with(rest));
        }
        // Written by the megabyte: the text held stays within twice the bound, the end kept.
        let mut s = Stderr::default();
        for i in 0..2000 {
            s.push(&format!("{i:06} {line}"));
            assert!(s.text.len() <= 2 * MAX_STDERR + line.len() + 7);
        }
        let kept = s.kept();
        assert!(kept.ends_with(&format!("001999 {line}")), "the last line");
        assert!(kept.starts_with("[floorcast: the first "));
    }

    /// A reader that hands out its chunks one `read` at a time, as a pipe does.
    struct Chunks(VecDeque<Vec<u8>>);

    impl Read for Chunks {
        fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
            let Some(mut chunk) = self.0.pop_front() else {
                return Ok(0);
            };
            let n = chunk.len().min(out.len());
            out[..n].copy_from_slice(&chunk[..n]);
            if n < chunk.len() {
                self.0.push_front(chunk.split_off(n));
            }
            Ok(n)
        }
    }

    fn texts(batch: &[Line]) -> Vec<String> {
        batch
            .iter()
            .map(|l| match l {
                Line::Text(t) => t.clone(),
                Line::Eof => "<eof>".into(),
                Line::TooLong => "<too long>".into(),
                Line::Failed(e) => format!("<failed {e}>"),
            })
            .collect()
    }

    #[test]
    fn lines_that_arrive_together_are_passed_on_together() {
        // (chunks as the pipe delivers them, batches expected)
        let cases: &[(&[&str], &[&[&str]])] = &[
            (&["a\nb\n"], &[&["a", "b"], &["<eof>"]]),
            (&["a\n", "b\n"], &[&["a"], &["b"], &["<eof>"]]),
            (&["a\nb", "c\n"], &[&["a"], &["bc"], &["<eof>"]]),
            (
                &["a\r\nb\nc\n", "d"],
                &[&["a", "b", "c"], &["d"], &["<eof>"]],
            ),
            (&[""], &[&["<eof>"]]),
        ];
        for (chunks, expected) in cases {
            let reader = Chunks(chunks.iter().map(|c| c.as_bytes().to_vec()).collect());
            let (tx, rx) = mpsc::channel();
            read_lines(reader, tx);
            let got: Vec<Vec<String>> = rx.iter().map(|b| texts(&b)).collect();
            assert_eq!(got, *expected, "{chunks:?}");
        }
    }

    #[test]
    fn an_early_line_is_taken_but_an_end_is_left_to_be_read() {
        let (tx, rx) = mpsc::channel();
        let mut lines = Lines {
            rx,
            pending: VecDeque::new(),
        };
        assert!(lines.try_recv_text().is_none(), "nothing has arrived");
        tx.send(vec![Line::Text("one".into()), Line::Text("two".into())])
            .unwrap();
        tx.send(vec![Line::Eof]).unwrap();
        drop(tx);
        let wait = Duration::from_millis(10);
        assert!(matches!(lines.recv_timeout(wait), Ok(Line::Text(t)) if t == "one"));
        assert_eq!(
            lines.try_recv_text().as_deref(),
            Some("two"),
            "sent with one"
        );
        assert!(lines.try_recv_text().is_none(), "the end is not text");
        assert!(
            matches!(lines.recv_timeout(wait), Ok(Line::Eof)),
            "and is kept"
        );
        assert!(matches!(
            lines.recv_timeout(wait),
            Err(RecvTimeoutError::Disconnected)
        ));
    }
}
