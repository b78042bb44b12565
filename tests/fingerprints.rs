//! Reference runs whose fingerprints (`RunResult::fingerprint`: every pose, decision, progress
//! sample and map cell) are committed in `tests/fingerprints.txt`, each under the version in
//! which its strategy's runs last changed (`floorcast_worker::runs_version`, from
//! `RUNS_CHANGED`). A version means one behaviour: a change of runs fails here until a new
//! version is added to `RUNS_CHANGED` (naming the strategies whose runs it changes, or every
//! run) with the crate version raised to it; then `FLOORCAST_UPDATE_FINGERPRINTS=1 cargo test
//! --release --test fingerprints` adds the new version's lines (it never rewrites a line of a
//! version already recorded: those are the history), the reference results are rerun, and
//! CHANGELOG.md says what changed. A change made only for speed leaves every fingerprint as it is.

use std::path::{Path, PathBuf};

use floorcast_worker::{run_job, Job, Settings, StrategyRef};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// (case name, building path relative to the repository, strategy, seed, settings changed from
/// the defaults).
const CASES: &[(&str, &str, &str, u64, Changed)] = &[
    (
        "small-baseline-1",
        "buildings/small.toml",
        "baseline",
        1,
        DEFAULT,
    ),
    (
        "small-layout-1",
        "buildings/small.toml",
        "layout",
        1,
        DEFAULT,
    ),
    (
        "small-layout-es-2",
        "buildings/small.toml",
        "layout-es",
        2,
        DEFAULT,
    ),
    (
        "small-layout-aes-1",
        "buildings/small.toml",
        "layout-aes",
        1,
        DEFAULT,
    ),
    (
        "small-layout-gaps-es-1",
        "buildings/small.toml",
        "layout-gaps-es",
        1,
        DEFAULT,
    ),
    (
        "paper-01-baseline-1",
        "buildings/paper/paper-01.toml",
        "baseline",
        1,
        DEFAULT,
    ),
    (
        "paper-01-layout-es-1",
        "buildings/paper/paper-01.toml",
        "layout-es",
        1,
        DEFAULT,
    ),
    (
        "franch1-baseline-1",
        "maps/schools/Franch1.yaml",
        "baseline",
        1,
        DEFAULT,
    ),
    // A real map with doorways the planning grid finds too narrow: decisions whose best
    // candidates have no path (the memo of what a failed search reached, `waypoints_to`).
    (
        "intel-map-baseline-1",
        "maps/radish/intel_map.yaml",
        "baseline",
        1,
        DEFAULT,
    ),
    // An annotated plan (its doorways, start and rooms drawn by formats::floorplan) and the
    // true-layout oracle with its early stop (its layout open at the doors).
    (
        "lamuniere1-plan-layout-truth-es-1",
        "maps/plans/Lamuniere1_updated.xml",
        "layout-truth-es",
        1,
        DEFAULT,
    ),
    // Every other built-in strategy, once (each registered strategy has a reference run).
    (
        "small-layout-switch-1",
        "buildings/small.toml",
        "layout-switch",
        1,
        DEFAULT,
    ),
    (
        "small-layout-gaps-1",
        "buildings/small.toml",
        "layout-gaps",
        1,
        DEFAULT,
    ),
    (
        "small-layout-truth-1",
        "buildings/small.toml",
        "layout-truth",
        1,
        DEFAULT,
    ),
    (
        "small-nearest-1",
        "buildings/small.toml",
        "nearest",
        1,
        DEFAULT,
    ),
    (
        "small-utility-exp-1",
        "buildings/small.toml",
        "utility-exp",
        1,
        DEFAULT,
    ),
    (
        "small-cost-utility-1",
        "buildings/small.toml",
        "cost-utility",
        1,
        DEFAULT,
    ),
    (
        "small-frontier-tsp-1",
        "buildings/small.toml",
        "frontier-tsp",
        1,
        DEFAULT,
    ),
    (
        "small-room-first-1",
        "buildings/small.toml",
        "room-first",
        1,
        DEFAULT,
    ),
    (
        "small-random-frontier-1",
        "buildings/small.toml",
        "random-frontier",
        1,
        DEFAULT,
    ),
    // The paper's layout trigger (`layout_update_fraction = 0`, the default before 0.7): the
    // runs of the layout strategies as they were made before the default changed, which the
    // grids that pin it reproduce (their fingerprints then were these).
    (
        "small-layout-es-2-paper-trigger",
        "buildings/small.toml",
        "layout-es",
        2,
        PAPER_TRIGGER,
    ),
    (
        "paper-01-layout-es-1-paper-trigger",
        "buildings/paper/paper-01.toml",
        "layout-es",
        1,
        PAPER_TRIGGER,
    ),
    // Teams (issue 81): each team strategy with two robots on one shared map, and the
    // assignments with three and four on a larger building.
    (
        "small-team-nearest-1-x2",
        "buildings/small.toml",
        "team-nearest",
        1,
        TEAM2,
    ),
    (
        "small-team-greedy-1-x2",
        "buildings/small.toml",
        "team-greedy",
        1,
        TEAM2,
    ),
    (
        "small-team-burgard-1-x2",
        "buildings/small.toml",
        "team-burgard",
        1,
        TEAM2,
    ),
    (
        "small-team-hungarian-1-x2",
        "buildings/small.toml",
        "team-hungarian",
        1,
        TEAM2,
    ),
    (
        "small-team-minpos-1-x2",
        "buildings/small.toml",
        "team-minpos",
        1,
        TEAM2,
    ),
    (
        "paper-01-team-hungarian-1-x3",
        "buildings/paper/paper-01.toml",
        "team-hungarian",
        1,
        TEAM3,
    ),
    (
        "paper-01-team-minpos-2-x4",
        "buildings/paper/paper-01.toml",
        "team-minpos",
        2,
        TEAM4,
    ),
];

