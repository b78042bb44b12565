//! The malformed-input corpus (`tests/malformed/cases.toml`): every case fails cleanly (exit code
//! 2, one `error: ...` line naming the file and the field, no panic) within bounded time and
//! memory, and leaves nothing behind. All failing cases are reported at once, by name.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use serde::Deserialize;

/// Longest a case may take.
const TIMEOUT: Duration = Duration::from_secs(20);
/// Address space a case may use (bytes), enforced with `prlimit` where it exists.
const MEMORY_LIMIT_BYTES: u64 = 4 << 30;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Corpus {
    case: Vec<Case>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Case {
    name: String,
    args: Vec<String>,
    /// Words the error line must hold.
    expect: Vec<String>,
    /// Paths (in the case's directory) that must not exist afterwards.
    #[serde(default)]
    absent: Vec<String>,
    /// Files that must be byte-identical afterwards.
    #[serde(default)]
    unchanged: Vec<String>,
    /// Directories to create before the run.
    #[serde(default)]
    mkdir: Vec<String>,
    /// Named pipes (FIFOs) to create before the run: reading one would block forever.
    #[serde(default)]
    fifo: Vec<String>,
    /// Words that must appear exactly once (an OS error said once, not twice).
    #[serde(default)]
    once: Vec<String>,
    /// Words that must not appear (Rust debug text).
    #[serde(default)]
    never: Vec<String>,
    /// Files to write before the run, in order: inputs too large or too deep to commit.
    #[serde(default)]
    generate: Vec<Generate>,
}

/// A file written into the case's directory before the run: the file `from` (in that
/// directory: a copy of `files/`, or a file an earlier entry generated; none when empty) with
/// `repeat` written `times` times before its first `at` (at its end when `at` is empty); `{i}`
/// in `repeat` becomes the repetition's number (0, 1, ...). Written as it is made: a 100 MB
/// file costs no memory.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Generate {
    file: String,
    #[serde(default)]
    from: String,
    #[serde(default)]
    at: String,
    repeat: String,
    times: u64,
}

impl Generate {
    fn write(&self, dir: &Path) {
        use std::io::Write;
        let base = if self.from.is_empty() {
            String::new()
        } else {
            std::fs::read_to_string(dir.join(&self.from)).unwrap()
        };
        let cut = if self.at.is_empty() {
            base.len()
        } else {
            base.find(&self.at)
                .unwrap_or_else(|| panic!("{:?} not in {}", self.at, self.from))
        };
        let file = std::fs::File::create(dir.join(&self.file)).unwrap();
        let mut out = std::io::BufWriter::new(file);
        out.write_all(&base.as_bytes()[..cut]).unwrap();
        for i in 0..self.times {
            if self.repeat.contains("{i}") {
                out.write_all(self.repeat.replace("{i}", &i.to_string()).as_bytes())
            } else {
                out.write_all(self.repeat.as_bytes())
            }
            .unwrap();
        }
        out.write_all(&base.as_bytes()[cut..]).unwrap();
        out.flush().unwrap();
    }
}

fn corpus_dir() -> PathBuf {
    common::repo().join("tests/malformed")
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), &target).unwrap();
        }
    }
}

/// Runs `cmd` with a timeout; `None` when it had to be killed.
fn run_bounded(mut cmd: Command) -> Option<(Option<i32>, String)> {
    let mut child = cmd
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("floorcast starts");
    let mut stderr = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        use std::io::Read;
        let _ = stderr.read_to_string(&mut s);
        s
    });
    let t0 = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return Some((status.code(), reader.join().unwrap()));
        }
        if t0.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// What is wrong with one case's run (empty: it passed).
fn check_case(case: &Case) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    copy_dir(&corpus_dir().join("files"), tmp);
    std::fs::copy(
        common::repo().join("buildings/small.toml"),
        tmp.join("small.toml"),
    )
    .unwrap();
    for d in &case.mkdir {
        std::fs::create_dir_all(tmp.join(d)).unwrap();
    }
    for g in &case.generate {
        g.write(tmp);
    }
    for f in &case.fifo {
        let made = Command::new("mkfifo").arg(tmp.join(f)).status().unwrap();
        assert!(made.success(), "mkfifo {f}");
    }
    let before: Vec<Option<Vec<u8>>> = case
        .unchanged
        .iter()
        .map(|f| std::fs::read(tmp.join(f)).ok())
        .collect();
    let maps = common::maps_dir().display().to_string();
    let args: Vec<String> = case
        .args
        .iter()
        .map(|a| a.replace("{maps}", &maps))
        .collect();
    let bin = env!("CARGO_BIN_EXE_floorcast");
    let mut cmd = if Path::new("/usr/bin/prlimit").exists() {
        let mut c = Command::new("/usr/bin/prlimit");
        c.arg(format!("--as={MEMORY_LIMIT_BYTES}"))
            .arg("--")
            .arg(bin);
        c
    } else {
        Command::new(bin)
    };
    cmd.args(&args).current_dir(tmp);
    let mut problems = Vec::new();
    let Some((code, err)) = run_bounded(cmd) else {
        return vec![format!("did not finish within {} s", TIMEOUT.as_secs())];
    };
    if code != Some(2) {
        problems.push(format!("exit code {code:?}, expected 2"));
    }
    if err.contains("panicked") || err.contains("RUST_BACKTRACE") {
        problems.push("panicked".into());
    }
    let lines: Vec<&str> = err.lines().collect();
    if lines.len() != 1 || !lines[0].starts_with("error: ") {
        problems.push(format!(
            "expected one `error: ...` line, got {} lines",
            lines.len()
        ));
    }
    for w in &case.expect {
        if !err.contains(w.as_str()) {
            problems.push(format!("{w:?} missing"));
        }
    }
    for w in &case.once {
        let n = err.matches(w.as_str()).count();
        if n != 1 {
            problems.push(format!("{w:?} appears {n} times, expected once"));
        }
    }
    for w in &case.never {
        if err.contains(w.as_str()) {
            problems.push(format!("{w:?} appears"));
        }
    }
    for p in &case.absent {
        if tmp.join(p).exists() {
            problems.push(format!("{p} was created"));
        }
    }
    for (f, b) in case.unchanged.iter().zip(before) {
        if std::fs::read(tmp.join(f)).ok() != b {
            problems.push(format!("{f} was changed"));
        }
    }
    if !problems.is_empty() {
        problems.push(format!("stderr: {}", err.trim()));
    }
    problems
}

