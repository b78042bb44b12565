//! Every command the documents print is run, as printed, and must succeed.
//!
//! The documents are README.md, FINDINGS.md, BENCHMARKS.md, formats/*.md, buildings/README.md,
//! maps/README.md, suites/README.md, results/**/README.md and docs/*.md. From each, the ```sh blocks are read; a line (joined with
//! its `\` continuations, a `for ... done` loop taken whole) runs when it invokes floorcast:
//! `floorcast ...`, `$F ...` after a `F=target/release/floorcast`-style assignment in the same
//! block, `target/release/floorcast ...`, or `cargo run --release -- ...` (run as `floorcast
//! ...`). Other `cargo` lines (`cargo build`, `cargo test`, `cargo bench`, `cargo run -p ...
//! --example`) are not run: they build or test this repository, which is what running this test
//! already does. Lines of other programs (`python3`, `zenohd`) are not run either.
//!
//! Each document's commands run in order, with `bash -c`, in a fresh temporary directory that
//! mirrors the repository: copies of `buildings/`, `grids/`, `results/`, `examples/` and `suites/` (so commands that
//! write there leave the repository clean), `target/release/floorcast` and `bin/floorcast`
//! (on `PATH`) linking to the built binary, and `maps/` linking to the repository's vendored
//! maps, so that relative paths in the commands mean what they mean in a checkout. Nothing
//! outside the repository is read.
//!
//! A few commands cannot run here; they are listed in [`NOT_RUN`], each checked otherwise:
//! a grid of hundreds of runs is loaded and planned with the coordinator's `Plan::load` (and its
//! results directory gets a stand-in store, the quick grid's results, so that the `report` lines
//! that follow run as printed), a command that waits for other machines is run with `--help`
//! appended (its options parse), its grid planned, one exploration of a large building (a
//! minute or more on 2 cores) runs as printed with its simulated time cut to 30 s, and a loop
//! over many files runs as printed over the first few of them.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use floorcast_coordinator::grid::Plan;

