//! Reference runs whose fingerprints (`RunResult::fingerprint`: every pose, decision, progress
//! sample and map cell) are committed in `tests/fingerprints.txt`. A change of behaviour fails
//! here until the file is updated, so that no change alters runs unnoticed: a change made only
//! for speed must leave every fingerprint as it is; any other change that alters runs updates
//! the file (`FLOORCAST_UPDATE_FINGERPRINTS=1 cargo test --workspace --release --test
//! fingerprints`), reruns the reference results and says what changed (CHANGELOG.md).

use std::path::{Path, PathBuf};

use floorcast_worker::{run_job, Job, Settings};

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
];

/// The settings a case changes from the defaults: `layout_update_fraction`, if it sets one.
type Changed = Option<f64>;
const DEFAULT: Changed = None;
const PAPER_TRIGGER: Changed = Some(0.0);

fn fingerprint(building: &Path, strategy: &str, seed: u64, changed: Changed) -> String {
    let b = floorcast_formats::read_building(building).unwrap();
    let job = Job {
        building: &b,
        building_name: b.name.clone(),
        strategy: strategy.to_string(),
        program: None,
        seed,
        settings: Settings {
            layout_update_fraction: changed.unwrap_or(Settings::default().layout_update_fraction),
            ..Settings::default()
        },
        start: None,
        snapshot_fractions: Vec::new(),
    };
    run_job(&job, &mut |_| {}).unwrap().result.fingerprint()
}

#[test]
fn reference_runs_keep_their_fingerprints() {
    let file = repo().join("tests/fingerprints.txt");
    let now: Vec<(String, String)> = CASES
        .iter()
        .map(|&(name, path, strategy, seed, changed)| {
            (
                name.to_string(),
                fingerprint(&repo().join(path), strategy, seed, changed),
            )
        })
        .collect();
    if std::env::var_os("FLOORCAST_UPDATE_FINGERPRINTS").is_some() {
        let text: String = now.iter().map(|(n, f)| format!("{n} {f}\n")).collect();
        std::fs::write(&file, text).unwrap();
    }
    let stored = std::fs::read_to_string(&file).unwrap();
    let stored: Vec<(String, String)> = stored
        .lines()
        .map(|l| {
            let (n, f) = l.split_once(' ').unwrap();
            (n.to_string(), f.to_string())
        })
        .collect();
    let changed: Vec<String> = now
        .iter()
        .filter(|c| !stored.contains(c))
        .map(|(n, f)| format!("{n} (now {f})"))
        .collect();
    assert!(
        changed.is_empty() && stored.len() == now.len(),
        "runs changed: {}; if the change is meant to alter runs, update tests/fingerprints.txt \
         (FLOORCAST_UPDATE_FINGERPRINTS=1), rerun the reference results and say what changed",
        changed.join(", ")
    );
}