#[test]
fn every_malformed_input_fails_cleanly() {
    let text = std::fs::read_to_string(corpus_dir().join("cases.toml")).unwrap();
    let corpus: Corpus = toml::from_str(&text).unwrap();
    assert!(corpus.case.len() >= 60, "{} cases", corpus.case.len());
    let mut names = std::collections::BTreeSet::new();
    let mut failures = Vec::new();
    for case in &corpus.case {
        assert!(names.insert(case.name.clone()), "case {} twice", case.name);
        let problems = check_case(case);
        if !problems.is_empty() {
            failures.push(format!("{}: {}", case.name, problems.join("; ")));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} malformed-input cases failed:\n{}",
        failures.len(),
        corpus.case.len(),
        failures.join("\n")
    );
}

/// A job that could only fail (here: a building without free space to start in) is found
/// when the grid is checked as a whole, before anything runs: `run` exits with code 2 and one
/// line naming the grid, the building and why. (A job that fails while running, a panic, is
/// stored as a failed job: `coordinator::run`'s tests.)
#[test]
fn run_refuses_a_grid_with_a_job_that_cannot_start() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = dir.path();
    std::fs::write(
        tmp.join("solid.toml"),
        "format = \"floorcast-building\"\nversion = 1\noutline = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0], [0.0, 0.0]]\n[[solids]]\npolygon = [[-1.0, -1.0], [5.0, -1.0], [5.0, 5.0], [-1.0, 5.0], [-1.0, -1.0]]\n",
    )
    .unwrap();
    std::fs::write(
        tmp.join("grid.toml"),
        "format = \"floorcast-grid\"\nversion = 1\nname = \"f\"\nbuildings = [\"solid.toml\"]\nseeds = [7]\n[[strategies]]\nname = \"baseline\"\n",
    )
    .unwrap();
    let o = common::floorcast()
        .args([
            "run",
            "grid.toml",
            "--results",
            "r",
            "--quiet",
            "--workers",
            "1",
        ])
        .current_dir(tmp)
        .output()
        .unwrap();
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    for w in ["grid.toml: buildings:", "solid.toml", "no free space"] {
        assert!(err.contains(w), "{w:?} not in {err}");
    }
    assert!(!tmp.join("r/results.sqlite").exists());
}

/// A polygon whose edges cross by a slip (one corner 0.4 m past its neighbour edge) is repaired:
/// the building loads (exit 0) with one `warning:` line on stderr naming the file, the polygon
/// and the size of the change, also in `--json`; `--strict` refuses it (the corpus's
/// `*-slip-strict*` cases). (args, words of the warning)
#[test]
fn slips_load_with_a_warning() {
    let files = corpus_dir().join("files");
    let cases: &[(&[&str], &[&str])] = &[
        (
            &["building", "check", "plan-slip.xml"],
            &[
                "warning: plan-slip.xml: space[1] (a)/bounding_polygon: the 'office' (type R): the edge from (-0.2, -3.0) to (10.0, -3.0) crosses the edge from (0.0, -13.0) to (0.0, -2.6) at (0.0, -3.0); repaired as the largest simple polygon: 1 crossing; the loop beyond it dropped: the area changed by 0.04 m² (0.04 % of the 100.0 m² kept) and a corner moved by up to 0.4 m",
            ],
        ),
        (
            &["building", "check", "slip.toml"],
            &[
                "warning: slip.toml: rooms[1].polygon: the room 2 ('office'): ",
                "at (1.0, 5.0)",
                "the area changed by 0.04 m²",
                "a corner moved by up to 0.4 m",
            ],
        ),
        (
            &["building", "check", "--json", "slip.toml"],
            &["warning: slip.toml: rooms[1].polygon: the room 2 ('office'): "],
        ),
    ];
    for (args, words) in cases {
        let o = common::floorcast()
            .args(*args)
            .current_dir(&files)
            .output()
            .unwrap();
        let err = common::stderr(&o);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        for w in *words {
            assert!(err.contains(w), "{args:?}: {w:?} not in {err}");
        }
        let out = common::stdout(&o);
        if args.contains(&"--json") {
            let v: serde_json::Value = serde_json::from_str(&out).unwrap();
            let ws = v["warnings"].as_array().unwrap();
            assert_eq!(ws.len(), 1, "{out}");
            assert!(
                ws[0]
                    .as_str()
                    .unwrap()
                    .contains("a corner moved by up to 0.4 m"),
                "{out}"
            );
        } else {
            assert!(out.contains("\nrooms:   "), "{out}");
        }
    }
}