/// How a command that is not run is checked instead.
#[derive(Debug, Clone, Copy)]
enum Check {
    /// A long grid (GRID: its file): planned with `Plan::load`, at least this many jobs (so it is
    /// long indeed), and a stand-in store put where its results go.
    LongGrid(&'static str, usize),
    /// Waits for other machines: run with `--help` appended; the grid, if any, is planned.
    Network(Option<&'static str>),
    /// One exploration of a large building (a minute or more on 2 cores): run as printed with
    /// `--time-limit-s 30` appended, so its building, strategy and options are still checked.
    LongRun,
    /// A `for V in LIST; do ... done` loop over many files (a minute or more): run as printed
    /// over the first this-many of its list (every glob expanded), so its body is still checked.
    LongLoop(usize),
}

/// The printed commands that are not run (the text after `floorcast`/`$F`, comments stripped).
const NOT_RUN: &[(&str, Check)] = &[
    ("run grids/paper.toml", Check::LongGrid("grids/paper.toml", 300)),
    ("run grids/paper-floor.toml", Check::LongGrid("grids/paper-floor.toml", 150)),
    ("run grids/paper-truth.toml", Check::LongGrid("grids/paper-truth.toml", 300)),
    ("run grids/paper-beyond.toml", Check::LongGrid("grids/paper-beyond.toml", 90)),
    ("run grids/paper-euclidean.toml", Check::LongGrid("grids/paper-euclidean.toml", 90)),
    ("run grids/paper-on-arrival.toml", Check::LongGrid("grids/paper-on-arrival.toml", 90)),
    ("run grids/paper-alpha.toml", Check::LongGrid("grids/paper-alpha.toml", 90)),
    ("run grids/paper-clearance.toml", Check::LongGrid("grids/paper-clearance.toml", 90)),
    ("run grids/schools.toml", Check::LongGrid("grids/schools.toml", 99)),
    ("run grids/paper-gaps.toml", Check::LongGrid("grids/paper-gaps.toml", 100)),
    ("run grids/starts.toml", Check::LongGrid("grids/starts.toml", 600)),
    ("run grids/layout-update.toml", Check::LongGrid("grids/layout-update.toml", 1000)),
    ("run grids/real-schools.toml", Check::LongGrid("grids/real-schools.toml", 1620)),
    ("run grids/plans.toml", Check::LongGrid("grids/plans.toml", 124)),
    ("run grids/leaderboard.toml", Check::LongGrid("grids/leaderboard.toml", 1215)),
    ("run grids/beat-nearest.toml", Check::LongGrid("grids/beat-nearest.toml", 54)),
    ("run grids/teams.toml", Check::LongGrid("grids/teams.toml", 297)),
    (
        "run grids/teams-ground-truth.toml",
        Check::LongGrid("grids/teams-ground-truth.toml", 81),
    ),
    // 66 runs a round, 11-20 minutes on 2 cores.
    ("run grids/sequential.toml", Check::LongGrid("grids/sequential.toml", 66)),
    (
        "run grids/layout-update-large.toml",
        Check::LongGrid("grids/layout-update-large.toml", 8),
    ),
    ("run grids/layout-fraction.toml", Check::LongGrid("grids/layout-fraction.toml", 8)),
    (
        "run grids/layout-fraction-real.toml",
        Check::LongGrid("grids/layout-fraction-real.toml", 42),
    ),
    ("run grids/distance-bound.toml", Check::LongGrid("grids/distance-bound.toml", 12)),
    (
        "run grids/distance-bound-layout.toml",
        Check::LongGrid("grids/distance-bound-layout.toml", 12),
    ),
    (
        "run grids/localization-large.toml",
        Check::LongGrid("grids/localization-large.toml", 48),
    ),
    (
        "run grids/paper.toml --listen tcp/0.0.0.0:7447 --workers 0",
        Check::Network(Some("grids/paper.toml")),
    ),
    (
        "run grids/paper.toml --connect tcp/R:7447 --workers 0",
        Check::Network(Some("grids/paper.toml")),
    ),
    ("worker --connect tcp/A:7447", Check::Network(None)),
    ("worker --connect tcp/R:7447", Check::Network(None)),
    ("router --listen tcp/0.0.0.0:7447", Check::Network(None)),
    (
        "explore --building buildings/paper/paper-01.toml --strategy baseline --seed 8 --out why/baseline",
        Check::LongRun,
    ),
    (
        "explore --building buildings/paper/paper-01.toml --strategy layout --seed 8 --layout-update-fraction 0 --layout-snapshots --out why/layout",
        Check::LongRun,
    ),
    (
        "explore --building buildings/paper/paper-05.toml --strategy baseline --seed 1 --out why/baseline",
        Check::LongRun,
    ),
    (
        "explore --building buildings/paper/paper-05.toml --strategy layout-truth --seed 1 --layout-update-fraction 0 --out why/layout-truth",
        Check::LongRun,
    ),
    (
        "explore --building buildings/paper/paper-03.toml --seed 1 --utility-distance euclidean",
        Check::LongRun,
    ),
    (
        "explore --building buildings/paper/paper-10.toml --strategy layout-es --seed 5 --layout-update-fraction 0",
        Check::LongRun,
    ),
    (
        "explore --building maps/schools/battle_creekhs_2.yaml --seed 2",
        Check::LongRun,
    ),
    // A 4000 m² office to the 4-hour limit: two minutes or more.
    (
        "explore --building office-77.toml --strategy layout-es --seed 1 --layout-update-fraction 0 --out chase/layout-es",
        Check::LongRun,
    ),
    // The layout of each of the 62 vendored plans: one to three minutes.
    (
        "for p in maps/plans/*.xml; do floorcast layout --map $p --truth $p --out results/plan-layouts/$(basename $p .xml) --picture svg > /dev/null; done",
        Check::LongLoop(4),
    ),
];

/// At most this many printed commands may be left unrun (each reference grid's `run` line is
/// one: they take minutes to hours and are planned instead; so is each line that waits for
/// other machines, or, as `router`, until it is stopped).
const MAX_NOT_RUN: usize = 39;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The documents whose commands run.
fn documents() -> Vec<PathBuf> {
    let root = repo();
    let mut docs = vec![
        root.join("README.md"),
        root.join("FINDINGS.md"),
        root.join("BENCHMARKS.md"),
        root.join("buildings/README.md"),
        root.join("maps/README.md"),
        root.join("suites/README.md"),
    ];
    let mut more = Vec::new();
    for dir in ["formats", "docs"] {
        if let Ok(entries) = std::fs::read_dir(root.join(dir)) {
            for e in entries.flatten() {
                if e.path().extension().is_some_and(|x| x == "md") {
                    more.push(e.path());
                }
            }
        }
    }
    collect_readmes(&root.join("results"), &mut more);
    more.sort();
    docs.extend(more);
    docs
}

fn collect_readmes(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            collect_readmes(&p, out);
        } else if p.file_name().is_some_and(|n| n == "README.md") {
            out.push(p);
        }
    }
}

/// One ```sh block: its variable assignments and its commands, in order.
#[derive(Debug, Default)]
struct Block {
    assignments: Vec<String>,
    commands: Vec<String>,
}

