//! External strategies over the strategy protocol (`docs/strategy-protocol.md`), end to end:
//! `explore --strategy-command` with the Python examples, and programs that break the protocol.

mod common;

use std::path::{Path, PathBuf};

use common::*;

fn python_command(script: &str) -> String {
    format!("python3 {}", repo().join(script).display())
}

/// Runs `explore` from `start` (empty: the default) with `extra` arguments; returns the output
/// directory's summary.
fn explore(
    building: &Path,
    seed: u64,
    start: &str,
    out: &Path,
    extra: &[&str],
) -> serde_json::Value {
    let mut args: Vec<&str> = Vec::new();
    if !start.is_empty() {
        args.extend_from_slice(&["--start", start]);
    }
    args.extend_from_slice(extra);
    explore_with(building, seed, out, &args)
}

fn read(p: PathBuf) -> String {
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// `examples/strategies/baseline.py` makes exactly the built-in `baseline`'s decisions: the same
/// decisions, trajectory and map, the same summary but for the strategy's identity and the
/// wall times.
fn python_baseline_is_the_built_in(building: &Path, seed: u64, start: &str) {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("built-in"), dir.path().join("python"));
    let mut built_in = explore(building, seed, start, &a, &["--strategy", "baseline"]);
    let command = python_command("examples/strategies/baseline.py");
    let mut python = explore(building, seed, start, &b, &["--strategy-command", &command]);
    for file in ["decisions.csv", "trajectory.csv", "progress.csv", "map.pgm"] {
        assert!(
            std::fs::read(a.join(file)).unwrap() == std::fs::read(b.join(file)).unwrap(),
            "{file} differs"
        );
    }
    assert_eq!(python["strategy"], "baseline.py");
    assert_eq!(python["strategy_name"], "baseline.py");
    assert_eq!(
        python["strategy_program"]["files_sha256"]
            .as_str()
            .unwrap()
            .len(),
        64
    );
    // Every decision was asked of the program (and some again, after a candidate without a path).
    let decisions = python["decisions"].as_u64().unwrap();
    assert!(decisions > 0);
    assert!(python["strategy_replies"].as_u64().unwrap() >= decisions);
    let python = python.as_object_mut().unwrap();
    for key in [
        "strategy",
        "strategy_program",
        "strategy_name",
        "strategy_compute_s",
        "strategy_replies",
        "wall_time_s",
        "speedup",
    ] {
        python.remove(key);
        built_in.as_object_mut().unwrap().remove(key);
    }
    assert_eq!(&built_in, &serde_json::Value::Object(python.clone()));
}

macro_rules! same_as_built_in_cases {
    ($($name:ident: $building:expr, $seed:expr, $start:expr;)*) => {$(
        #[test]
        fn $name() {
            python_baseline_is_the_built_in(&$building, $seed, $start);
        }
    )*};
}

same_as_built_in_cases! {
    python_baseline_small_building: repo().join("buildings/small.toml"), 1, "";
    python_baseline_franch1: maps_dir().join("schools/Franch1.yaml"), 2, "";
    python_baseline_freiburg79_random_start: maps_dir().join("radish/freiburg_building79.yaml"), 3, "random";
}

