//! `floorcast explore` end to end.

mod common;

use common::*;

fn explore(building: &std::path::Path, seed: u64, out: &std::path::Path) -> serde_json::Value {
    explore_with(building, seed, out, &["--strategy", "baseline"])
}

/// `--start X,Y,THETA` reads a heading as a grid's `[starts]` does: one angle of (-180, 180], so
/// that 360 starts the run 0 does (to the bit: its trajectory and decisions), and an `explore`
/// reproduces a grid's job.
#[test]
fn a_start_heading_is_one_angle_whichever_way_it_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let b = repo().join("buildings/small.toml");
    let own = explore_with(&b, 1, &dir.path().join("own"), &["--time-limit-s", "60"]);
    let (x, y) = (
        own["start"][0].as_f64().unwrap(),
        own["start"][1].as_f64().unwrap(),
    );
    // (heading as written, the same heading in (-180, 180], its radians as recorded)
    let cases: &[(&str, &str, f64)] = &[
        ("360", "0", 0.0),
        ("-180", "180", std::f64::consts::PI),
        ("-270", "90", std::f64::consts::FRAC_PI_2),
        ("270", "-90", -std::f64::consts::FRAC_PI_2),
        ("-45", "-45", -std::f64::consts::FRAC_PI_4),
    ];
    for (i, (written, normal, radians)) in cases.iter().enumerate() {
        let run = |heading: &str, name: &str| {
            let out = dir.path().join(format!("{i}-{name}"));
            let start = format!("{x},{y},{heading}");
            let s = explore_with(&b, 1, &out, &["--start", &start, "--time-limit-s", "60"]);
            let read = |f: &str| std::fs::read_to_string(out.join(f)).unwrap();
            (s, read("trajectory.csv"), read("decisions.csv"))
        };
        let (a, b_) = (run(written, "written"), run(normal, "normal"));
        assert_eq!(a.0["start"], b_.0["start"], "{written}");
        assert_eq!(a.0["start"][2].as_f64(), Some(*radians), "{written}");
        assert!(
            a.1 == b_.1 && a.2 == b_.2,
            "{written}: another run than {normal}"
        );
    }
}