/// The settings a case changes from the defaults: `layout_update_fraction`, if it sets one, and
/// `robots`.
type Changed = (Option<f64>, usize);
const DEFAULT: Changed = (None, 1);
const PAPER_TRIGGER: Changed = (Some(0.0), 1);
const TEAM2: Changed = (None, 2);
const TEAM3: Changed = (None, 3);
const TEAM4: Changed = (None, 4);

fn fingerprint(building: &Path, strategy: &str, seed: u64, changed: Changed) -> String {
    let b = floorcast_formats::read_building(building).unwrap();
    let job = Job {
        building: &b,
        building_name: b.name.clone(),
        strategy: StrategyRef::built_in(strategy).unwrap(),
        seed,
        settings: Settings {
            layout_update_fraction: changed
                .0
                .unwrap_or(Settings::default().layout_update_fraction),
            robots: changed.1,
            ..Settings::default()
        },
        start: None,
        snapshot_fractions: Vec::new(),
    };
    run_job(&job, &mut |_| {}).unwrap().result.fingerprint()
}

/// A version's numbers, for ordering ("0.10.0" after "0.9.1").
fn version_key(v: &str) -> Vec<u64> {
    v.split('.')
        .map(|p| {
            p.parse()
                .unwrap_or_else(|_| panic!("version '{v}': '{p}' is not a number"))
        })
        .collect()
}

/// The lines of tests/fingerprints.txt: (case, runs version, fingerprint).
fn stored(text: &str) -> Vec<(String, String, String)> {
    text.lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            assert_eq!(
                w.len(),
                3,
                "tests/fingerprints.txt: '{l}' is not 'case version fingerprint'"
            );
            (w[0].to_string(), w[1].to_string(), w[2].to_string())
        })
        .collect()
}

