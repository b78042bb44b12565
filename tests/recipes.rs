//! ARCHITECTURE.md's "Where to add" recipes, checked by counting what each asks for: every map
//! format `read_building` accepts comes with its reader, its malformed inputs (the corpus of
//! `tests/malformed/`) and an example in the repository; every robot, laser and odometry
//! parameter is a setting; every statistic is tested where it is defined. (A strategy's recipe:
//! `tests/strategy_registry.rs`.)

use std::collections::BTreeSet;
use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &str) -> String {
    std::fs::read_to_string(root().join(path)).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The extensions `formats::read_building` dispatches on (its `kind_of` match arms), each with
/// the `Kind` it chooses.
fn format_extensions() -> Vec<(String, String)> {
    let lib = read("formats/src/lib.rs");
    let start = lib
        .find("fn kind_of(")
        .expect("formats/src/lib.rs: fn kind_of");
    let body = &lib[start..start + lib[start..].find("\n}\n").unwrap()];
    let mut out = Vec::new();
    for line in body.lines().filter(|l| l.contains("=> Ok(Kind::")) {
        let kind = line
            .split("Kind::")
            .nth(1)
            .unwrap()
            .trim_end_matches([')', ',']);
        for ext in line.split('"').skip(1).step_by(2) {
            out.push((ext.to_string(), kind.to_string()));
        }
    }
    out
}

/// Files under `dir` (recursively) with extension `ext`.
fn files_with(dir: &Path, ext: &str, out: &mut Vec<std::path::PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            files_with(&p, ext, out);
        } else if p.extension().is_some_and(|x| x.eq_ignore_ascii_case(ext)) {
            out.push(p);
        }
    }
}

/// A map format: `read_building` chooses it by extension, a reader function of a module of
/// `formats/src/` reads it, the malformed corpus has cases of it that the CLI runs, and the
/// repository holds an example (under `maps/` or `buildings/`).
#[test]
fn every_map_format_has_its_reader_malformed_cases_and_an_example() {
    let exts = format_extensions();
    let kinds: BTreeSet<&str> = exts.iter().map(|(_, k)| k.as_str()).collect();
    assert!(kinds.len() >= 4, "formats read: {exts:?}");
    let lib = read("formats/src/lib.rs");
    let cases = read("tests/malformed/cases.toml");
    for kind in kinds {
        // The reader: `Kind::X => ... read_x(path) ...` in `read_building`, `read_x` defined in
        // a module of its own.
        let arm = lib
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("Kind::{kind} =>")))
            .unwrap_or_else(|| panic!("read_building has no arm for Kind::{kind}"));
        let reader: String = arm
            .split("read_")
            .nth(1)
            .map(|r| r.chars().take_while(|c| c.is_alphanumeric() || *c == '_'))
            .unwrap_or_else(|| panic!("Kind::{kind}: no read_ function in {arm}"))
            .collect();
        let defined = std::fs::read_dir(root().join("formats/src"))
            .unwrap()
            .flatten()
            .map(|e| e.path())
            .filter(|p| !p.ends_with("lib.rs"))
            .any(|p| {
                let text = std::fs::read_to_string(&p).unwrap_or_default();
                text.contains(&format!("pub fn read_{reader}("))
            });
        assert!(
            defined,
            "Kind::{kind}: read_{reader} not defined in a module of formats/src"
        );
        let ext_of_kind: Vec<&str> = exts
            .iter()
            .filter(|(_, k)| k == kind)
            .map(|(e, _)| e.as_str())
            .collect();
        let mut malformed = Vec::new();
        let mut examples = Vec::new();
        for ext in &ext_of_kind {
            files_with(&root().join("tests/malformed/files"), ext, &mut malformed);
            files_with(&root().join("maps"), ext, &mut examples);
            files_with(&root().join("buildings"), ext, &mut examples);
        }
        let run: Vec<_> = malformed
            .iter()
            .filter(|p| cases.contains(p.file_name().unwrap().to_str().unwrap()))
            .collect();
        assert!(
            !run.is_empty(),
            "Kind::{kind} ({ext_of_kind:?}): no malformed case"
        );
        assert!(
            !examples.is_empty(),
            "Kind::{kind} ({ext_of_kind:?}): no example"
        );
    }
}

/// The reader of the recipe's count sees what a fifth format would add.
#[test]
fn the_format_count_reads_the_dispatch() {
    let exts = format_extensions();
    for (e, k) in [
        ("yaml", "MapServer"),
        ("yml", "MapServer"),
        ("xml", "FloorPlan"),
    ] {
        assert!(exts.contains(&(e.to_string(), k.to_string())), "{exts:?}");
    }
}

/// The `pub` fields of struct `name` in `text` (a struct of named fields, one per line).
fn struct_fields(text: &str, name: &str) -> Vec<String> {
    let start = text
        .find(&format!("pub struct {name} {{"))
        .unwrap_or_else(|| panic!("no struct {name}"));
    let body = &text[start..start + text[start..].find("\n}").unwrap()];
    body.lines()
        .skip(1)
        .filter_map(|l| l.trim().strip_prefix("pub "))
        .filter_map(|l| l.split(':').next())
        .map(str::to_string)
        .collect()
}

/// A robot-level feature: the robot, its laser and its odometry are configured by fields of
/// `sim`'s configs, and each such field is a user setting (`declare_settings!` applies it to
/// `cfg.sim.<part>.<field>`), so that a grid file, the command line and every run's record
/// carry it.
#[test]
fn every_robot_laser_and_odometry_parameter_is_a_setting() {
    let settings = read("settings/src/lib.rs");
    let mut missing = Vec::new();
    let mut count = 0;
    for (file, name, part) in [
        ("sim-core/src/sim/robot.rs", "RobotConfig", "robot"),
        ("sim-core/src/sim/laser.rs", "LaserConfig", "laser"),
        ("sim-core/src/sim/odometry.rs", "OdometryConfig", "odometry"),
    ] {
        for field in struct_fields(&read(file), name) {
            count += 1;
            let applied = format!("cfg.sim.{part}.{field} =");
            if !settings.contains(&applied) {
                missing.push(applied);
            }
        }
    }
    assert!(count >= 10, "{count} fields read");
    assert!(missing.is_empty(), "fields no setting applies: {missing:?}");
}

/// A statistic: a pure function of `floorcast-stats`' `stats.rs`, each tested there (named in
/// its test module) against published values or a reference implementation.
#[test]
fn every_statistic_is_tested_where_it_is_defined() {
    let text = read("stats/src/stats.rs");
    let split = text
        .find("\n#[cfg(test)]")
        .expect("stats.rs has a test module");
    let (code, tests) = text.split_at(split);
    let names: Vec<&str> = code
        .lines()
        .filter_map(|l| l.strip_prefix("pub fn "))
        .map(|l| l.split(['(', '<']).next().unwrap())
        .collect();
    assert!(names.len() >= 10, "statistics found: {names:?}");
    let untested: Vec<&&str> = names
        .iter()
        .filter(|n| !tests.contains(&format!("{n}(")) && !tests.contains(&format!("{n}::<")))
        .collect();
    assert!(
        untested.is_empty(),
        "statistics no test calls: {untested:?}"
    );
}
