//! End-to-end tests of the layout pipeline: ASCII maps, synthetic buildings with ground truth,
//! partial maps, properties.

use proptest::prelude::*;

use super::synthetic::{
    complete_map, corridor_building, corridor_pieces, corridor_views, explored_map, observe,
    rasterise, BuildingSpec,
};
use super::*;
use crate::building::{fill_polygon, Building};
use crate::generate::{generate, BuildingKind, GenerateConfig};
use crate::geom::Vec2;
use crate::grid::{Bitmap, GridFrame, Occupancy, OccupancyGrid};

/// `from_ascii` with every character a `k` x `k` block of cells of `char_m / k` metres.
fn ascii_scaled(text: &str, char_m: f64, k: usize) -> OccupancyGrid {
    let rows: Vec<String> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .map(|l| l.chars().flat_map(|c| std::iter::repeat_n(c, k)).collect())
        .collect();
    let big: Vec<String> = rows
        .iter()
        .flat_map(|r| std::iter::repeat_n(r.clone(), k))
        .collect();
    OccupancyGrid::from_ascii(&big.join("\n"), char_m / k as f64)
}

fn ascii_config() -> LayoutConfig {
    LayoutConfig {
        min_room_area_m2: 0.5,
        ..LayoutConfig::default()
    }
}

#[test]
fn two_rooms_and_a_door() {
    // 0.25 m walls and a 0.5 m door, drawn at 0.05 m cells.
    let g = ascii_scaled(
        "
        ##########################
        #...........#............#
        #...........#............#
        #...........#............#
        #........................#
        #........................#
        #...........#............#
        #...........#............#
        #...........#............#
        ##########################
        ",
        0.25,
        5,
    );
    let l = reconstruct_layout(&g, &ascii_config());
    assert_eq!(l.rooms.len(), 2, "{l:#?}");
    let mut areas: Vec<f64> = l.rooms.iter().map(|r| r.area_m2).collect();
    areas.sort_by(f64::total_cmp);
    // Interiors 2.75 x 2 and 3 x 2 m, plus half walls.
    assert!((areas[0] - 6.2).abs() < 0.8, "{areas:?}");
    assert!((areas[1] - 6.7).abs() < 0.8, "{areas:?}");
    assert!(l
        .rooms
        .iter()
        .all(|r| r.label == RoomLabel::Full && !r.predicted));
    // The point in the middle of each room finds its room.
    let a = room_at(&l, Vec2::new(1.5, 1.2)).map(|r| r.id);
    let b = room_at(&l, Vec2::new(4.8, 1.2)).map(|r| r.id);
    assert!(a.is_some() && b.is_some() && a != b);
    assert!(layout_walls(&l).len() >= 8);
}

#[test]
fn l_corridor_is_one_room() {
    let g = OccupancyGrid::from_ascii(
        "
        ########
        #......#
        #......#
        #......#
        #......#
        #......#
        #......#
        #......#
        #......##################
        #.......................#
        #.......................#
        #.......................#
        #.......................#
        #########################
        ",
        0.25,
    );
    let l = reconstruct_layout(&g, &ascii_config());
    assert_eq!(l.rooms.len(), 1, "{l:#?}");
    let free_m2 = g.count(Occupancy::Free) as f64 * 0.0625;
    let r = &l.rooms[0];
    assert!(
        r.area_m2 > free_m2 && r.area_m2 < free_m2 * 1.35,
        "{} vs {free_m2}",
        r.area_m2
    );
    // Concave: the corner opposite the bend is not in the room.
    assert!(room_at(&l, Vec2::new(4.0, 3.0)).is_none());
}