/// Drops a trailing `# comment` (a `#` at the start or after a blank, outside quotes).
fn strip_comment(line: &str) -> &str {
    let (mut single, mut double) = (false, false);
    let mut prev_blank = true;
    for (i, c) in line.char_indices() {
        match c {
            '\'' if !double => single = !single,
            '"' if !single => double = !double,
            '#' if !single && !double && prev_blank => return line[..i].trim_end(),
            _ => {}
        }
        prev_blank = c.is_whitespace();
    }
    line.trim_end()
}

fn is_assignment(line: &str) -> bool {
    let Some((name, value)) = line.split_once('=') else {
        return false;
    };
    !name.is_empty()
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        && !name.starts_with(|c: char| c.is_ascii_digit())
        && !value.is_empty()
        && !value.contains(char::is_whitespace)
}

fn sh_blocks(text: &str) -> Vec<Block> {
    let mut blocks = Vec::new();
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        let indent = line.len() - line.trim_start().len();
        if line.trim() != "```sh" {
            continue;
        }
        let mut block = Block::default();
        let mut pending = String::new();
        let mut in_loop = false;
        for line in lines.by_ref() {
            if line.trim() == "```" {
                break;
            }
            let line = line.get(indent..).unwrap_or(line.trim_start());
            let code = strip_comment(line);
            if let Some(head) = code.strip_suffix('\\') {
                pending.push_str(head.trim_end());
                pending.push(' ');
                continue;
            }
            pending.push_str(code.trim_start_matches(' '));
            if pending.starts_with("for ") {
                in_loop = true;
            }
            if in_loop {
                if pending.trim() == "done" {
                    in_loop = false;
                }
                let last = block.commands.last_mut().filter(|c| c.starts_with("for "));
                match last {
                    Some(c) if !pending.starts_with("for ") => {
                        c.push('\n');
                        c.push_str(&pending);
                    }
                    _ => block.commands.push(pending.clone()),
                }
                pending.clear();
                continue;
            }
            let cmd = std::mem::take(&mut pending);
            let cmd = cmd.trim();
            if cmd.is_empty() {
                continue;
            }
            if is_assignment(cmd) {
                block.assignments.push(cmd.to_string());
            } else {
                block.commands.push(cmd.to_string());
            }
        }
        blocks.push(block);
    }
    blocks
}

/// The variables of a block that name the floorcast binary (`F=target/release/floorcast`).
fn binary_variables(block: &Block) -> Vec<String> {
    block
        .assignments
        .iter()
        .filter_map(|a| a.split_once('='))
        .filter(|(_, v)| v.ends_with("/floorcast") || *v == "floorcast")
        .map(|(n, _)| format!("${n}"))
        .collect()
}

/// The command as run (`cargo run --release --` becomes `floorcast`), or `None` when it does
/// not invoke floorcast.
fn floorcast_command(cmd: &str, vars: &[String]) -> Option<String> {
    if let Some(rest) = cmd.strip_prefix("cargo run --release -- ") {
        return Some(format!("floorcast {rest}"));
    }
    if cmd.starts_with("cargo ") {
        // cargo build / test / bench / run -p ... --example: not run (see the module doc).
        return None;
    }
    let invokes = |s: &str| {
        s.split(|c: char| c.is_whitespace() || c == ';' || c == '&' || c == '|')
            .map(|w| w.trim_matches('"'))
            .any(|w| w == "floorcast" || w.ends_with("/floorcast") || vars.iter().any(|v| w == v))
    };
    invokes(cmd).then(|| cmd.to_string())
}

/// The command's arguments after the program (for matching [`NOT_RUN`]).
fn arguments<'a>(cmd: &'a str, vars: &[String]) -> &'a str {
    let first = cmd.split_whitespace().next().unwrap_or("");
    if first == "floorcast" || first.ends_with("/floorcast") || vars.iter().any(|v| v == first) {
        cmd[first.len()..].trim()
    } else {
        cmd
    }
}

fn link(target: &Path, link: &Path) {
    std::fs::create_dir_all(link.parent().unwrap()).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(target, link).unwrap();
    #[cfg(not(unix))]
    std::fs::copy(target, link).unwrap();
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let p = e.path();
        let dest = to.join(e.file_name());
        if p.is_dir() {
            copy_dir(&p, &dest);
        } else {
            std::fs::copy(&p, &dest).unwrap();
        }
    }
}

