//! The true-layout oracle's early stop (`layout-truth-es`) leaves no room unexplored that
//! `baseline` explores, on real plans (issue 77): the oracle is the reference every layout
//! strategy is measured against.

mod common;

use common::*;

/// (plan, seed): Lamuniere1's seed 1 is the run that stopped at 85.9 % with a classroom unseen
/// when the true layout closed every doorway (issue 56); Milano-1's rooms meet in places with
/// no wall and no door listed, which the true layout closes (a candidate cause of the held-out
/// plan's room left unexplored, issue 77: not reproduced on the vendored plans); PineCondos'
/// seed 2 stopped at 97.5 % with a room unexplored behind a wall the laser had only grazed, the
/// frontier's candidate on that wall beside the room's door (issue 77, a held-out plan).
const CASES: &[(&str, u64)] = &[
    ("maps/plans/Lamuniere1_updated.xml", 1),
    ("maps/plans/Milano-1.xml", 1),
    ("maps/regressions/PineCondos.xml", 2),
];

#[test]
fn the_oracles_early_stop_leaves_no_room_that_baseline_explores() {
    let dir = tempfile::tempdir().unwrap();
    for (k, (plan, seed)) in CASES.iter().enumerate() {
        let b = repo().join(plan);
        let run = |strategy: &str| {
            let out = dir.path().join(format!("{k}-{strategy}"));
            explore_with(&b, *seed, &out, &["--strategy", strategy])
        };
        let (base, oracle) = (run("baseline"), run("layout-truth-es"));
        let left = |s: &serde_json::Value| s["rooms_unexplored"].as_u64().unwrap();
        assert!(
            left(&oracle) <= left(&base),
            "{plan} seed {seed}: the oracle left {} rooms unexplored, baseline {}",
            left(&oracle),
            left(&base)
        );
        assert_eq!(left(&oracle), 0, "{plan} seed {seed}");
        assert_eq!(oracle["end_reason"], "early stop", "{plan} seed {seed}");
        let explored = oracle["explored_fraction"].as_f64().unwrap();
        assert!(explored >= 0.99, "{plan} seed {seed}: {explored}");
    }
}
