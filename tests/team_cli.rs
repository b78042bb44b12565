//! Teams end to end (issue 81): `explore --robots`, per-robot starts, the team's summary and
//! files, a grid's `robots` factor, and the team inputs refused with a message naming them.

mod common;

use common::*;

/// A team of three on the small building: the team's summary (its figures, each robot's), the
/// robot column of trajectory.csv and decisions.csv, the same run again for the same seed, and a
/// team of one the run alone.
#[test]
fn a_team_explores_and_reports_each_robot() {
    let dir = tempfile::tempdir().unwrap();
    let b = repo().join("buildings/small.toml");
    let team = |name: &str, extra: &[&str]| {
        let mut args = vec!["--strategy", "team-minpos"];
        args.extend_from_slice(extra);
        explore_with(&b, 2, &dir.path().join(name), &args)
    };
    let s = team("three", &["--robots", "3"]);
    assert!(s["explored_fraction"].as_f64().unwrap() >= 0.99, "{s}");
    assert_eq!(s["settings"]["robots"], 3);
    let t = &s["team"];
    assert_eq!(t["robots"], 3);
    assert_eq!(t["per_robot"].as_array().unwrap().len(), 3);
    let summed: f64 = t["per_robot"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["path_length_m"].as_f64().unwrap())
        .sum();
    assert!((summed - s["path_length_m"].as_f64().unwrap()).abs() < 1e-6);
    assert!(t["min_separation_m"].as_f64().unwrap() >= 0.38, "{t}");
    assert!(t["time_to_99_s"].as_f64().unwrap() <= s["exploration_time_s"].as_f64().unwrap());
    assert!(t["exchanges"].as_u64().unwrap() > 0);
    let overlap = t["overlap_fraction"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&overlap));
    let read =
        |name: &str, f: &str| std::fs::read_to_string(dir.path().join(name).join(f)).unwrap();
    for f in ["trajectory.csv", "decisions.csv"] {
        let text = read("three", f);
        assert!(text.starts_with("robot,"), "{f}");
        for k in 0..3 {
            assert!(
                text.lines().any(|l| l.starts_with(&format!("{k},"))),
                "{f}: robot {k}"
            );
        }
    }
    // The same run again.
    let again = team("again", &["--robots", "3"]);
    assert_eq!(
        read("three", "trajectory.csv"),
        read("again", "trajectory.csv")
    );
    assert_eq!(s["team"], again["team"]);
    // A team of one is the run alone (`team-minpos` alone is `nearest`).
    team("one", &["--robots", "1"]);
    explore_with(
        &b,
        2,
        &dir.path().join("nearest"),
        &["--strategy", "nearest"],
    );
    assert_eq!(
        read("one", "trajectory.csv"),
        read("nearest", "trajectory.csv")
    );
    assert!(!read("one", "summary.json").contains("\"team\""));
}

