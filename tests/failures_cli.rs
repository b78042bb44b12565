//! Running grids for real (issue 60): a failed job's stderr and its history are kept, `run
//! --retry-failed` runs it again once fixed, `report --failures` shows them; `explore` keeps a
//! failing strategy's stderr; a killed floorcast's private folders are removed at the next
//! start; the provenance names floorcast's own commit.

mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;

use common::*;

/// A strategy that raises (a Python traceback on stderr) at its first decision while the file
/// `broken` lies beside it (or in `FLAKY_DIR`), sleeps there while `slow` does (after writing its process id to
/// `started`), and else ranks the candidates as `nearest` does. Its files do not change when
/// it is "fixed" (the flag files are not its files), so its jobs keep their ids.
const FLAKY: &str = r#"import os, time
from floorcast_strategy import Strategy, run

# Beside the program, or where FLAKY_DIR says (a remote worker runs a copy of it).
HERE = os.environ.get("FLAKY_DIR") or os.path.dirname(os.path.abspath(__file__))


class Flaky(Strategy):
    name = "flaky.py"

    def decide(self, d):
        if os.path.exists(os.path.join(HERE, "slow")):
            with open(os.path.join(HERE, "started"), "w") as f:
                f.write(str(os.getpid()))
            time.sleep(300)
        if os.path.exists(os.path.join(HERE, "broken")):
            raise ValueError("flaky.py is broken: remove the flag file")
        ranked = sorted(d["candidates"], key=lambda c: (c["path_m"], c["id"]))
        return [c["id"] for c in ranked]


run(Flaky())
"#;

const TRACEBACK_FIRST: &str = "Traceback (most recent call last):";
const TRACEBACK_LAST: &str = "ValueError: flaky.py is broken: remove the flag file";

/// A project with `strategies/flaky.py` and `grids/grid.toml` running it on the small
/// building with `seeds`, its flag files named in `flags` set.
fn project(dir: &Path, seeds: &str, flags: &[&str]) -> PathBuf {
    std::fs::create_dir_all(dir.join("strategies")).unwrap();
    std::fs::create_dir_all(dir.join("grids")).unwrap();
    std::fs::write(dir.join("strategies/flaky.py"), FLAKY).unwrap();
    for f in flags {
        std::fs::write(dir.join("strategies").join(f), "").unwrap();
    }
    let text = format!(
        "format = \"floorcast-grid\"\nversion = 1\nname = \"flaky\"\nbuildings = [\"{}\"]\nseeds = {seeds}\n[[strategies]]\nlabel = \"flaky.py\"\ncommand = [\"python3\", \"../strategies/flaky.py\"]\n[settings]\ntime_limit_s = 300\n",
        repo().join("buildings/small.toml").display()
    );
    let g = dir.join("grids/grid.toml");
    std::fs::write(&g, text).unwrap();
    g
}

/// `floorcast ARGS` with an exit code, stdout and stderr.
fn floorcast_in(args: &[&str], cwd: &Path, tmpdir: &Path) -> (Option<i32>, String, String) {
    let o = floorcast()
        .args(args)
        .current_dir(cwd)
        .env("TMPDIR", tmpdir)
        .output()
        .unwrap();
    (o.status.code(), stdout(&o), stderr(&o))
}

/// The store's failures table: (job, attempt, error, stderr) by job and attempt.
fn failures_table(res: &Path) -> Vec<(String, i64, String, Option<String>)> {
    let conn = rusqlite::Connection::open(res.join("results.sqlite")).unwrap();
    let mut st = conn
        .prepare(
            "SELECT job_id, attempt, error, stderr_tail FROM failures ORDER BY job_id, attempt",
        )
        .unwrap();
    st.query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?)))
        .unwrap()
        .map(Result::unwrap)
        .collect()
}

