//! The layout runs on every real map of the shared folder without panicking and finds lines and
//! rooms on the complete school maps.

mod common;

use sim_core::layout::{reconstruct_layout, LayoutConfig};

#[test]
fn every_real_map_gives_a_layout() {
    let maps = common::all_maps();
    assert!(maps.len() >= 15, "shared maps not found: {maps:?}");
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