#[test]
fn python_baseline_on_a_generated_building() {
    let dir = tempfile::tempdir().unwrap();
    let b = dir.path().join("gen.toml");
    let o = run(&[
        "building",
        "generate",
        "--seed",
        "11",
        "--area-m2",
        "900",
        "--out",
        b.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    python_baseline_is_the_built_in(&b, 4, "");
}

#[test]
fn nearest_frontier_first_explores_the_small_building() {
    let dir = tempfile::tempdir().unwrap();
    let command = python_command("examples/strategies/nearest.py");
    let s = explore(
        &repo().join("buildings/small.toml"),
        1,
        "",
        dir.path(),
        &["--strategy-command", &command],
    );
    assert_eq!(s["strategy"], "nearest.py");
    assert_eq!(s["end_reason"], "complete");
    assert!(s["explored_fraction"].as_f64().unwrap() >= 0.97, "{s}");
}

/// A strategy's own parameters reach it in the run message and are recorded with the run:
/// `nearest.py` stops exploring when no candidate's gain reaches `stop_below_m2`.
#[test]
fn a_strategy_gets_its_params() {
    let dir = tempfile::tempdir().unwrap();
    let command = python_command("examples/strategies/nearest.py");
    let params = r#"{"stop_below_m2": 1e9, "note": ["any", {"json": true}]}"#;
    let s = explore(
        &repo().join("buildings/small.toml"),
        1,
        "",
        dir.path(),
        &["--strategy-command", &command, "--strategy-params", params],
    );
    assert_eq!(s["end_reason"], "early stop", "{s}");
    assert_eq!(s["decisions"], 0, "{s}");
    let given: serde_json::Value = serde_json::from_str(params).unwrap();
    assert_eq!(s["strategy_program"]["params"], given, "{s}");
}

/// A strategy's own goal points (goal replies): one off the map is reported back as
/// unreachable at the next attempt; the others are driven to, and the building explored.
#[test]
fn a_strategy_drives_to_points_of_its_own() {
    let dir = tempfile::tempdir().unwrap();
    let command = python_command("tests/strategies/goal_points.py");
    let s = explore(
        &repo().join("buildings/small.toml"),
        1,
        "",
        dir.path(),
        &["--strategy-command", &command],
    );
    assert_eq!(s["end_reason"], "complete", "{s}");
    assert!(s["explored_fraction"].as_f64().unwrap() >= 0.97, "{s}");
    let log = read(dir.path().join("strategy-stderr.txt"));
    assert!(log.contains("told unreachable: True"), "{log}");
    let points: usize = log
        .split("goal_points: ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{log}"));
    assert!(points >= 5, "{log}");
}

/// A strategy gives candidates up (drop replies): they are not offered again at the same place,
/// the others are explored, and the run ends with the dropped frontiers left.
#[test]
fn a_strategy_drops_candidates_it_does_not_want() {
    let dir = tempfile::tempdir().unwrap();
    let command = python_command("tests/strategies/drops_small.py");
    let s = explore(
        &repo().join("maps/schools/Franch1.yaml"),
        2,
        "",
        dir.path(),
        &["--strategy-command", &command],
    );
    let log = read(dir.path().join("strategy-stderr.txt"));
    let dropped: usize = log
        .split("drops_small: dropped ")
        .nth(1)
        .and_then(|t| t.trim().parse().ok())
        .unwrap_or_else(|| panic!("{log}"));
    assert!(dropped >= 5, "{log}");
    assert!(
        s["blacklisted_goals"].as_u64().unwrap() >= dropped as u64,
        "{s}"
    );
    assert!(s["explored_fraction"].as_f64().unwrap() >= 0.9, "{s}");
    assert_ne!(s["end_reason"], "time limit", "{s}");
}

#[test]
fn a_strategy_that_needs_the_layout_and_the_map_gets_them() {
    let dir = tempfile::tempdir().unwrap();
    let command = python_command("tests/strategies/needs_everything.py");
    let s = explore(
        &repo().join("buildings/small.toml"),
        1,
        "",
        dir.path(),
        &["--strategy-command", &command],
    );
    // The program checks every message (a layout gain per candidate, the map's changes within
    // its size) and fails the run otherwise; it reports what it saw on stderr.
    assert!(s["layouts_computed"].as_u64().unwrap() > 0, "{s}");
    let log = read(dir.path().join("strategy-stderr.txt"));
    let replies = s["strategy_replies"].as_u64().unwrap();
    assert!(
        log.contains(&format!("needs_everything: {replies} decisions")),
        "{log}"
    );
    // Every layout made reached it, once, with its rooms.
    let layouts = s["layouts_computed"].as_u64().unwrap();
    assert!(log.contains(&format!(", {layouts} layouts, ")), "{log}");
    assert!(!log.contains(", 0 rooms"), "{log}");
}

/// Protocol 2: a program's needs may depend on its params (its ready reply lists the run's),
/// and with the need "layout" every decide message carries the robot's predicted room. The
/// program checks each message and fails the run otherwise.
#[test]
fn a_strategy_needs_what_its_params_ask_for() {
    let command = python_command("tests/strategies/needs_by_params.py");
    // (params, whether the run has the layout)
    for (params, rooms) in [(r#"{"rooms": true}"#, true), ("{}", false)] {
        let dir = tempfile::tempdir().unwrap();
        let s = explore(
            &repo().join("buildings/small.toml"),
            1,
            "",
            dir.path(),
            &["--strategy-command", &command, "--strategy-params", params],
        );
        assert_eq!(s["end_reason"], "complete", "{params}: {s}");
        let log = read(dir.path().join("strategy-stderr.txt"));
        let line = log
            .lines()
            .find(|l| l.starts_with("needs_by_params: "))
            .unwrap_or_else(|| panic!("{params}: {log}"));
        let numbers: Vec<u64> = line
            .split(|c: char| !c.is_ascii_digit())
            .filter_map(|w| w.parse().ok())
            .collect();
        let [decisions, with_room, in_room] = numbers[..] else {
            panic!("{line}")
        };
        assert!(
            line.contains(&format!("rooms {}", if rooms { "True" } else { "False" })),
            "{line}"
        );
        assert!(decisions > 3, "{line}");
        assert_eq!(with_room, if rooms { decisions } else { 0 }, "{line}");
        // The robot starts in a room of the small building and stays in rooms a while.
        assert_eq!(in_room > 0, rooms, "{line}");
        assert!(in_room <= with_room, "{line}");
    }
    // The compliance check runs the same session: the run's needs are its ready reply's.
    for (params, needs) in [(r#"{"rooms": true}"#, "needs [layout]"), ("{}", "needs []")] {
        let o = run(&["strategy", "check", &command, "--strategy-params", params]);
        let out = stdout(&o);
        assert!(o.status.success(), "{out}{}", stderr(&o));
        assert!(out.contains(&format!("ok    run: ready, {needs}")), "{out}");
        assert!(out.contains("protocol 2, needs []"), "{out}");
        assert!(
            out.contains("keeps to the strategy protocol version 2"),
            "{out}"
        );
    }
}

#[test]
fn a_strategy_that_stops_ends_the_run_as_an_early_stop() {
    let dir = tempfile::tempdir().unwrap();
    let command = python_command("tests/strategies/stops_at_once.py");
    let s = explore(
        &repo().join("buildings/small.toml"),
        1,
        "",
        dir.path(),
        &["--strategy-command", &command],
    );
    assert_eq!(s["end_reason"], "early stop");
    assert_eq!(s["stopped_early"], true);
    assert_eq!(s["decisions"], 0);
    // Asked again with the last resorts' candidates before the stop stood.
    assert!(s["strategy_replies"].as_u64().unwrap() >= 2, "{s}");
}

/// A program that breaks the protocol fails the run: exit 2, one line naming the program and
/// what it did, no output directory left behind but, for a program that wrote to stderr during
/// the run, one holding only `strategy-stderr.txt` (its traceback), which the error names.
fn fails_cleanly(command: &str, needles: &[&str]) {
    fails_cleanly_with(command, &[], needles);
}

/// As [`fails_cleanly`], with `extra` arguments.
fn fails_cleanly_with(command: &str, extra: &[&str], needles: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let building = repo().join("buildings/small.toml");
    let mut args = vec![
        "explore",
        "--building",
        building.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--strategy-timeout-s",
        "2",
        "--strategy-command",
        command,
    ];
    args.extend_from_slice(extra);
    let o = run(&args);
    assert_clean_failure(&o, needles);
    if !stderr(&o).contains("strategy-stderr.txt") {
        assert!(!out.exists(), "an output directory was left behind");
        return;
    }
    let files: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(files, ["strategy-stderr.txt"], "only the program's stderr");
    // The file holds what the program wrote, down to the last line the error quotes.
    let text = std::fs::read_to_string(out.join("strategy-stderr.txt")).unwrap();
    let err = stderr(&o);
    let quoted = err
        .split("its last stderr line: '")
        .nth(1)
        .and_then(|rest| rest.split('\'').next())
        .unwrap_or_else(|| panic!("no stderr line quoted: {err}"));
    assert!(text.trim_end().ends_with(quoted), "{text}");
}

macro_rules! broken_strategy_cases {
    ($($name:ident: $command:expr => [$($needle:expr),*];)*) => {$(
        #[test]
        fn $name() {
            fails_cleanly($command.as_ref(), &[$($needle),*]);
        }
    )*};
}

broken_strategy_cases! {
    crash_at_hello: python_command("tests/strategies/crash_at_hello.py") =>
        ["crash_at_hello.py", "exited with status 3 before answering the hello message", "something went wrong", "(its stderr: ", "strategy-stderr.txt)"];
    crash_mid_run: python_command("tests/strategies/crash_mid_run.py") =>
        ["crash_mid_run.py", "exited with status 1 before answering decision 2", "strategy bug at decision 3", "(its stderr: ", "strategy-stderr.txt)"];
    hang: python_command("tests/strategies/hang.py") =>
        ["hang.py", "did not answer decision 0 within 2 s"];
    nonsense: python_command("tests/strategies/nonsense.py") =>
        ["nonsense.py", "answered decision 0 with a line that is not a protocol message: 'this is not json'"];
    chatty: python_command("tests/strategies/chatty.py") =>
        ["chatty.py", "'debug: deciding'", "logs go to stderr"];
    goal_not_a_point: format!("{} '{{\"type\":\"goal\",\"point\":\"here\"}}'", python_command("tests/strategies/nonsense.py")) =>
        ["nonsense.py", "answered decision 0 with {\"point\":\"here\",\"type\":\"goal\"} (expected \"point\": [x, y], metres in the map frame)"];
    goal_of_three_numbers: format!("{} '{{\"type\":\"goal\",\"point\":[1,2,3]}}'", python_command("tests/strategies/nonsense.py")) =>
        ["nonsense.py", "(expected \"point\": [x, y]"];
    illegal_id: python_command("tests/strategies/illegal_id.py") =>
        ["illegal_id.py", "chose candidate 99999, which decision 0 did not offer"];
    wrong_protocol: python_command("tests/strategies/wrong_protocol.py") =>
        ["wrong_protocol.py", "speaks protocol version 99; this floorcast speaks versions 1 to 2"];
    missing_interpreter: "no-such-interpreter-x7 strategy.py" =>
        ["cannot start 'no-such-interpreter-x7': no such program"];
    unclosed_quote: "python3 'my strategy.py" =>
        ["--strategy-command", "cannot split", "unclosed quote"];
    empty_command: "  " =>
        ["--strategy-command", "the strategy command is empty"];
}

macro_rules! bad_params_cases {
    ($($name:ident: $params:expr => [$($needle:expr),*];)*) => {$(
        #[test]
        fn $name() {
            let command = python_command("examples/strategies/nearest.py");
            let params: String = $params.into();
            fails_cleanly_with(&command, &["--strategy-params", &params], &[$($needle),*]);
        }
    )*};
}

bad_params_cases! {
    params_not_an_object: "[1, 2]" =>
        ["--strategy-params", "expected a JSON object"];
    params_not_json: "{stop_below_m2 = 5}" =>
        ["--strategy-params", "not JSON", "expected an object"];
    params_too_large: format!(r#"{{"blob": "{}"}}"#, "x".repeat(70_000)) =>
        ["--strategy-params", "bytes of JSON (at most 65536)"];
}

#[test]
fn a_strategy_command_with_a_built_in_strategy_is_refused() {
    let o = run(&[
        "explore",
        "--building",
        repo().join("buildings/small.toml").to_str().unwrap(),
        "--strategy",
        "layout",
        "--strategy-command",
        "python3 x.py",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("cannot be used with"), "{}", stderr(&o));
}

/// `floorcast strategy check`: every check passes for a compliant program; a broken one fails
/// at the check it breaks, exit 2.
#[test]
fn the_compliance_check_names_the_rule_a_program_breaks() {
    // (program, last line printed on stdout, exit code)
    let cases = [
        (
            "examples/strategies/baseline.py",
            "keeps to the strategy protocol version 2",
            0,
        ),
        (
            "examples/strategies/nearest.py",
            "keeps to the strategy protocol version 2",
            0,
        ),
        (
            "tests/strategies/needs_everything.py",
            "keeps to the strategy protocol version 2",
            0,
        ),
        (
            "tests/strategies/plain_v1.py",
            "keeps to the strategy protocol version 1",
            0,
        ),
        (
            "tests/strategies/crash_at_hello.py",
            "FAIL  hello: exited with status 3",
            2,
        ),
        (
            "tests/strategies/wrong_protocol.py",
            "FAIL  hello: speaks protocol version 99",
            2,
        ),
        (
            "tests/strategies/illegal_id.py",
            "FAIL  decide: chose candidate 99999",
            2,
        ),
        (
            "tests/strategies/chatty.py",
            "FAIL  decide: answered decision 0 with a line that is not a protocol message",
            2,
        ),
        (
            "tests/strategies/crash_mid_run.py",
            "FAIL  decide with one candidate (id 7): exited with status 1",
            2,
        ),
        // Its exit is told at once, not as a timeout, though a child it left holds its stdout.
        (
            "tests/strategies/forks_and_exits.py",
            "FAIL  hello: exited with status 5 before answering the hello message, but its stdout is still held open by a process it started and left running",
            2,
        ),
        (
            "tests/strategies/v1_ready_needs.py",
            "FAIL  run: answered the run message with \"needs\" in its ready reply, which protocol version 2 added, but its hello said it speaks version 1",
            2,
        ),
    ];
    for (script, last, code) in cases {
        let t0 = std::time::Instant::now();
        let o = run(&[
            "strategy",
            "check",
            &python_command(script),
            "--strategy-timeout-s",
            "2",
        ]);
        let out = stdout(&o);
        assert_eq!(o.status.code(), Some(code), "{script}: {out}{}", stderr(&o));
        assert!(
            out.trim().lines().last().unwrap_or("").contains(last),
            "{script}: {out}"
        );
        assert!(!stderr(&o).contains("panicked"), "{script}");
        if script.contains("forks_and_exits") {
            // Well before the 2 s timeout (0.3 s for its last lines, 1 s for its stderr).
            let took = t0.elapsed();
            assert!(
                took < std::time::Duration::from_millis(1900),
                "{script}: {took:?}"
            );
        }
    }
}

/// `strategy list --json` lists every built-in strategy (the names `explore --strategy`
/// accepts) with a citation, and each literature strategy with its paper and the setting it
/// reads at its default.
#[test]
fn the_strategy_list_in_json_cites_each_strategy_and_its_parameters() {
    let o = floorcast()
        .args(["strategy", "list", "--json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["format"], "floorcast-strategies");
    let list = v["strategies"].as_array().unwrap();
    let names: Vec<&str> = list.iter().map(|s| s["name"].as_str().unwrap()).collect();
    assert_eq!(names, floorcast_worker::strategy_names());
    let cases = [
        ("nearest", "Yamauchi", None),
        (
            "utility-exp",
            "González-Baños",
            Some(("utility_exp_lambda_per_m", 0.2)),
        ),
        (
            "cost-utility",
            "Burgard",
            Some(("cost_utility_beta_m2_per_m", 1.0)),
        ),
        ("frontier-tsp", "Kulich", None),
        ("room-first", "Holz", None),
        ("baseline", "Luperto", Some(("alpha", 0.5))),
        ("layout-es", "Luperto", Some(("es_threshold_m2", 1.0))),
        ("layout-aes", "Luperto", Some(("aes_min_gain_m2", 2.0))),
    ];
    for (name, cited, param) in cases {
        let s = list.iter().find(|s| s["name"] == name).unwrap();
        assert!(s["citation"].as_str().unwrap().contains(cited), "{s}");
        let params = s["parameters"].as_array().unwrap();
        match param {
            Some((setting, default)) => assert!(
                params
                    .iter()
                    .any(|p| p["setting"] == setting && p["default"].as_f64() == Some(default)),
                "{s}"
            ),
            None => assert!(
                params.iter().all(|p| p["setting"] == "layout_update_m2"
                    || p["setting"] == "layout_update_fraction"),
                "{s}"
            ),
        }
    }
    for s in list {
        assert!(!s["citation"].as_str().unwrap().is_empty(), "{s}");
    }
}