/// `report RES --failures --json FILE` shows both jobs' failure, the traceback's first and
/// last lines (as text and in the JSON), and exits with 0.
fn assert_failures_shown(res: &Path, cwd: &Path, tmp: &Path) {
    let r = res.to_str().unwrap();
    let json = cwd.join("report.json");
    let (code, out, err) = floorcast_in(
        &["report", r, "--failures", "--json", json.to_str().unwrap()],
        cwd,
        tmp,
    );
    assert_eq!(code, Some(0), "{err}");
    assert!(
        out.contains("failures: 2 job(s) failing, 0 job(s) failed before they succeeded"),
        "{out}"
    );
    for seed in [1, 2] {
        assert!(
            out.contains(&format!(
                "small flaky.py (strategy flaky.py) seed {seed}: failed, 1 attempt(s):"
            )),
            "{out}"
        );
    }
    assert_eq!(
        out.matches(&format!("    | {TRACEBACK_FIRST}")).count(),
        2,
        "{out}"
    );
    assert_eq!(
        out.matches(&format!("    | {TRACEBACK_LAST}")).count(),
        2,
        "{out}"
    );
    assert!(out.contains("its last stderr line"), "the error: {out}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let listed = v["failures"].as_array().unwrap();
    assert_eq!(listed.len(), 2, "{v}");
    for job in listed {
        assert_eq!(job["status"], "failed");
        let a = &job["attempts"][0];
        assert_eq!(a["stderr_head"][0], TRACEBACK_FIRST, "{a}");
        let tail = a["stderr_tail"].as_array().unwrap();
        let last = if tail.is_empty() {
            &a["stderr_head"]
        } else {
            &a["stderr_tail"]
        };
        let last = last.as_array().unwrap().last().unwrap();
        assert_eq!(last, TRACEBACK_LAST, "{a}");
    }
}

#[test]
fn a_failed_job_is_kept_shown_and_retried_once_fixed() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let g = project(dir.path(), "[1, 2]", &["broken"]);
    let (g, res) = (g.to_str().unwrap(), dir.path().join("res"));
    let r = res.to_str().unwrap();
    let cwd = dir.path();

    // The first run: both jobs fail, run says so and how to run them again.
    let (code, out, err) = floorcast_in(&["run", g, "--results", r, "-q"], cwd, tmp.path());
    assert_eq!(code, Some(2), "{out}{err}");
    // (Each failed job is logged as it comes; the error is the last line.)
    let last = err.trim().lines().last().unwrap();
    assert!(last.starts_with("error: 2 of 2 jobs failed"), "{err}");
    assert!(
        last.contains("--retry-failed") && last.contains("--failures"),
        "{last}"
    );
    // Again without the flag: nothing runs, and the message says what would.
    let (code, out, err) = floorcast_in(&["run", g, "--results", r, "-q"], cwd, tmp.path());
    assert_eq!(code, Some(2), "{out}{err}");
    assert!(
        out.contains("nothing to do")
            && out.contains("2 of them failed: --retry-failed runs them again"),
        "{out}"
    );

    // The failures, with the traceback's first and last lines, and exit code 0.
    assert_failures_shown(&res, cwd, tmp.path());
    let first = failures_table(&res);
    assert_eq!(first.len(), 2, "one failure per job: {first:?}");

    // Fixed: --retry-failed runs both again and stores them ok; the failures stay.
    std::fs::remove_file(dir.path().join("strategies/broken")).unwrap();
    let (code, out, err) = floorcast_in(
        &["run", g, "--results", r, "-q", "--retry-failed"],
        cwd,
        tmp.path(),
    );
    assert_eq!(code, Some(0), "{out}{err}");
    assert!(
        out.contains("--retry-failed: 2 failed jobs run again"),
        "{out}"
    );
    let rows = report_rows(&res);
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(|r| r["status"] == "ok"), "{rows:?}");
    assert_eq!(
        failures_table(&res),
        first,
        "the failures are kept as they were"
    );
    for (_, attempt, error, stderr) in &first {
        assert_eq!(*attempt, 1);
        assert!(error.contains(TRACEBACK_LAST), "{error}");
        let stderr = stderr.as_deref().unwrap();
        assert!(stderr.starts_with(TRACEBACK_FIRST), "{stderr}");
        assert!(stderr.trim_end().ends_with(TRACEBACK_LAST), "{stderr}");
    }
    let (code, out, _) = floorcast_in(&["report", r, "--failures"], cwd, tmp.path());
    assert_eq!(code, Some(0));
    assert!(
        out.contains("failures: 0 job(s) failing, 2 job(s) failed before they succeeded"),
        "{out}"
    );
    assert_eq!(
        out.matches("later succeeded (attempt 2); earlier failures:")
            .count(),
        2,
        "{out}"
    );
    // Nothing left to retry.
    let (code, out, err) = floorcast_in(
        &["run", g, "--results", r, "-q", "--retry-failed"],
        cwd,
        tmp.path(),
    );
    assert_eq!(code, Some(0), "{out}{err}");
    assert!(
        out.contains("nothing to do") && !out.contains("--retry-failed"),
        "{out}"
    );
}

