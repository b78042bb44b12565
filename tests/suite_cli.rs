//! `floorcast suite` end to end: the shipped suites list and check on the real data; a suite
//! whose files changed, or whose building is not explorable, fails naming each building; a grid
//! naming a suite plans and runs it, every record carrying the suite's name and hash; one
//! results directory holds one version of a suite.

mod common;

use std::path::{Path, PathBuf};

use common::*;

/// `floorcast ARGS` run in `dir`.
fn run_in(dir: &Path, args: &[&str]) -> std::process::Output {
    floorcast()
        .args(args)
        .current_dir(dir)
        .output()
        .expect("floorcast runs")
}

#[test]
fn the_shipped_suites_list_with_their_hashes() {
    let o = run_in(&repo(), &["suite", "list"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    for name in ["real-schools", "real-offices", "school-maps", "paper-set"] {
        assert!(out.contains(name), "{name}: {out}");
    }
    // Every annotated plan of maps/plans, by its type.
    let (schools, offices) = plans_by_type();
    assert!(schools >= 40 && offices >= 10, "{schools} {offices}");
    assert!(
        out.contains(&format!("school {schools}")) && out.contains(&format!("office {offices}")),
        "{out}"
    );
    let o = run_in(&repo(), &["suite", "list", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let list: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let list = list.as_array().unwrap();
    assert_eq!(list.len(), 4);
    for s in list {
        let name = s["name"].as_str().unwrap();
        let manifest =
            floorcast_formats::suite::read_manifest(&repo().join(format!("suites/{name}.toml")))
                .unwrap();
        assert_eq!(s["hash"], manifest.hash(), "{name}");
        assert_eq!(s["buildings"], manifest.buildings.len(), "{name}");
    }
    // The school maps and the paper set: as their folders hold them.
    let count = |s: &str| {
        list.iter().find(|x| x["name"] == s).unwrap()["buildings"]
            .as_u64()
            .unwrap()
    };
    assert_eq!(count("school-maps"), 11);
    assert_eq!(count("paper-set"), 10);
    // From a folder below the repository, by name too.
    let o = run_in(&repo().join("grids"), &["suite", "list"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// The real schools: every plan loads, has its manifest's hash, area and rooms, and is
/// explorable from its start (this fails when the floor-plan conversion changes a plan until
/// `floorcast suite update real-schools` is run).
#[test]
fn real_schools_check() {
    let o = run_in(&repo(), &["suite", "check", "real-schools"]);
    assert!(o.status.success(), "{}{}", stdout(&o), stderr(&o));
    let out = stdout(&o);
    let (schools, _) = plans_by_type();
    assert_eq!(out.matches(": ok: ").count(), schools, "{out}");
    assert!(
        out.contains(&format!("all {schools} buildings pass")),
        "{out}"
    );
}

/// How many plans of maps/plans are schools and how many offices (their `<main_type>`).
fn plans_by_type() -> (usize, usize) {
    let (mut schools, mut offices) = (0, 0);
    for e in std::fs::read_dir(repo().join("maps/plans")).unwrap() {
        let text = std::fs::read_to_string(e.unwrap().path()).unwrap();
        schools += usize::from(text.contains("<main_type>SCHOOL</main_type>"));
        offices += usize::from(text.contains("<main_type>OFFICE</main_type>"));
    }
    (schools, offices)
}

/// A suite of its own in a scratch copy: `suites/` and the buildings it names.
fn scratch() -> (tempfile::TempDir, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path().join("repo");
    std::fs::create_dir_all(root.join("buildings")).unwrap();
    std::fs::create_dir_all(root.join("grids")).unwrap();
    std::fs::copy(
        repo().join("buildings/small.toml"),
        root.join("buildings/small.toml"),
    )
    .unwrap();
    // Two halves that no door joins: the robot sees half of it from its start.
    std::fs::write(
        root.join("buildings/halves.toml"),
        "format = \"floorcast-building\"\nversion = 1\noutline = [[0.0, 0.0], [12.0, 0.0], [12.0, 6.0], [0.0, 6.0], [0.0, 0.0]]\n[[walls]]\nfrom = [6.0, 0.0]\nto = [6.0, 6.0]\nthickness = 0.2\n[start]\nx = 3.0\ny = 3.0\n",
    )
    .unwrap();
    (tmp, root)
}

/// `suite update NAME` of `files` as generated buildings made here under MIT, with `more` flags.
fn update_generated(
    root: &std::path::Path,
    name: &str,
    more: &[&str],
    files: &[&str],
) -> std::process::Output {
    let mut args = vec![
        "suite",
        "update",
        name,
        "--kind",
        "generated",
        "--source",
        "made here",
        "--licence",
        "MIT",
    ];
    args.extend_from_slice(more);
    args.extend_from_slice(files);
    run_in(root, &args)
}

#[test]
fn a_suite_is_written_checked_and_fails_naming_each_building() {
    let (_tmp, root) = scratch();
    // Made from files.
    let o = update_generated(
        &root,
        "mine",
        &["--description", "Two buildings"],
        &["buildings/small.toml", "buildings/halves.toml"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("(new)"), "{}", stdout(&o));
    let manifest = root.join("suites/mine.toml");
    let m = floorcast_formats::suite::read_manifest(&manifest).unwrap();
    assert_eq!(m.buildings.len(), 2);
    assert_eq!(m.buildings[1].path, "../buildings/small.toml");
    let small = root.join("buildings/small.toml");
    let check = run(&["building", "check", "--json", small.to_str().unwrap()]);
    let check: serde_json::Value = serde_json::from_str(&stdout(&check)).unwrap();
    assert_eq!(m.buildings[1].hash, check["hash"].as_str().unwrap());
    // The halves fail: half of it is out of reach.
    let o = run_in(&root, &["suite", "check", "mine"]);
    assert_clean_failure(
        &o,
        &[
            "suite mine",
            "1 of 2 buildings fail",
            "halves",
            "explorable",
        ],
    );
    assert!(stdout(&o).contains("small: ok:"), "{}", stdout(&o));
    // A building that changed: its hash, and the command that refreshes the manifest.
    let o = run_in(&root, &["suite", "update", "mine", "buildings/small.toml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let b = floorcast_formats::read_building(&small).unwrap();
    let g = sim_core::generate::generate(&sim_core::generate::GenerateConfig {
        seed: 2,
        area_m2: 400.0,
        kind: sim_core::generate::BuildingKind::School,
        clutter: false,
        rotation_rad: 0.0,
        name: "small".into(),
    });
    assert_ne!(g.content_hash(), b.content_hash());
    floorcast_formats::write_building_toml(&g, &small).unwrap();
    // By path too; the area and rooms differ as well.
    let o = run_in(&root, &["suite", "check", "suites/mine.toml"]);
    assert_clean_failure(
        &o,
        &[
            "1 of 1 buildings fail",
            "small (hash differs",
            "run `floorcast suite update suites/mine.toml`",
        ],
    );
    let o = run_in(&root, &["suite", "update", "suites/mine.toml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("content hash changed: small"),
        "{}",
        stdout(&o)
    );
    let o = run_in(&root, &["suite", "check", "mine"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A new file needs its description.
    let o = run_in(
        &root,
        &[
            "suite",
            "update",
            "mine",
            "buildings/small.toml",
            "buildings/halves.toml",
        ],
    );
    assert_clean_failure(
        &o,
        &[
            "--kind, --source, --licence",
            "halves.toml",
            "new to suite mine",
        ],
    );
    // An unknown suite names the ones there are.
    let o = run_in(&root, &["suite", "check", "theirs"]);
    assert_clean_failure(&o, &["no suite named 'theirs'", "its suites: mine"]);
}

/// A grid naming a suite: planned (`run --summary`), run, every record carrying the suite's name
/// and hash; a grid whose suite changed is refused by that results directory, and a grid whose
/// suite's file changed is refused until the manifest is refreshed.
#[test]
fn a_grid_runs_a_suite_and_its_records_carry_the_suite() {
    let (_tmp, root) = scratch();
    let o = update_generated(
        &root,
        "one",
        &["--description", "One building"],
        &["buildings/small.toml"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let hash = floorcast_formats::suite::read_manifest(&root.join("suites/one.toml"))
        .unwrap()
        .hash();
    std::fs::write(
        root.join("grids/g.toml"),
        "format = \"floorcast-grid\"\nversion = 1\nname = \"g\"\nresults = \"results/g\"\nsuites = [\"one\"]\nseeds = [1, 2]\n[[strategies]]\nname = \"baseline\"\n[settings]\ntime_limit_s = 20\n",
    )
    .unwrap();
    let o = run_in(&root, &["run", "grids/g.toml", "--summary"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains(&format!("suite one: 1 buildings, hash {hash}")),
        "{out}"
    );
    assert!(out.contains("0 of 2 jobs stored"), "{out}");
    let o = run_in(&root, &["run", "grids/g.toml", "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows = report_rows(&root.join("results/g"));
    assert_eq!(rows.len(), 2);
    for r in &rows {
        assert_eq!(r["suite"], "one");
        assert_eq!(r["suite_hash"], hash);
        assert_eq!(r["building"], "small");
    }
    let o = run_in(&root, &["report", "results/g"]);
    assert!(
        stdout(&o).contains(&format!("suite one, hash {hash}: 2 runs")),
        "{}",
        stdout(&o)
    );
    // The record in the store: summary version 2 with the suite.
    let stored = floorcast_coordinator::store::Store::open_existing(&root.join("results/g"))
        .unwrap()
        .all()
        .unwrap();
    for r in &stored {
        let s = r.summary.as_ref().unwrap();
        assert_eq!(s.version, 2);
        assert_eq!(s.suite.as_deref(), Some("one"));
        assert_eq!(s.suite_hash.as_deref(), Some(hash.as_str()));
    }
    // Another version of the suite (another building added): refused in that directory.
    let o = update_generated(
        &root,
        "one",
        &[],
        &["buildings/small.toml", "buildings/halves.toml"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run_in(&root, &["run", "grids/g.toml", "--quiet"]);
    assert_clean_failure(
        &o,
        &[
            "suite one has hash",
            "one results directory holds one version of a suite",
        ],
    );
    // A building whose file changed since its manifest was written: refused, naming the fix.
    let g = sim_core::generate::generate(&sim_core::generate::GenerateConfig {
        seed: 3,
        area_m2: 400.0,
        kind: sim_core::generate::BuildingKind::School,
        clutter: false,
        rotation_rad: 0.0,
        name: "small".into(),
    });
    floorcast_formats::write_building_toml(&g, &root.join("buildings/small.toml")).unwrap();
    let o = run_in(
        &root,
        &["run", "grids/g.toml", "--summary", "--results", "results/h"],
    );
    assert_clean_failure(
        &o,
        &[
            "grids/g.toml: suites[0]",
            "building small",
            "run `floorcast suite update one`",
        ],
    );
}