#[test]
fn runs_versions_are_ordered_and_released() {
    let table = floorcast_worker::RUNS_CHANGED;
    assert!(
        table[0].1.is_none(),
        "RUNS_CHANGED's first entry must cover every run"
    );
    for w in table.windows(2) {
        assert!(
            version_key(w[0].0) < version_key(w[1].0),
            "RUNS_CHANGED: {} is not after {}",
            w[1].0,
            w[0].0
        );
    }
    let crate_version = version_key(env!("CARGO_PKG_VERSION"));
    let names = sim_core::explore::Strategy::names();
    for (v, strategies) in table {
        assert!(
            version_key(v) <= crate_version,
            "RUNS_CHANGED names {v}, after the crate's version {}: raise the crate's version",
            env!("CARGO_PKG_VERSION")
        );
        for s in strategies.unwrap_or(&[]) {
            assert!(
                names.contains(s),
                "RUNS_CHANGED {v} names '{s}', not a built-in strategy"
            );
        }
        // The CHANGELOG has the version's section, saying what changed.
        let changelog = std::fs::read_to_string(repo().join("CHANGELOG.md")).unwrap();
        assert!(
            changelog.contains(&format!("## {v} ")),
            "CHANGELOG.md has no section for {v}, a version that changed runs"
        );
    }
    // An external program's runs change with every entry that changes every run.
    let newest_all = table
        .iter()
        .rev()
        .find(|(_, s)| s.is_none())
        .map(|(v, _)| *v);
    assert_eq!(
        Some(floorcast_worker::runs_version("an external program")),
        newest_all
    );
}

#[test]
fn every_built_in_strategy_has_a_reference_run() {
    for name in sim_core::explore::Strategy::names() {
        assert!(
            CASES.iter().any(|c| c.2 == name),
            "no reference run of '{name}' in tests/fingerprints.rs: add a case (a change of its \
             runs would go unnoticed)"
        );
    }
}

#[test]
fn reference_runs_keep_their_fingerprints() {
    let file = repo().join("tests/fingerprints.txt");
    let mut lines = stored(&std::fs::read_to_string(&file).unwrap());
    let now: Vec<(String, String, String)> = CASES
        .iter()
        .map(|&(name, path, strategy, seed, changed)| {
            (
                name.to_string(),
                floorcast_worker::runs_version(strategy).to_string(),
                fingerprint(&repo().join(path), strategy, seed, changed),
            )
        })
        .collect();
    let recorded = |lines: &[(String, String, String)], (n, v, _): &(String, String, String)| {
        lines
            .iter()
            .find(|(ln, lv, _)| ln == n && lv == v)
            .map(|(_, _, f)| f.clone())
    };
    // A run that differs from its version's line: the version was not raised.
    let changed: Vec<String> = now
        .iter()
        .filter_map(|c| {
            let f = recorded(&lines, c)?;
            (f != c.2).then(|| format!("{} (runs version {}: {f}, now {})", c.0, c.1, c.2))
        })
        .collect();
    assert!(
        changed.is_empty(),
        "runs changed without a new version: {}. A version means one behaviour: add a version \
         to RUNS_CHANGED (worker/src/lib.rs) naming the strategies whose runs change, raise the \
         crate's version to it, then FLOORCAST_UPDATE_FINGERPRINTS=1 adds its lines; rerun the \
         reference results and say what changed in CHANGELOG.md",
        changed.join(", ")
    );
    let missing: Vec<&(String, String, String)> = now
        .iter()
        .filter(|c| recorded(&lines, c).is_none())
        .collect();
    if std::env::var_os("FLOORCAST_UPDATE_FINGERPRINTS").is_some() && !missing.is_empty() {
        lines.extend(missing.iter().map(|c| (*c).clone()));
        let text: String = lines
            .iter()
            .map(|(n, v, f)| format!("{n} {v} {f}\n"))
            .collect();
        std::fs::write(&file, text).unwrap();
        return;
    }
    assert!(
        missing.is_empty(),
        "reference runs with no fingerprint for their runs version: {}; record them with \
         FLOORCAST_UPDATE_FINGERPRINTS=1",
        missing
            .iter()
            .map(|(n, v, _)| format!("{n} ({v})"))
            .collect::<Vec<_>>()
            .join(", ")
    );
}
