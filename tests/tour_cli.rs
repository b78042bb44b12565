//! `floorcast tour` and the tours `run` makes: an estimate before a tour is made, a lower bound
//! beside it, a robot that fits nowhere refused (exit 2), and a tour over `run --tour-budget`
//! skipped with a warning, its runs then shown without efficiency by `report`.

mod common;
use common::*;

/// Writes `settings` (a JSON object) to a file in `dir`.
fn settings(dir: &std::path::Path, name: &str, settings: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, settings).unwrap();
    p
}

/// `floorcast tour --building B --settings S --json J` with the settings `json` written to
/// `dir/settings.json`: the command's output and J (`dir/tour.json`).
fn tour_of(
    dir: &std::path::Path,
    building: &std::path::Path,
    json: &str,
) -> (std::process::Output, std::path::PathBuf) {
    let s = settings(dir, "settings.json", json);
    let out = dir.join("tour.json");
    let o = run(&[
        "tour",
        "--building",
        building.to_str().unwrap(),
        "--settings",
        s.to_str().unwrap(),
        "--json",
        out.to_str().unwrap(),
    ]);
    (o, out)
}

/// A robot that fits nowhere it could drive from the start (radius 2 m in buildings/small.toml,
/// or 1.5 m) is an error naming the building and the setting, exit 2, and no JSON is written.
#[test]
fn a_robot_that_fits_nowhere_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let small = repo().join("buildings/small.toml");
    for radius in ["2", "1.5"] {
        let (o, json) = tour_of(
            dir.path(),
            &small,
            &format!("{{\"robot_radius_m\": {radius}}}"),
        );
        assert_clean_failure(
            &o,
            &[
                "small.toml",
                &format!("robot_radius_m = {radius}"),
                "fits nowhere",
            ],
        );
        assert!(!json.exists(), "{radius}: a tour was written");
    }
}

/// `tour` says its estimate before it starts, and after the tour its lower bound, which the JSON
/// (record version 4) holds, at most the tour's time; a shorter laser range makes both the
/// estimate and the bound larger.
#[test]
fn the_tour_says_its_estimate_and_its_lower_bound() {
    let dir = tempfile::tempdir().unwrap();
    let small = repo().join("buildings/small.toml");
    let mut seen = Vec::new();
    for range in ["6", "2"] {
        let (o, json) = tour_of(
            dir.path(),
            &small,
            &format!("{{\"laser_range_m\": {range}}}"),
        );
        assert!(o.status.success(), "{}", stderr(&o));
        let out = stdout(&o);
        let first = out.lines().next().unwrap();
        assert!(
            first.contains("making the tour:") && first.contains("estimated"),
            "{out}"
        );
        assert!(out.contains("no tour is faster than"), "{out}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert_eq!(v["version"], 4);
        let bound = v["lower_bound_s"].as_f64().unwrap();
        let time = v["time_s"].as_f64().unwrap();
        assert!(
            bound > 0.0 && bound <= time,
            "{range}: bound {bound}, tour {time}"
        );
        let estimate: f64 = first
            .split("estimated ")
            .nth(1)
            .and_then(|t| t.split(' ').next())
            .and_then(|t| t.parse().ok())
            .unwrap_or_else(|| panic!("{first}"));
        seen.push((estimate, bound));
    }
    assert!(seen[1].0 >= seen[0].0, "{seen:?}");
    assert!(seen[1].1 > seen[0].1, "{seen:?}");
}

/// `run` with a tour whose estimate exceeds `--tour-budget` skips it with a warning that says
/// the estimate and the budget; `report` then shows no efficiency and says why. A budget below
/// 1 s is refused.
#[test]
fn run_skips_a_tour_over_its_budget() {
    let dir = tempfile::tempdir().unwrap();
    let small = repo().join("buildings/small.toml");
    let g = dir.path().join("grid.toml");
    std::fs::write(
        &g,
        format!(
            r#"format = "floorcast-grid"
version = 1
name = "budget"
buildings = ["{}"]
seeds = [1]
[[strategies]]
name = "nearest"
[settings]
time_limit_s = 30
laser_range_m = 0.5
"#,
            small.display()
        ),
    )
    .unwrap();
    let res = dir.path().join("res");
    let o = run(&[
        "run",
        g.to_str().unwrap(),
        "--results",
        res.to_str().unwrap(),
        "-q",
        "--tour-budget",
        "0.5",
    ]);
    assert_clean_failure(&o, &["--tour-budget", "0.5", "at least 1"]);
    let o = run(&[
        "run",
        g.to_str().unwrap(),
        "--results",
        res.to_str().unwrap(),
        "-q",
        "--tour-budget",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("skipped: its estimate is") && err.contains("over the budget of 1 s"),
        "{err}"
    );
    let o = run(&["report", res.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(!out.contains("efficiency at"), "{out}");
    assert!(
        out.contains("no efficiency: 1 successful runs have no stored tour"),
        "{out}"
    );
}