/// A temporary mirror of the repository: returns (the guard, the repository's mirror).
fn mirror() -> (tempfile::TempDir, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path().join("floorcast");
    for dir in ["buildings", "grids", "results", "examples", "suites"] {
        copy_dir(&repo().join(dir), &root.join(dir));
    }
    let bin = Path::new(env!("CARGO_BIN_EXE_floorcast"));
    link(bin, &root.join("target/release/floorcast"));
    link(bin, &tmp.path().join("bin/floorcast"));
    // The vendored maps are only read: linked, not copied.
    link(&repo().join("maps"), &root.join("maps"));
    (tmp, root)
}

/// The quick grid's results with `nearest` beside its three strategies (the label the
/// leaderboard's commands compare with), made once: the stand-in store of long grids' results.
fn stand_in_store() -> &'static Path {
    static STORE: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    let (_, dir) = STORE.get_or_init(|| {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("quick");
        let quick = std::fs::read_to_string(repo().join("grids/quick.toml")).unwrap();
        let small = repo().join("buildings/small.toml");
        let grid = quick
            .replace("../buildings/small.toml", &small.display().to_string())
            .replace(
                "[settings]",
                "[[strategies]]\nname = \"nearest\"\n\n[settings]",
            );
        assert!(grid.contains("name = \"nearest\""), "{grid}");
        let grid_file = tmp.path().join("stand-in.toml");
        std::fs::write(&grid_file, grid).unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_floorcast"))
            .arg("run")
            .arg(&grid_file)
            .args(["--quiet", "--results"])
            .arg(&dir)
            .current_dir(repo())
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "quick grid: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        (tmp, dir)
    });
    dir
}

fn sh(script: &str, dir: &Path, bin_dir: &Path) -> std::process::Output {
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    Command::new("bash")
        .arg("-c")
        .arg(script)
        .current_dir(dir)
        .env("PATH", path)
        .output()
        .expect("sh runs")
}