/// `--start` once per robot starts each where given; the team's starts by the default rule are
/// around robot 0, 2 radii + 0.3 m apart at least.
#[test]
fn team_starts_are_given_per_robot_or_placed_around_robot_0() {
    let dir = tempfile::tempdir().unwrap();
    let b = repo().join("buildings/small.toml");
    let placed = explore_with(
        &b,
        1,
        &dir.path().join("placed"),
        &[
            "--strategy",
            "team-nearest",
            "--robots",
            "4",
            "--time-limit-s",
            "20",
        ],
    );
    let starts: Vec<[f64; 2]> = placed["team"]["per_robot"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            [
                r["start"][0].as_f64().unwrap(),
                r["start"][1].as_f64().unwrap(),
            ]
        })
        .collect();
    assert_eq!(starts.len(), 4);
    for i in 0..4 {
        for j in i + 1..4 {
            let d = ((starts[i][0] - starts[j][0]).powi(2) + (starts[i][1] - starts[j][1]).powi(2))
                .sqrt();
            assert!(d >= 0.7 - 1e-9, "robots {i} and {j}: {d} m");
        }
    }
    let given = [
        format!("{},{},0", starts[0][0], starts[0][1]),
        format!("{},{},90", starts[2][0], starts[2][1]),
    ];
    let s = explore_with(
        &b,
        1,
        &dir.path().join("given"),
        &[
            "--strategy",
            "team-nearest",
            "--start",
            &given[0],
            "--start",
            &given[1],
            "--time-limit-s",
            "20",
        ],
    );
    assert_eq!(s["team"]["robots"], 2);
    let r1 = &s["team"]["per_robot"][1]["start"];
    assert!((r1[0].as_f64().unwrap() - starts[2][0]).abs() < 1e-9);
    assert!((r1[2].as_f64().unwrap() - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
}

/// Team inputs refused before anything runs, each message naming what was wrong.
#[test]
fn bad_team_inputs_are_refused_naming_them() {
    let dir = tempfile::tempdir().unwrap();
    let b = repo().join("buildings/small.toml");
    let b = b.to_str().unwrap();
    let out = dir.path().join("out");
    let out = out.to_str().unwrap();
    let cases: &[(&[&str], &[&str])] = &[
        (&["--robots", "9"], &["--robots", "1 to 8"]),
        (&["--robots", "0"], &["--robots"]),
        (
            &["--robots", "3", "--start", "5,5,0", "--start", "6,5,0"],
            &["--start", "2 times", "3 robots"],
        ),
        (
            &["--start", "5,5,0", "--start", "5.1,5,0"],
            &["robots 0 and 1", "overlap"],
        ),
        (
            &["--start", "random", "--start", "5,5,0"],
            &["--start random", "pose per robot"],
        ),
        (
            &[
                "--robots",
                "2",
                "--strategy-command",
                "python3 examples/strategies/nearest.py",
            ],
            &["external program", "robots = 1"],
        ),
    ];
    for (args, words) in cases {
        let mut all = vec!["explore", "--building", b, "--out", out, "-q"];
        all.extend_from_slice(args);
        let o = run(&all);
        assert!(!o.status.success(), "{args:?}");
        let e = stderr(&o);
        for w in *words {
            assert!(e.contains(w), "{args:?}: '{w}' not in: {e}");
        }
        assert!(!e.contains("panicked"), "{e}");
    }
}

/// A grid's `robots` factor: each strategy with each team size, labelled `NAME xN`; a bad
/// factor refused naming it.
#[test]
fn a_grid_runs_each_strategy_per_team_size() {
    let dir = tempfile::tempdir().unwrap();
    let small = repo().join("buildings/small.toml");
    let grid = |body: &str| {
        let p = dir.path().join("g.toml");
        std::fs::write(
            &p,
            format!(
                "format = \"floorcast-grid\"\nversion = 1\nname = \"g\"\nbuildings = [{:?}]\nseeds = [1]\n{body}\n[[strategies]]\nname = \"team-nearest\"\n[settings]\ntime_limit_s = 60\n",
                small.to_str().unwrap()
            ),
        )
        .unwrap();
        p
    };
    let res = dir.path().join("res");
    let o = run(&[
        "run",
        grid("robots = [1, 2]").to_str().unwrap(),
        "--results",
        res.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report = run(&["report", res.to_str().unwrap()]);
    let text = stdout(&report);
    for label in ["team-nearest x1", "team-nearest x2"] {
        assert!(text.contains(label), "{label}: {text}");
    }
    for (factor, words) in [
        ("robots = [9]", &["robots[0]", "1 to 8"][..]),
        ("robots = []", &["robots", "empty"][..]),
        ("robots = [2, 2]", &["robots[1]", "twice"][..]),
    ] {
        let o = run(&[
            "run",
            grid(factor).to_str().unwrap(),
            "--results",
            res.to_str().unwrap(),
            "-q",
        ]);
        assert!(!o.status.success(), "{factor}");
        let e = stderr(&o);
        for w in words {
            assert!(e.contains(w), "{factor}: '{w}' not in {e}");
        }
    }
}
