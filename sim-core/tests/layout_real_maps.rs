//! The layout runs on every real map of the repository's `maps/` without panicking and finds
//! lines and rooms on the complete school maps.

// Benchmarks, examples and integration tests run at the edge: they read files and clocks,
// which the kernel itself may not (sim-core/clippy.toml).
#![allow(clippy::disallowed_types, clippy::disallowed_methods)]
mod common;

use sim_core::layout::evidence::{
    fill_thin_unknown, fill_thin_unknown_in, fill_thin_unknown_reference, known_box,
};
use sim_core::layout::{reconstruct_layout, LayoutConfig};

#[test]
fn every_real_map_gives_a_layout() {
    let maps = common::all_maps();
    assert!(
        maps.len() >= 15,
        "the real maps of maps/ not found: {maps:?}"
    );
    for yaml in maps {
        let grid = common::load_map(&yaml);
        let layout = reconstruct_layout(&grid, &LayoutConfig::default());
        let name = yaml.to_string_lossy();
        if name.contains("schools") {
            assert!(layout.lines.len() >= 10, "{name}: {:?}", layout.diagnostics);
            assert!(
                (5..=200).contains(&layout.rooms.len()),
                "{name}: {} rooms",
                layout.rooms.len()
            );
        }
        for r in &layout.rooms {
            assert!(r.area_m2 > 0.0 && r.area_m2.is_finite(), "{name}: {r:?}");
        }
    }
}

/// The windowed thin-unknown fill gives the same grid as the whole-grid reference on every real
/// map, and reports the known box of its result.
#[test]
fn windowed_thin_fill_matches_the_reference_on_real_maps() {
    let maps = common::all_maps();
    assert!(
        maps.len() >= 15,
        "the real maps of maps/ not found: {maps:?}"
    );
    for yaml in maps {
        let grid = common::load_map(&yaml);
        let t = LayoutConfig::default().thin_unknown_wall_m;
        let (a, na) = fill_thin_unknown(&grid, t);
        let (b, nb) = fill_thin_unknown_reference(&grid, t);
        assert_eq!(na, nb, "{yaml:?}");
        assert!(a == b, "{yaml:?}");
        let (_, _, bbox) = fill_thin_unknown_in(&grid, t, known_box(&grid).0);
        assert_eq!(bbox, known_box(&a).0, "{yaml:?}");
    }
}