fn check_not_run(check: Check, cmd: &str, root: &Path, bin_dir: &Path) {
    match check {
        Check::LongGrid(grid, min_jobs) => {
            let plan = Plan::load(&root.join(grid), None)
                .unwrap_or_else(|e| panic!("`{cmd}`: the grid does not plan: {e}"));
            assert!(
                plan.jobs.len() >= min_jobs,
                "`{cmd}`: {} jobs, not long enough to be left unrun",
                plan.jobs.len()
            );
            let results = root.join(&plan.results_dir);
            if !results.exists() {
                copy_dir(stand_in_store(), &results);
            }
        }
        Check::LongRun => {
            let out = sh(&format!("{cmd} --time-limit-s 30"), root, bin_dir);
            assert!(
                out.status.success(),
                "`{cmd} --time-limit-s 30`: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        Check::LongLoop(first) => {
            let (head, body) = cmd
                .split_once("; do")
                .unwrap_or_else(|| panic!("`{cmd}`: not a `for V in LIST; do ... done` loop"));
            let (var, list) = head
                .rsplit_once("for ")
                .and_then(|(before, h)| Some((before, h.split_once(" in ")?)))
                .map(|(before, (v, l))| (format!("{before}for {v}"), l))
                .unwrap_or_else(|| panic!("`{cmd}`: not a `for V in LIST; do ... done` loop"));
            let script = format!("{var} in $(printf '%s\\n' {list} | head -n {first}); do{body}");
            let out = sh(&script, root, bin_dir);
            assert!(
                out.status.success(),
                "`{script}`: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        Check::Network(grid) => {
            if let Some(grid) = grid {
                Plan::load(&root.join(grid), None)
                    .unwrap_or_else(|e| panic!("`{cmd}`: the grid does not plan: {e}"));
            }
            let out = sh(&format!("{cmd} --help"), root, bin_dir);
            assert!(
                out.status.success(),
                "`{cmd} --help`: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
    }
}

/// Runs one document's commands; returns the commands not run (matched in [`NOT_RUN`]).
fn run_document(doc: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(doc).unwrap();
    let (tmp, root) = mirror();
    let bin_dir = tmp.path().join("bin");
    let mut not_run = Vec::new();
    for block in sh_blocks(&text) {
        let vars = binary_variables(&block);
        for cmd in &block.commands {
            let first = cmd.split_whitespace().next().unwrap_or("");
            assert!(
                !first.starts_with('$') || vars.iter().any(|v| v == first),
                "{}: `{cmd}` runs {first}, which no assignment in its block names",
                doc.display()
            );
            let Some(cmd) = floorcast_command(cmd, &vars) else {
                continue;
            };
            let args = arguments(&cmd, &vars);
            if let Some((_, check)) = NOT_RUN.iter().find(|(a, _)| *a == args) {
                check_not_run(*check, &cmd_with(&block, &cmd), &root, &bin_dir);
                not_run.push(args.to_string());
                continue;
            }
            if args.starts_with("run ") && args.contains(" --import ") {
                import_covers_its_grid(args, &root);
            }
            let script = cmd_with(&block, &cmd);
            let start = std::time::Instant::now();
            let out = sh(&script, &root, &bin_dir);
            eprintln!(
                "{}: {:.1} s: {cmd}",
                doc.strip_prefix(repo()).unwrap_or(doc).display(),
                start.elapsed().as_secs_f64()
            );
            assert!(
                out.status.success(),
                "{}: `{cmd}` exited with {:?}\nstdout: {}\nstderr: {}",
                doc.display(),
                out.status.code(),
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            );
        }
    }
    not_run
}

/// Panics unless `run GRID ... --import FILE` (arguments as printed, relative to `root`) finds
/// every job of its grid in the file: else it would run them all (hours for a leaderboard),
/// e.g. after a version change, when the file must be written again.
fn import_covers_its_grid(args: &str, root: &Path) {
    let words: Vec<&str> = args.split_whitespace().collect();
    let file = words
        .iter()
        .position(|w| *w == "--import")
        .and_then(|i| words.get(i + 1))
        .unwrap_or_else(|| panic!("`{args}`: --import names no file"));
    let plan = Plan::load(&root.join(words[1]), None)
        .unwrap_or_else(|e| panic!("`{args}`: the grid does not plan: {e}"));
    let runs = floorcast_coordinator::board::read(&root.join(file))
        .unwrap_or_else(|e| panic!("`{args}`: {file}: {e}"));
    let ids: std::collections::BTreeSet<&str> =
        runs.runs.iter().map(|r| r.job_id.as_str()).collect();
    let missing = plan
        .jobs
        .iter()
        .filter(|j| !ids.contains(j.id.as_str()))
        .count();
    assert_eq!(
        missing,
        0,
        "`{args}`: {missing} of the grid's {} jobs are not in {file}: run the grid and write the file again (`report DIR --export-runs FILE`)",
        plan.jobs.len()
    );
}

/// The block's assignments, then the command.
fn cmd_with(block: &Block, cmd: &str) -> String {
    let mut s = String::new();
    for a in &block.assignments {
        s.push_str(a);
        s.push('\n');
    }
    s.push_str(cmd);
    s
}

#[test]
fn docs_commands_parse_as_printed() {
    let text = "```sh\nF=target/release/floorcast\n$F explore --building b.toml \\\n    --seed 1   # a comment\ncargo build --release\nfor g in a b; do\n  floorcast run grids/$g.toml\ndone\npython3 x.py\n```\n";
    let blocks = sh_blocks(text);
    assert_eq!(blocks.len(), 1);
    let b = &blocks[0];
    assert_eq!(b.assignments, ["F=target/release/floorcast"]);
    let vars = binary_variables(b);
    let cmds: Vec<_> = b
        .commands
        .iter()
        .filter_map(|c| floorcast_command(c, &vars))
        .collect();
    assert_eq!(
        cmds,
        [
            "$F explore --building b.toml --seed 1",
            "for g in a b; do\nfloorcast run grids/$g.toml\ndone"
        ]
    );
    assert_eq!(
        arguments(&cmds[0], &vars),
        "explore --building b.toml --seed 1"
    );
    assert_eq!(
        floorcast_command("cargo run --release -- explore --building x", &[]).as_deref(),
        Some("floorcast explore --building x")
    );
    assert_eq!(strip_comment("a 'b # c' # d"), "a 'b # c'");
}

#[test]
fn docs_commands() {
    assert!(NOT_RUN.len() <= MAX_NOT_RUN, "too many commands left unrun");
    let docs = documents();
    for required in ["README.md", "FINDINGS.md", "BENCHMARKS.md"] {
        assert!(docs.contains(&repo().join(required)) && repo().join(required).exists());
    }
    // Two documents at a time (the machine this must fit on has 2 cores).
    let queue = std::sync::Mutex::new(docs.clone());
    let not_run = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let Some(doc) = queue.lock().unwrap().pop() else {
                    break;
                };
                let skipped = run_document(&doc);
                not_run.lock().unwrap().extend(skipped);
            });
        }
    });
    let not_run = not_run.into_inner().unwrap();
    // Every listed exception is still printed somewhere (the list does not outlive its reason).
    for (args, _) in NOT_RUN {
        assert!(
            not_run.iter().any(|a| a == args),
            "NOT_RUN lists `{args}`, which no document prints any more"
        );
    }
    // The README prints the two commands CI and a newcomer start with.
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    assert!(readme.contains("cargo test --workspace --release\n"));
}
