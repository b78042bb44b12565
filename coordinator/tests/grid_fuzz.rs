//! Fuzzing the grid file parser: mutations of a valid grid never panic, never hang, and every
//! error is one line naming the grid file. `PROPTEST_CASES` sets how many cases run.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use floorcast_coordinator::grid::Plan;
use proptest::prelude::*;

const GRID: &str = r#"format = "floorcast-grid"
version = 1
name = "t"
results = "results/t"
buildings = ["../buildings/small.toml"]
seed_range = [1, 3]
[[strategies]]
name = "baseline"
[[strategies]]
name = "layout-es"
label = "near"
settings = { alpha = 0.8, laser_beams = 90 }
[settings]
time_limit_s = 600
localization = "odometry"
"#;

fn grid_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../grids/fuzz.toml")
}

/// The tokens that matter to a grid file.
const TOKENS: [&[u8]; 12] = [
    b"1e300",
    b"-1",
    b"nan",
    b"[",
    b"\"",
    b"\n",
    b"9223372036854775807",
    b"\"\"",
    b"{",
    b"layout-truth",
    b"*",
    b"0",
];

fn mutate(text: &str, edits: &[(usize, u8, u8)]) -> String {
    floorcast_formats::mutation::mutate(text, edits, &TOKENS)
}

proptest! {
    #[test]
    fn grid_files_never_panic(edits in proptest::collection::vec((any::<usize>(), any::<u8>(), any::<u8>()), 0..10)) {
        let text = mutate(GRID, &edits);
        let path = grid_path();
        let t = Instant::now();
        let r = Plan::parse(&text, &path, None);
        prop_assert!(t.elapsed() < Duration::from_secs(5), "took {:?}", t.elapsed());
        if let Err(e) = r {
            let s = e.to_string();
            prop_assert!(!s.contains('\n'), "multi-line: {}", s);
            prop_assert!(s.contains("fuzz.toml"), "does not name the grid: {}", s);
        }
    }
}

#[test]
fn the_seed_of_the_fuzzer_is_valid() {
    let p = Plan::parse(GRID, &grid_path(), None).unwrap();
    assert_eq!(p.jobs.len(), 6);
}