/// A room cut by the frontier: no wall line runs along the frontier, so the face holding the
/// room's seen part already extends to the top wall line shared with the other rooms; the room
/// is not Full and its polygon holds the unknown part.
#[test]
fn room_cut_by_the_frontier_reaches_the_shared_wall() {
    let g = OccupancyGrid::from_ascii(
        "
        ##############################????????
        #........#........#.........#?????????
        #........#........#.........#?????????
        #........#........#.........#?????????
        #........#........#.........#?????????
        #........#........#.........#?????????
        #........#........#.........#.........
        #........#........#.........#.........
        #........#........#.........#.........
        ###.########.########.########.......#
        #....................................#
        #....................................#
        #....................................#
        ######################################
        ",
        0.25,
    );
    let l = reconstruct_layout(&g, &ascii_config());
    let r = room_at(&l, Vec2::new(8.5, 1.2 + 0.25 * 6.0)).expect("the cut room");
    assert_ne!(r.label, RoomLabel::Full, "{l:#?}");
    // Predicted up to the top wall line seen on the other rooms (y about 3.4 m).
    let top = r
        .polygon
        .vertices
        .iter()
        .map(|v| v.y)
        .fold(f64::MIN, f64::max);
    // Within about a cell (0.25 m) of the wall line.
    assert!((top - 3.4).abs() < 0.3, "top {top}: {r:#?}");
    assert!(r.unknown_area_m2 > 1.0, "{r:#?}");
    assert!(r.area_m2 >= r.observed_area_m2);
}

#[test]
fn degenerate_inputs_give_empty_layouts() {
    let cfg = LayoutConfig::default();
    let empty = OccupancyGrid::filled(GridFrame::new(Vec2::zeros(), 0.05, 0, 0), Occupancy::Free);
    assert!(reconstruct_layout(&empty, &cfg).rooms.is_empty());
    let frame = GridFrame::new(Vec2::zeros(), 0.05, 50, 40);
    let unknown = OccupancyGrid::filled(frame, Occupancy::Unknown);
    assert!(reconstruct_layout(&unknown, &cfg).rooms.is_empty());
    // All free: no walls, no lines; the whole box is one room at most.
    let free = OccupancyGrid::filled(frame, Occupancy::Free);
    let l = reconstruct_layout(&free, &cfg);
    assert!(l.lines.is_empty());
    assert!(l.rooms.len() <= 1);
    let occ = OccupancyGrid::filled(frame, Occupancy::Occupied);
    assert!(reconstruct_layout(&occ, &cfg).rooms.is_empty());
    let zero_res = OccupancyGrid::filled(GridFrame::new(Vec2::zeros(), 0.0, 3, 3), Occupancy::Free);
    assert!(reconstruct_layout(&zero_res, &cfg).rooms.is_empty());
    let one = OccupancyGrid::from_ascii(".", 0.05);
    assert!(reconstruct_layout(&one, &cfg).rooms.is_empty());
}

#[test]
fn single_room_gives_one_full_room() {
    let b = corridor_building(&BuildingSpec {
        room_widths_m: vec![],
        ..BuildingSpec::default()
    });
    let g = rasterise(&b, 0.05);
    let l = reconstruct_layout(&g, &LayoutConfig::default());
    assert_eq!(l.rooms.len(), 1, "{:?}", l.diagnostics);
    assert_eq!(l.rooms[0].label, RoomLabel::Full);
}

fn long_spec() -> BuildingSpec {
    BuildingSpec {
        room_widths_m: vec![4.0, 4.0, 6.0, 4.0, 4.0, 6.0, 4.0, 4.0],
        ..BuildingSpec::default()
    }
}

#[test]
fn complete_synthetic_building_is_accurate() {
    for rotation_rad in [0.0, 0.5, std::f64::consts::FRAC_PI_4] {
        let spec = BuildingSpec {
            rotation_rad,
            ..long_spec()
        };
        let b = corridor_building(&spec);
        let g = rasterise(&b, 0.05);
        let l = reconstruct_layout(&g, &LayoutConfig::default());
        let a = evaluate(&l, &b.rooms, g.frame);
        assert!(
            a.matched_room_iou >= 0.9,
            "rotation {rotation_rad}: {a:?} {:?}",
            l.diagnostics
        );
        assert!(a.pixel_accuracy >= 0.9, "{a:?}");
        assert_eq!(
            a.rooms_found,
            b.rooms.len(),
            "rotation {rotation_rad}: {a:?}"
        );
        assert!(l.rooms.iter().all(|r| r.label == RoomLabel::Full));
    }
}