#[test]
fn explores_the_small_building_completely_and_reproducibly() {
    let dir = tempfile::tempdir().unwrap();
    let b = repo().join("buildings/small.toml");
    let s1 = explore(&b, 1, &dir.path().join("a"));
    let s1b = explore(&b, 1, &dir.path().join("b"));
    let s2 = explore(&b, 2, &dir.path().join("c"));
    for k in [
        "building",
        "building_hash",
        "strategy",
        "seed",
        "exploration_time_s",
        "explored_area_m2",
        "free_area_m2",
        "explored_fraction",
        "path_length_m",
        "decisions",
        "stopped_early",
        "end_reason",
        "wall_time_s",
        "floorcast_version",
    ] {
        assert!(s1.get(k).is_some(), "summary lacks {k}");
    }
    assert_eq!(s1["end_reason"], "complete");
    assert!(s1["explored_fraction"].as_f64().unwrap() >= 0.97, "{s1}");
    // Same seed: same summary but for the wall time.
    let strip = |v: &serde_json::Value| {
        let mut v = v.clone();
        for k in ["wall_time_s", "speedup"] {
            v.as_object_mut().unwrap().remove(k);
        }
        v
    };
    assert_eq!(strip(&s1), strip(&s1b));
    // Another seed: different but close.
    let t1 = s1["exploration_time_s"].as_f64().unwrap();
    let t2 = s2["exploration_time_s"].as_f64().unwrap();
    assert_ne!(t1, t2);
    assert!((t1 - t2).abs() < 0.5 * t1.max(t2), "{t1} vs {t2}");
    // The other outputs exist and are usable.
    let a = dir.path().join("a");
    let csv = std::fs::read_to_string(a.join("progress.csv")).unwrap();
    assert!(csv.starts_with("time_s,explored_area_m2,explored_fraction\n"));
    assert!(csv.lines().count() > 10);
    let o = run(&[
        "building",
        "check",
        a.join("map.yaml").to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(image::open(a.join("final.png")).is_ok());
    // A complete run leaves no frontier to draw.
    assert_eq!(frontier_pixels(&a.join("final.png")), 0);
}

/// Pixels of the colour `final.png` draws the frontiers left at the end in.
fn frontier_pixels(png: &std::path::Path) -> usize {
    let img = image::open(png).unwrap().to_rgba8();
    img.pixels()
        .filter(|p| p.0[..3] == [200, 0, 200] && p.0[3] > 0)
        .count()
}

#[test]
fn the_picture_of_a_run_cut_short_shows_the_frontiers_left() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cut");
    let s = explore_with(
        &repo().join("buildings/small.toml"),
        1,
        &out,
        &["--time-limit-s", "60"],
    );
    assert_eq!(s["end_reason"], "time limit", "{s}");
    assert!(frontier_pixels(&out.join("final.png")) > 100);
}

#[test]
fn a_start_without_room_for_the_robot_is_refused_with_a_position_that_has_room() {
    let b = repo().join("buildings/small.toml");
    // (start, what is wrong with it); small.toml's west wall's face is at x = -0.1.
    let cases = [
        ("-50,-50,0", "is not in free space"),
        (
            "0.0,9.81,0",
            "is 0.100 m from solid space, too close for the robot's body",
        ),
        ("0.05,9.81,90", "is 0.150 m from solid space"),
    ];
    for (start, problem) in cases {
        let dir = tempfile::tempdir().unwrap();
        let o = run(&[
            "explore",
            "--building",
            b.to_str().unwrap(),
            "--start",
            start,
            "--out",
            dir.path().to_str().unwrap(),
            "--quiet",
        ]);
        let hint = "the nearest free position with room for the robot is ";
        assert_clean_failure(&o, &["small.toml", "from --start", problem, hint]);
        // The position suggested is accepted.
        let err = stderr(&o);
        let xy = err.trim().rsplit(hint).next().unwrap();
        let s = explore_with(
            &b,
            1,
            dir.path(),
            &["--start", &format!("{xy},0"), "--time-limit-s", "5"],
        );
        assert_eq!(s["start_source"], "command line", "{s}");
        assert_eq!(
            format!(
                "{:.2},{:.2}",
                s["start"][0].as_f64().unwrap(),
                s["start"][1].as_f64().unwrap()
            ),
            xy
        );
    }
}

#[test]
fn a_start_heading_beyond_a_full_turn_is_refused() {
    let b = repo().join("buildings/small.toml");
    for (start, needle) in [
        ("3,3,1e300", "heading 1e300"),
        ("3,3,361", "[-360, 360]"),
        ("3,3,-400", "[-360, 360]"),
        ("3,nan,0", "'nan' in '3,nan,0' is not a finite number"),
        ("3e400,3,0", "'3e400' in '3e400,3,0' is not a finite number"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let o = run(&[
            "explore",
            "--building",
            b.to_str().unwrap(),
            &format!("--start={start}"),
            "--out",
            dir.path().to_str().unwrap(),
            "--quiet",
        ]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{start}: {err}");
        assert!(
            err.contains(needle) && !err.contains("panicked"),
            "{start}: {err}"
        );
    }
}

/// A number a flag cannot take is refused naming the flag, the value and what was expected; a
/// negative number is that flag's value, not taken for an unknown flag.
#[test]
fn a_flags_bad_number_is_refused_saying_what_was_expected() {
    let b = repo().join("buildings/small.toml");
    let whole = |lo: &str, hi: &str| format!("expected a whole number from {lo} to {hi}");
    let u64_max = u64::MAX.to_string();
    for (flag, value, expected) in [
        ("--seed", "-1", whole("0", &u64_max)),
        ("--seed", "1.5", whole("0", &u64_max)),
        ("--seed", "18446744073709551616", whole("0", &u64_max)),
        ("--max-cells", "-5", whole("1", "4000000000")),
        ("--max-cells", "0", whole("1", "4000000000")),
        ("--time-limit-s", "abc", "expected a number".into()),
        ("--time-limit-s", "inf", "expected a finite number".into()),
        ("--alpha", "nan", "expected a finite number".into()),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let o = run(&[
            "explore",
            "--building",
            b.to_str().unwrap(),
            flag,
            value,
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{flag} {value}: {err}");
        assert!(
            err.contains(&format!("invalid value '{value}' for '{flag}"))
                && err.contains(&expected),
            "{flag} {value}: {err}"
        );
        assert!(!out.exists(), "{flag} {value}");
    }
}

#[test]
fn a_random_start_is_drawn_from_the_seed() {
    let b = repo().join("buildings/small.toml");
    let dir = tempfile::tempdir().unwrap();
    let args = ["--start", "random", "--time-limit-s", "5"];
    let a = explore_with(&b, 3, &dir.path().join("a"), &args);
    let again = explore_with(&b, 3, &dir.path().join("again"), &args);
    let other = explore_with(&b, 4, &dir.path().join("other"), &args);
    assert_eq!(a["start_source"], "random");
    assert_eq!(a["start"], again["start"]);
    assert_ne!(a["start"], other["start"]);
    // Not the building file's start.
    let file = explore_with(&b, 3, &dir.path().join("file"), &["--time-limit-s", "5"]);
    assert_eq!(file["start_source"], "building file");
    assert_ne!(a["start"], file["start"]);
}

#[test]
fn buildings_open_to_their_outline_start_inside_and_are_explored() {
    // BUILDING_FORMAT.md's example without its [start] (walls only along the bottom and half
    // way up the middle: the outline closes the rest), and an outline alone (60 m2). Both
    // used to start in a corner or not at all.
    let doc = std::fs::read_to_string(repo().join("formats/BUILDING_FORMAT.md")).unwrap();
    let example: String = doc
        .split("```toml\n")
        .nth(1)
        .unwrap()
        .split("```")
        .next()
        .unwrap()
        .split("[start]")
        .next()
        .unwrap()
        .to_string();
    assert!(example.contains("[[walls]]") && !example.contains("[start]"));
    let outline = "format = \"floorcast-building\"\nversion = 1\n\
                   outline = [[0.0, 0.0], [10.0, 0.0], [10.0, 6.0], [0.0, 6.0], [0.0, 0.0]]\n";
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in [("doc.toml", example.as_str()), ("outline.toml", outline)] {
        let file = dir.path().join(name);
        std::fs::write(&file, text).unwrap();
        let s = explore_with(
            &file,
            1,
            &dir.path().join(format!("{name}-out")),
            &["--localization", "ground-truth"],
        );
        assert_eq!(s["start_source"], "largest clearance", "{name}: {s}");
        let (x, y) = (
            s["start"][0].as_f64().unwrap(),
            s["start"][1].as_f64().unwrap(),
        );
        assert!(
            (2.5..=7.6).contains(&x) && (2.9..=3.6).contains(&y),
            "{name}: {x}, {y}"
        );
        assert_eq!(s["end_reason"], "complete", "{name}: {s}");
        assert!(
            s["explored_fraction"].as_f64().unwrap() > 0.97,
            "{name}: {s}"
        );
    }
}

#[test]
fn the_readme_quick_start_pose_on_franch1_has_room_for_the_robot() {
    let dir = tempfile::tempdir().unwrap();
    let s = explore_with(
        &maps_dir().join("schools/Franch1.yaml"),
        1,
        dir.path(),
        &[
            "--localization",
            "ground-truth",
            "--start",
            "8,5,90",
            "--time-limit-s",
            "5",
        ],
    );
    assert_eq!(s["start_source"], "command line");
}

#[test]
fn the_true_layout_oracle_on_a_map_without_rooms_is_a_clean_error() {
    let dir = tempfile::tempdir().unwrap();
    let map = maps_dir().join("schools/Sabadell1.yaml");
    let o = run(&[
        "explore",
        "--building",
        map.to_str().unwrap(),
        "--strategy",
        "layout-truth",
        "--out",
        dir.path().to_str().unwrap(),
        "--quiet",
    ]);
    assert_clean_failure(&o, &["Sabadell1", "layout-truth", "ground-truth rooms"]);
}

#[test]
fn layout_snapshots_draw_the_paper_sequence() {
    let dir = tempfile::tempdir().unwrap();
    let b = repo().join("buildings/small.toml");
    let s = explore_with(
        &b,
        1,
        dir.path(),
        &["--strategy", "layout", "--layout-snapshots"],
    );
    assert_eq!(s["strategy"], "layout");
    for pct in [20, 40, 60, 80, 90] {
        let p = dir.path().join(format!("layout-{pct}.png"));
        assert!(image::open(&p).is_ok(), "{} missing", p.display());
    }
}

/// Real school maps (map_server rasters from `maps/schools`) explored with the SLAM
/// localization, one test per case: at least 97 % explored, not cut by the time limit, walls
/// where the building has them, and an end class that agrees with the frontier cells left
/// ("complete" exactly when none is left that the robot did not look into; the others name
/// what is left, e.g. a speckled corner the robot gave up on).
fn explores_school_map(name: &str, seed: u64) {
    let dir = tempfile::tempdir().unwrap();
    let map = maps_dir().join(format!("schools/{name}.yaml"));
    let s = explore(&map, seed, dir.path());
    let f = s["explored_fraction"].as_f64().unwrap();
    assert!(f >= 0.97, "{name} seed {seed}: explored {f}");
    assert_ne!(s["end_reason"], "time limit", "{name} seed {seed}");
    assert_ne!(s["end_reason"], "early stop", "{name} seed {seed}");
    let left = s["frontier_cells_left"].as_u64().unwrap();
    assert_eq!(s["end_reason"] == "complete", left == 0, "{s}");
    let p = s["map_occupied_precision_aligned"].as_f64().unwrap();
    assert!(p >= 0.85, "{name} seed {seed}: occupied precision {p}");
}

macro_rules! school_map_cases {
    ($($(#[$doc:meta])* $test:ident: $name:literal, $seed:literal;)*) => {
        $(
            $(#[$doc])*
            #[test]
            fn $test() {
                explores_school_map($name, $seed);
            }
        )*
    };
}

school_map_cases! {
    school_sabadell1_seed_1: "Sabadell1", 1;
    school_sabadell1_seed_2: "Sabadell1", 2;
    school_franch1_seed_1: "Franch1", 1;
    school_franch1_seed_2: "Franch1", 2;
    school_autosales_seed_1: "autoSales", 1;
    school_autosales_seed_2: "autoSales", 2;
    school_classforaction_seed_1: "ClassForAction", 1;
    /// Starts in open space: the heading drifts by ~3 degrees before the laser sees a wall, so
    /// the whole map is turned; the explored area credits what the sensor observed.
    school_modern_office_seed_2: "modern-office-floor-plan-1", 2;
    /// The last room is seen from the corridor through its door at a slant: the frontier runs
    /// from the door up a strip too narrow to drive, so its middle cell cannot be reached. The
    /// run used to end there (85 % explored); the frontier's reachable end is now the last
    /// resort before ending.
    school_lamuniere1_seed_1: "Lamuniere1", 1;
    /// The robot used to aim at the waypoint after a corner once within reach of the corner, run
    /// into the end of the wall the path went around, and push against it until every goal was
    /// given up (96.5 % explored); it now aims along the path.
    school_sabadell3_seed_2: "Sabadell3", 2;
    /// Drawn bent before 0.3.0 (aligned precision 0.77 on both seeds): the scan matches' heading
    /// noise random-walked the estimate; the calibrated odometry now holds it.
    school_battle_creekhs_2_seed_2: "battle_creekhs_2", 2;
}

/// The early stops on a real map (modern-office, 1640 m² explorable) from a start where one used
/// to miss a room: an early stop may drop only what the layout predicts is left, never a room
/// behind an opening the robot has seen. Each case ends by the early stop with less than 5 m²
/// (a corner or two) left unexplored.
fn early_stop_leaves_no_room(strategy: &str, seed: u64, start: &str) {
    let dir = tempfile::tempdir().unwrap();
    let map = maps_dir().join("schools/modern-office-floor-plan-1.yaml");
    let s = explore_with(
        &map,
        seed,
        dir.path(),
        &["--strategy", strategy, "--start", start],
    );
    assert_eq!(s["end_reason"], "early stop", "{s}");
    let left = s["unexplored_free_m2"].as_f64().unwrap();
    assert!(
        left < 5.0,
        "{strategy} seed {seed} from {start}: {left} m2 left"
    );
}

macro_rules! early_stop_cases {
    ($($(#[$doc:meta])* $test:ident: $strategy:literal, $seed:literal, $start:literal;)*) => {
        $(
            $(#[$doc])*
            #[test]
            fn $test() {
                early_stop_leaves_no_room($strategy, $seed, $start);
            }
        )*
    };
}

early_stop_cases! {
    /// A room of 50 m² below the main corridor is seen only through its door at a slant: a
    /// wedge of free cells too thin to drive, whose frontier's goal could not be reached, so the
    /// rule summed the other frontiers' gains and stopped at 96.7 % explored (54.7 m² left).
    /// The unreachable frontiers now get their reachable part before the rule ends the run.
    /// (Seed 2 since 0.7.0, whose laser changed the runs: seed 1's now ends complete.)
    early_stop_modern_office_layout_es_random_start: "layout-es", 2, "6.375,32.225,-126.92072186924302";
    early_stop_modern_office_layout_aes_random_start: "layout-aes", 1, "6.375,32.225,-126.92072186924302";
}

/// Runs from random starts that used to end "stuck" short of 97 % explored (the starts grid) when
/// at one decision no frontier could be reached even without the safety margin, and the last
/// resort gave every frontier up. Two causes, two more rungs of the ladder: (pocket_) the map,
/// sharpened by later scans, showed the passage the robot had come in by narrower than its body;
/// the robot now plans through the cells it has travelled as well and leaves the way it came.
/// (closer_look_) a doorway seen only from afar, drawn narrower than the robot; the robot now
/// drives as near to it as it can and looks again. `building` is relative to the repository;
/// `rooms_never_entered` is what the summary must say (null on a map without rooms).
fn a_random_start_that_ended_short_explores_the_building(
    building: &str,
    strategy: &str,
    seed: u64,
    start: &str,
    rooms_never_entered: serde_json::Value,
) {
    let dir = tempfile::tempdir().unwrap();
    let s = explore_with(
        &repo().join(building),
        seed,
        dir.path(),
        &["--strategy", strategy, "--start", start],
    );
    let f = s["explored_fraction"].as_f64().unwrap();
    assert!(
        f >= 0.97,
        "{building} {strategy} seed {seed} from {start}: explored {f}"
    );
    assert_ne!(s["end_reason"], "time limit", "{s}");
    assert_eq!(s["rooms_never_entered"], rooms_never_entered, "{s}");
}

macro_rules! short_end_cases {
    ($($(#[$doc:meta])* $test:ident: $building:literal, $strategy:literal, $seed:literal, $start:literal, $rooms:expr;)*) => {
        $(
            $(#[$doc])*
            #[test]
            fn $test() {
                a_random_start_that_ended_short_explores_the_building(
                    $building, $strategy, $seed, $start, $rooms,
                );
            }
        )*
    };
}

short_end_cases! {
    /// A crowded room whose way out the map narrowed to less than the body: 95.2 % explored.
    pocket_freiburg_building101_baseline: "maps/radish/freiburg_building101.yaml",
        "baseline", 1, "9.125,14.375,-142.7496640392991", serde_json::Value::Null;
    pocket_freiburg_building101_layout_es: "maps/radish/freiburg_building101.yaml",
        "layout-es", 1, "9.125,14.375,-142.7496640392991", serde_json::Value::Null;
    /// A corridor about 0.5 m wide pinched shut by the map's noise ahead and behind: 95.5 %.
    pocket_intel_map_baseline: "maps/radish/intel_map.yaml",
        "baseline", 1, "9.625,17.725,-142.7496640392991", serde_json::Value::Null;
    /// The door of a 67 m² room given up, the run ended "stuck" at 97.7 % with the room never
    /// entered (`baseline` explores it).
    pocket_paper_08_layout_es: "buildings/paper/paper-08.toml",
        "layout-es", 1, "80.275,15.975,109.27675325726294", serde_json::json!(0);
    /// The door into the building's middle seen only from afar: the middle never entered,
    /// 79.3 % explored (0.5.0's starts grid).
    closer_look_intel_map_baseline: "maps/radish/intel_map.yaml",
        "baseline", 1, "1.5750000000000002,22.275000000000002,14.83180040987069", serde_json::Value::Null;
}

/// Every strategy completes on a real map; the early stop leaves it nearly explored.
#[test]
fn every_strategy_explores_a_real_map() {
    let dir = tempfile::tempdir().unwrap();
    let map = maps_dir().join("schools/Sabadell1.yaml");
    for strategy in ["layout", "layout-es", "layout-gaps-es"] {
        let s = explore_with(
            &map,
            1,
            &dir.path().join(strategy),
            &["--strategy", strategy],
        );
        assert_eq!(s["strategy"], strategy);
        let f = s["explored_fraction"].as_f64().unwrap();
        assert!(f >= 0.97, "{strategy}: explored {f}");
        assert_ne!(s["end_reason"], "time limit", "{strategy}");
    }
}

/// A generated building with a ring of corridors (paper-10, 3569 m2): before 0.3.0 the heading
/// random-walked by up to 7 degrees around the ring, and this run ended with 98.5 % explored and
/// a map whose walls overlapped the building's only after a 0.31 aligned precision (walls
/// doubled, rooms drawn turned). The run is that one, with the paper's layout trigger (the
/// default before 0.7): its path, hence its map, depends on it. (The aligned precision of
/// `layout` on paper-10 over seeds 1-8 is 0.74-0.93 with that trigger and 0.72-0.90 with the
/// default, 2026-11-30: this seed's 0.92 is among the best of both; doubled walls gave 0.31.)
#[test]
fn a_ring_of_corridors_is_mapped_without_doubled_walls() {
    let dir = tempfile::tempdir().unwrap();
    let b = repo().join("buildings/paper/paper-10.toml");
    let s = explore_with(
        &b,
        6,
        dir.path(),
        &["--strategy", "layout", "--layout-update-fraction", "0"],
    );
    let f = s["explored_fraction"].as_f64().unwrap();
    assert!(f >= 0.97, "explored {f}");
    assert_eq!(s["end_reason"], "complete");
    let p = s["map_occupied_precision_aligned"].as_f64().unwrap();
    assert!(p >= 0.9, "aligned occupied precision {p}");
}

/// With map updates every 0.5 m / 0.25 rad, Lamuniere1 (seed 2) used to end at 86 % explored:
/// the map showed the passage the robot had come in by narrower than the robot plus its safety
/// margin, so no frontier could be reached. Planning without the margin is now the last resort.
#[test]
fn a_passage_narrower_than_the_safety_margin_does_not_end_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let settings = dir.path().join("settings.json");
    std::fs::write(
        &settings,
        r#"{"map_update_distance_m": 0.5, "map_update_angle_rad": 0.25}"#,
    )
    .unwrap();
    let map = maps_dir().join("schools/Lamuniere1.yaml");
    let s = explore_with(
        &map,
        2,
        &dir.path().join("run"),
        &["--settings", settings.to_str().unwrap()],
    );
    assert_eq!(s["settings"]["map_update_distance_m"], 0.5, "{s}");
    assert_ne!(s["end_reason"], "time limit", "{s}");
    let left = s["frontier_cells_left"].as_u64().unwrap();
    assert_eq!(s["end_reason"] == "complete", left == 0, "{s}");
    let f = s["explored_fraction"].as_f64().unwrap();
    assert!(f >= 0.97, "explored {f}");
}

/// With the paper's straight-line distance in the utility, the robot on paper-03 (seed 1) used
/// to alternate at every periodic re-decision between two candidates behind walls, each nearer
/// in a straight line once it headed for the other, until the 4 h time limit (89.8 % explored).
/// Periodic re-decisions now wait for new map, so the robot keeps to its goal, and the run ends.
#[test]
fn alternating_goals_do_not_hold_the_robot_forever() {
    let dir = tempfile::tempdir().unwrap();
    let b = repo().join("buildings/paper/paper-03.toml");
    let s = explore_with(
        &b,
        1,
        dir.path(),
        &["--strategy", "baseline", "--utility-distance", "euclidean"],
    );
    assert_eq!(s["end_reason"], "complete", "{s}");
    assert!(s["explored_fraction"].as_f64().unwrap() >= 0.97, "{s}");
    assert!(
        s["exploration_time_s"].as_f64().unwrap() < 2.0 * 3600.0,
        "{s}"
    );
    assert_eq!(s["settings"]["utility_distance"], "euclidean", "{s}");
}

/// A run's `summary.json` names every setting, so that its `settings` given back as a settings
/// file run the same run: with the paper's layout trigger (`layout_update_fraction` 0, which
/// a table without the setting would read as the default 0.1) and the default, `layout-es` on
/// a building whose known map passes the 200 m2 where the two triggers part.
#[test]
fn a_records_settings_given_back_as_a_settings_file_run_the_same_run() {
    let dir = tempfile::tempdir().unwrap();
    let b = repo().join("buildings/paper/paper-01.toml");
    let mut layouts = Vec::new();
    for fraction in ["0", "0.1"] {
        let first_out = dir.path().join(format!("first-{fraction}"));
        let first = explore_with(
            &b,
            1,
            &first_out,
            &[
                "--strategy",
                "layout-es",
                "--layout-update-fraction",
                fraction,
                "--time-limit-s",
                "900",
            ],
        );
        let written = first["settings"].as_object().unwrap();
        assert_eq!(
            written["layout_update_fraction"].as_f64(),
            Some(fraction.parse().unwrap()),
            "{first}"
        );
        let file = dir.path().join(format!("settings-{fraction}.json"));
        std::fs::write(&file, serde_json::to_string(&first["settings"]).unwrap()).unwrap();
        let again_out = dir.path().join(format!("again-{fraction}"));
        let again = explore_with(
            &b,
            1,
            &again_out,
            &[
                "--strategy",
                "layout-es",
                "--settings",
                file.to_str().unwrap(),
            ],
        );
        assert_eq!(again["settings"], first["settings"], "{fraction}");
        for f in ["decisions.csv", "trajectory.csv"] {
            let read = |d: &std::path::Path| std::fs::read_to_string(d.join(f)).unwrap();
            assert!(
                read(&first_out) == read(&again_out),
                "{fraction}: {f} differs"
            );
        }
        assert_eq!(again["layouts_computed"], first["layouts_computed"]);
        layouts.push(first["layouts_computed"].as_u64().unwrap());
    }
    // The two triggers part on this building: the test tells them apart.
    assert!(layouts[0] > layouts[1], "layouts {layouts:?}");
}

/// A settings file in another format is refused with the file's name and what is expected.
#[test]
fn a_settings_file_that_is_not_json_is_refused_with_what_is_expected() {
    let dir = tempfile::tempdir().unwrap();
    let settings = dir.path().join("settings.toml");
    std::fs::write(&settings, "alpha = 1.0\n").unwrap();
    let b = repo().join("buildings/small.toml");
    let o = run(&[
        "explore",
        "--building",
        b.to_str().unwrap(),
        "--settings",
        settings.to_str().unwrap(),
        "--out",
        dir.path().join("out").to_str().unwrap(),
        "--quiet",
    ]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("settings.toml") && e.contains("JSON object"),
        "{e}"
    );
    assert!(!dir.path().join("out/summary.json").exists());
}

/// Real buildings with their true rooms: from the default start, `baseline` and the true-layout
/// oracle with the paper's early stop explore at least 97 % and leave no room unexplored. (The
/// oracle's gain once stopped at a door the robot had not yet seen open: Lamuniere1 ended at
/// 85.9 % with a classroom unseen; Sabadell3's first doorways let the robot into 85 %.)
#[test]
fn annotated_plans_are_explored_with_no_room_left() {
    let dir = tempfile::tempdir().unwrap();
    for plan in [
        "Lamuniere1_updated",
        "Sabadell3_updated",
        "Franch1_updated",
        "chewlane",
    ] {
        for strategy in ["baseline", "layout-truth-es"] {
            let b = repo().join(format!("maps/plans/{plan}.xml"));
            let s = explore_with(
                &b,
                1,
                &dir.path().join(format!("{plan}-{strategy}")),
                &["--strategy", strategy],
            );
            let what = format!("{plan} {strategy}");
            assert!(
                s["explored_fraction"].as_f64().unwrap() >= 0.97,
                "{what}: {s}"
            );
            assert_eq!(s["rooms_unexplored"], 0, "{what}: {s}");
            assert!(s["rooms_never_entered"].as_u64().is_some(), "{what}: {s}");
        }
    }
}

/// `floorcast tour` on real buildings of three kinds (a SLAM map with clutter, an annotated
/// plan): the tour sees at least 99 % of the explorable area by its own sweeps and when
/// replayed with the run's laser, and its record and picture are written.
#[test]
fn the_tour_of_real_buildings_is_seen_when_replayed() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        "maps/radish/freiburg_building79.yaml",
        "maps/plans/Borchen4_updated.xml",
    ];
    for building in cases {
        let json = dir.path().join("tour.json");
        let png = dir.path().join("tour.png");
        let o = run(&[
            "tour",
            "--building",
            repo().join(building).to_str().unwrap(),
            "--json",
            json.to_str().unwrap(),
            "--picture",
            png.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{building}: {}", stderr(&o));
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert_eq!(v["format"], "floorcast-tour", "{building}");
        for field in ["covered_fraction", "replayed_fraction"] {
            let f = v[field].as_f64().unwrap();
            assert!(f >= 0.99, "{building}: {field} {f}");
        }
        assert!(v["time_s"].as_f64().unwrap() > 0.0, "{building}");
        assert!(std::fs::metadata(&png).unwrap().len() > 1000, "{building}");
    }
}