#[test]
fn explore_keeps_a_failing_strategys_stderr() {
    let dir = tempfile::tempdir().unwrap();
    project(dir.path(), "[1]", &["broken"]);
    let out = dir.path().join("out");
    let o = floorcast()
        .args([
            "explore",
            "--building",
            repo().join("buildings/small.toml").to_str().unwrap(),
            "--strategy-command",
            "python3 strategies/flaky.py",
            "--out",
            out.to_str().unwrap(),
            "-q",
        ])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_clean_failure(&o, &[TRACEBACK_LAST, "strategy-stderr.txt"]);
    let text = std::fs::read_to_string(out.join("strategy-stderr.txt")).unwrap();
    assert!(text.starts_with(TRACEBACK_FIRST), "{text}");
    assert_eq!(
        text.trim_end().lines().last(),
        Some(TRACEBACK_LAST),
        "{text}"
    );
    assert!(
        !out.join("summary.json").exists(),
        "a failed run has no summary"
    );
}

/// The entries of `dir` whose names start with `floorcast-`.
fn floorcast_folders(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("floorcast-"))
        .collect();
    v.sort();
    v
}

#[test]
fn a_run_killed_mid_job_leaves_no_folder_after_a_restart() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let g = project(dir.path(), "[1]", &["slow"]);
    let res = dir.path().join("res");
    let mut child = floorcast()
        .args([
            "run",
            g.to_str().unwrap(),
            "--results",
            res.to_str().unwrap(),
            "-q",
        ])
        .current_dir(dir.path())
        .env("TMPDIR", tmp.path())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Mid-job: the strategy is deciding (and sleeps).
    let started = dir.path().join("strategies/started");
    let t0 = std::time::Instant::now();
    while !started.exists() || std::fs::read_to_string(&started).unwrap().is_empty() {
        assert!(
            t0.elapsed() < Duration::from_secs(120),
            "the job did not start"
        );
        assert!(child.try_wait().unwrap().is_none(), "run ended early");
        std::thread::sleep(Duration::from_millis(50));
    }
    let left = floorcast_folders(tmp.path());
    assert!(
        left.iter().any(|n| n.starts_with("floorcast-python-")),
        "the job's folder: {left:?}"
    );
    send_signal(child.id(), "9");
    child.wait().unwrap();
    // The program outlives floorcast (in its own process group): ended here.
    let program = std::fs::read_to_string(&started).unwrap();
    let _ = std::process::Command::new("kill")
        .args(["-9", program.trim()])
        .status();
    assert_eq!(
        floorcast_folders(tmp.path()),
        left,
        "kill -9 leaves the folder"
    );

    // Restarted (the strategy no longer sleeps): the folder of the dead run goes.
    std::fs::remove_file(dir.path().join("strategies/slow")).unwrap();
    let (code, out, err) = floorcast_in(
        &[
            "run",
            g.to_str().unwrap(),
            "--results",
            res.to_str().unwrap(),
        ],
        dir.path(),
        tmp.path(),
    );
    assert_eq!(code, Some(0), "{out}{err}");
    assert!(
        err.contains(&format!("removed {} temporary folder(s)", left.len())),
        "{err}"
    );
    assert_eq!(floorcast_folders(tmp.path()), Vec::<String>::new());
}