fn generated(seed: u64, kind: BuildingKind, area_m2: f64, rotation_rad: f64) -> Building {
    generate(&GenerateConfig {
        seed,
        area_m2,
        kind,
        rotation_rad,
        ..GenerateConfig::default()
    })
}

/// Generated schools and offices of 1000-3500 m2, some rotated, complete maps at 0.05 m: the
/// mean matched room IoU is at least 0.9, the straight pieces of a corridor counting as one room
/// (the generator cuts corridors where they meet, without a wall), and at least 0.8 with every
/// piece on its own.
#[test]
fn complete_generated_buildings_are_accurate() {
    let cases = [
        (0, BuildingKind::School, 1000.0, 0.0),
        (1, BuildingKind::Office, 1000.0, 0.0),
        (2, BuildingKind::School, 2000.0, 0.35),
        (3, BuildingKind::Office, 2000.0, 0.0),
        (4, BuildingKind::School, 3500.0, std::f64::consts::FRAC_PI_4),
        (5, BuildingKind::Office, 1500.0, 0.5),
    ];
    let (mut merged, mut raw) = (Vec::new(), Vec::new());
    for (seed, kind, area_m2, rotation_rad) in cases {
        let b = generated(seed, kind, area_m2, rotation_rad);
        let g = complete_map(&b, 0.05);
        let l = reconstruct_layout(&g, &LayoutConfig::default());
        let a = evaluate_merged(&l, &b.rooms, &corridor_pieces(&b), g.frame);
        let r = evaluate(&l, &b.rooms, g.frame);
        assert!(a.matched_room_iou > 0.7, "{seed} {kind:?}: {a:?}");
        merged.push(a.matched_room_iou);
        raw.push(r.matched_room_iou);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(mean(&merged) >= 0.9, "corridors merged: {merged:?}");
    assert!(mean(&raw) >= 0.8, "corridor pieces apart: {raw:?}");
}

/// Partial maps explored 30-90 % by a walking laser: prediction raises the mean IoU of the
/// partially observed rooms over the observed-only layout; Open rooms, and only they among the
/// partial ones, reach the border of the known map's box.
#[test]
fn prediction_improves_partial_rooms() {
    let (mut pred, mut obs) = (Vec::new(), Vec::new());
    let mut open_rooms = 0;
    for (seed, kind, rotation_rad) in [
        (0, BuildingKind::School, 0.0),
        (1, BuildingKind::Office, 0.3),
        (2, BuildingKind::Office, 0.0),
    ] {
        let b = generated(seed, kind, 1200.0, rotation_rad);
        let full = complete_map(&b, 0.05);
        for fraction in [0.3, 0.6, 0.9] {
            let g = explored_map(&b, &full, fraction, 0.4, seed);
            let l = reconstruct_layout(&g, &LayoutConfig::default());
            let a = evaluate(&l, &b.rooms, g.frame);
            if let (Some(p), Some(o)) = (a.predicted_iou, a.observed_only_iou) {
                pred.push(p);
                obs.push(o);
            }
            // The box of the known cells, grown by the line separation as in the arrangement.
            let res = g.frame.resolution_m;
            let (mut lo, mut hi) = (Vec2::new(f64::MAX, f64::MAX), Vec2::new(f64::MIN, f64::MIN));
            for (c, st) in g.iter() {
                if *st != Occupancy::Unknown {
                    let p = g.frame.world_from_cell(c);
                    lo = Vec2::new(lo.x.min(p.x), lo.y.min(p.y));
                    hi = Vec2::new(hi.x.max(p.x), hi.y.max(p.y));
                }
            }
            let m = LayoutConfig::default().min_line_separation_m + res / 2.0;
            let (lo, hi) = (lo - Vec2::new(m, m), hi + Vec2::new(m, m));
            let on = |a: f64, b: f64| (a - b).abs() < 1e-6;
            for r in &l.rooms {
                let edge_on_box: Vec<bool> = r
                    .polygon
                    .edges()
                    .map(|e| {
                        (on(e.a.x, lo.x) && on(e.b.x, lo.x))
                            || (on(e.a.x, hi.x) && on(e.b.x, hi.x))
                            || (on(e.a.y, lo.y) && on(e.b.y, lo.y))
                            || (on(e.a.y, hi.y) && on(e.b.y, hi.y))
                    })
                    .collect();
                // The room reports exactly its edges on the box as open.
                assert_eq!(r.open_edges, edge_on_box, "{r:?}");
                let on_box = edge_on_box.iter().any(|b| *b);
                match r.label {
                    RoomLabel::Open => {
                        open_rooms += 1;
                        assert!(on_box, "open room off the box: {r:?}");
                    }
                    RoomLabel::Partial => assert!(!on_box, "partial room on the box: {r:?}"),
                    RoomLabel::Full => {}
                }
            }
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(pred.len() >= 6, "{pred:?}");
    assert!(open_rooms >= 1);
    assert!(
        mean(&pred) > mean(&obs) + 0.01,
        "predicted {:.3} vs observed {:.3}",
        mean(&pred),
        mean(&obs)
    );
}

fn rooms_raster(l: &Layout, frame: GridFrame) -> Vec<u8> {
    let mut cover = vec![0u8; frame.len()];
    for r in &l.rooms {
        let mut m = Bitmap::filled(frame, false);
        fill_polygon(&mut m, &r.polygon, true);
        for (c, b) in cover.iter_mut().zip(&m.data) {
            *c += *b as u8;
        }
    }
    cover
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]
    #[test]
    fn rooms_are_disjoint_and_full_rooms_are_free(
        widths in prop::collection::vec(3.0f64..6.0, 1..5),
        depth in 3.0f64..6.0,
        rotation_rad in 0.0f64..1.6,
        fraction in 0.2f64..1.2,
    ) {
        rooms_disjoint_and_full_free(widths, depth, rotation_rad, fraction)?;
    }
}

fn rooms_disjoint_and_full_free(
    widths: Vec<f64>,
    depth: f64,
    rotation_rad: f64,
    fraction: f64,
) -> Result<(), TestCaseError> {
    let spec = BuildingSpec {
        room_widths_m: widths,
        room_depth_m: depth,
        rotation_rad,
        ..BuildingSpec::default()
    };
    let b = corridor_building(&spec);
    let full = rasterise(&b, 0.1);
    let g = observe(&full, &corridor_views(&spec, fraction), 6.0);
    // Thin unknown bands taken as walls would make rooms Full over unseen strips: off here.
    let config = LayoutConfig {
        thin_unknown_wall_m: 0.0,
        ..LayoutConfig::default()
    };
    let l = reconstruct_layout(&g, &config);
    let cover = rooms_raster(&l, g.frame);
    prop_assert!(cover.iter().all(|c| *c <= 1));
    for r in l.rooms.iter().filter(|r| r.label == RoomLabel::Full) {
        let mut m = Bitmap::filled(g.frame, false);
        fill_polygon(&mut m, &r.polygon, true);
        let n = m.count_true();
        let free = m
            .data
            .iter()
            .zip(&g.data)
            .filter(|(b, s)| **b && **s == Occupancy::Free)
            .count();
        prop_assert!(free as f64 >= 0.75 * n as f64, "room {} {free}/{n}", r.id);
    }
    Ok(())
}

/// A case the property test found (CI, session 4): a rotated corridor seen over a quarter of its
/// length yields one wall direction only; the corridor's face runs far into the unseen, and its
/// frontier cells, split among clusters that each lie mostly elsewhere, did not make it partial.
#[test]
fn a_partly_seen_rotated_corridor_is_not_full() {
    rooms_disjoint_and_full_free(
        vec![3.4022736104765343],
        3.0,
        1.089921312325854,
        0.26307696624037996,
    )
    .unwrap();
}