/// Waits until the flaky strategy, sleeping mid-job, wrote its process id to `started`.
fn wait_started(started: &Path, child: &mut std::process::Child) -> String {
    let t0 = std::time::Instant::now();
    loop {
        if let Ok(pid) = std::fs::read_to_string(started) {
            if !pid.is_empty() {
                return pid.trim().to_string();
            }
        }
        assert!(
            t0.elapsed() < Duration::from_secs(120),
            "the job did not start"
        );
        assert!(child.try_wait().unwrap().is_none(), "it ended early");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Waits for `child` to end (at most `s` seconds); its exit code.
fn wait_for(child: &mut std::process::Child, s: u64) -> Option<i32> {
    let t0 = std::time::Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status.code();
        }
        if t0.elapsed() > Duration::from_secs(s) {
            let _ = child.kill();
            panic!("did not end within {s} s");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn a_worker_killed_mid_job_leaves_no_folder_after_a_restart() {
    let dir = tempfile::tempdir().unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let g = project(dir.path(), "[1]", &["slow"]);
    let flags = dir.path().join("strategies");
    let res = dir.path().join("res");
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let mut coordinator = floorcast()
        .args([
            "run",
            g.to_str().unwrap(),
            "--results",
            res.to_str().unwrap(),
        ])
        .args([
            "--workers",
            "0",
            "-q",
            "--lease-s",
            "2",
            "--listen",
            &endpoint,
        ])
        .current_dir(dir.path())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let worker = |stderr: std::process::Stdio| {
        floorcast()
            .args([
                "worker",
                "--connect",
                &endpoint,
                "--jobs",
                "1",
                "--wait-s",
                "60",
            ])
            .current_dir(dir.path())
            .env("TMPDIR", tmp.path())
            .env("FLAKY_DIR", &flags)
            .stdout(std::process::Stdio::null())
            .stderr(stderr)
            .spawn()
            .unwrap()
    };
    let mut first = worker(std::process::Stdio::null());
    let program = wait_started(&flags.join("started"), &mut first);
    let left = floorcast_folders(tmp.path());
    assert!(
        left.iter().any(|n| n.starts_with("floorcast-job-")),
        "the job's folder: {left:?}"
    );
    for pid in [first.id().to_string(), program] {
        let _ = std::process::Command::new("kill")
            .args(["-9", &pid])
            .status();
    }
    first.wait().unwrap();
    assert_eq!(
        floorcast_folders(tmp.path()),
        left,
        "kill -9 leaves the folders"
    );

    // A new worker (the strategy no longer sleeps) removes them, and takes the job again once
    // its lease ran out.
    std::fs::remove_file(flags.join("slow")).unwrap();
    let second = worker(std::process::Stdio::piped());
    let out = second.wait_with_output().unwrap();
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        err.contains(&format!("removed {} temporary folder(s)", left.len())),
        "{err}"
    );
    assert_eq!(wait_for(&mut coordinator, 120), Some(0));
    assert_eq!(floorcast_folders(tmp.path()), Vec::<String>::new());
    assert_eq!(report_rows(&res)[0]["status"], "ok");
}

/// `git ARGS` in `dir`, its output trimmed.
fn git(dir: &Path, args: &[&str]) -> String {
    let o = std::process::Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(args)
        .output()
        .unwrap();
    assert!(o.status.success(), "git {args:?}: {}", stderr(&o));
    stdout(&o).trim().to_string()
}

#[test]
fn provenance_names_floorcasts_own_commit_not_the_current_directorys() {
    let own = git(&repo(), &["rev-parse", "HEAD"]);
    assert_eq!(own.len(), 40, "{own}");
    // The user's experiments, in a repository of their own.
    let dir = tempfile::tempdir().unwrap();
    git(dir.path(), &["init", "-q"]);
    std::fs::write(dir.path().join("notes.txt"), "mine").unwrap();
    git(dir.path(), &["add", "notes.txt"]);
    git(
        dir.path(),
        &[
            "-c",
            "user.name=t",
            "-c",
            "user.email=t@t",
            "commit",
            "-q",
            "-m",
            "mine",
        ],
    );
    let theirs = git(dir.path(), &["rev-parse", "HEAD"]);
    assert_ne!(own, theirs);
    let g = dir.path().join("grid.toml");
    std::fs::write(
        &g,
        format!(
            "format = \"floorcast-grid\"\nversion = 1\nname = \"p\"\nbuildings = [\"{}\"]\nseeds = [1]\n[[strategies]]\nname = \"baseline\"\n[settings]\ntime_limit_s = 30\n",
            repo().join("buildings/small.toml").display()
        ),
    )
    .unwrap();
    let (code, out, err) = floorcast_in(
        &["run", "grid.toml", "--results", "res", "-q", "--no-tours"],
        dir.path(),
        &std::env::temp_dir(),
    );
    assert_eq!(code, Some(0), "{out}{err}");
    let conn = rusqlite::Connection::open(dir.path().join("res/results.sqlite")).unwrap();
    let (commit, profile, cwd_commit): (String, String, String) = conn
        .query_row(
            "SELECT git_commit, build_profile, cwd_git_commit FROM runs",
            [],
            |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)),
        )
        .unwrap();
    assert_eq!(commit, own, "floorcast's own commit");
    assert_eq!(cwd_commit, theirs, "the current directory's, apart");
    let want = if cfg!(debug_assertions) {
        "debug"
    } else {
        "release"
    };
    assert_eq!(profile, want);
    let o = run(&["--version"]);
    assert!(
        stdout(&o).contains(&format!("(commit {own}, dirty ")),
        "{}",
        stdout(&o)
    );
}
