use super::*;
use crate::building::{fill_polygon, flood_fill};
use crate::distance::distance_to;
use crate::grid::{Bitmap, GridFrame};

fn config(seed: u64, area_m2: f64, kind: BuildingKind) -> GenerateConfig {
    GenerateConfig {
        seed,
        area_m2,
        kind,
        clutter: false,
        rotation_rad: 0.0,
        name: format!("test-{seed}"),
    }
}

const KINDS: [BuildingKind; 2] = [BuildingKind::School, BuildingKind::Office];

#[test]
fn same_config_same_building_and_seeds_differ() {
    for kind in KINDS {
        let mut c = config(7, 2000.0, kind);
        c.clutter = true;
        c.rotation_rad = 0.4;
        let a = generate(&c);
        let b = generate(&c);
        assert_eq!(a, b);
        assert_eq!(a.content_hash(), b.content_hash());
        c.seed = 8;
        let d = generate(&c);
        assert_ne!(a.content_hash(), d.content_hash());
    }
}

#[test]
fn free_area_is_within_15_percent_of_target() {
    for kind in KINDS {
        for area in [300.0, 1000.0, 2000.0, 3500.0, 5000.0] {
            for seed in 0..8 {
                let b = generate(&config(seed, area, kind));
                let got = b.free_area_m2();
                assert!(
                    (got / area - 1.0).abs() <= 0.15,
                    "{kind:?} seed {seed}: {got:.0} m2 for a target of {area} m2"
                );
            }
        }
    }
}

#[test]
fn all_skeleton_shapes_occur() {
    let mut seen = std::collections::BTreeSet::new();
    for seed in 0..40 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let p = plan::Params::sample(BuildingKind::School, &mut rng);
        let s = plan::choose_shape(&p, 2000.0, &mut rng);
        seen.insert(match s {
            plan::Shape::Straight { .. } => "straight",
            plan::Shape::L { .. } => "L",
            plan::Shape::T { .. } => "T",
            plan::Shape::Ring { .. } => "ring",
        });
    }
    assert_eq!(seen.len(), 4, "{seen:?}");
}

/// Free space of a building on a 0.1 m grid.
fn free_mask(b: &Building) -> Bitmap {
    b.free_mask(GridFrame::covering(&b.bounds(), 0.1, 0.5))
}

fn room_mask(frame: GridFrame, room: &Room) -> Bitmap {
    let mut m = Bitmap::filled(frame, false);
    fill_polygon(&mut m, &room.polygon, true);
    m
}

/// Every structural invariant of a generated building.
fn check_building(b: &Building) {
    let free = free_mask(b);
    let frame = free.frame;
    let label = &b.name;
    assert!(!b.rooms.is_empty(), "{label}: no rooms");
    // Rooms are disjoint and lie in free space.
    let mut owner = vec![0u32; frame.len()];
    for r in &b.rooms {
        let m = room_mask(frame, r);
        let cells = m.count_true();
        assert!(cells > 0, "{label}: room {} is empty", r.id);
        let mut in_free = 0;
        for (i, &inside) in m.data.iter().enumerate() {
            if inside {
                assert_eq!(
                    owner[i], 0,
                    "{label}: rooms {} and {} overlap",
                    owner[i], r.id
                );
                owner[i] = r.id;
                in_free += free.data[i] as usize;
            }
        }
        assert!(
            in_free as f64 >= 0.95 * cells as f64,
            "{label}: room {} only {in_free}/{cells} free",
            r.id
        );
    }
    // The start is free, with clearance.
    let start = b.start.expect("a start pose");
    let solid = Bitmap {
        frame,
        data: free.data.iter().map(|f| !f).collect(),
    };
    let dist_m = distance_to(&solid);
    let sc = frame.cell_from_world(start.position());
    assert!(b.is_free(start.position()), "{label}: start not free");
    let clearance_m = *dist_m.get(sc).unwrap() as f64 * frame.resolution_m;
    assert!(clearance_m >= 0.4, "{label}: start clearance {clearance_m}");
    // Doors are free at their midpoints; doors of rooms are 0.9-1.5 m wide (the entrance and
    // the open junctions between corridors may be wider).
    let kind_of = |id: Option<u32>| {
        id.and_then(|i| b.rooms.iter().find(|r| r.id == i))
            .map(|r| r.kind.as_str())
    };
    for d in &b.doors {
        let kinds = d.rooms.map(kind_of);
        let junction = kinds == [Some("corridor"), Some("corridor")];
        if !junction && d.rooms.iter().all(|r| r.is_some()) {
            let w = (d.b - d.a).norm();
            assert!(
                (0.9 - 1e-9..=1.5 + 1e-9).contains(&w),
                "{label}: door {d:?} is {w} m wide"
            );
        }
        assert!(
            kinds.iter().all(|k| k.is_some()) || d.rooms.contains(&None),
            "{label}: door to no room"
        );
        let mid = (d.a + d.b) / 2.0;
        assert!(b.is_free(mid), "{label}: door {d:?} is blocked");
    }
    // Every room is reachable by a robot of radius 0.2 m.
    let radius_cells = 0.2 / frame.resolution_m;
    let eroded = Bitmap {
        frame,
        data: dist_m
            .data
            .iter()
            .map(|&d| d as f64 > radius_cells)
            .collect(),
    };
    let reach = flood_fill(&eroded, sc);
    for r in &b.rooms {
        let m = room_mask(frame, r);
        let (mut open, mut reached) = (0usize, 0usize);
        for i in 0..frame.len() {
            if m.data[i] && eroded.data[i] {
                open += 1;
                reached += reach.data[i] as usize;
            }
        }
        assert!(
            open > 0 && reached as f64 >= 0.9 * open as f64,
            "{label}: room {} ({}) reached {reached}/{open}",
            r.id,
            r.kind
        );
    }
}

#[test]
fn generated_buildings_are_consistent() {
    for kind in KINDS {
        for (seed, area) in [
            (0, 1000.0),
            (1, 2000.0),
            (2, 3500.0),
            (3, 300.0),
            (4, 5000.0),
            (5, 2000.0),
        ] {
            check_building(&generate(&config(seed, area, kind)));
        }
    }
}

#[test]
fn cluttered_and_rotated_buildings_are_consistent() {
    for kind in KINDS {
        for seed in 0..4 {
            let mut c = config(seed, 1500.0, kind);
            c.clutter = true;
            c.rotation_rad = 0.3 + seed as f64;
            let b = generate(&c);
            let plain = generate(&GenerateConfig {
                clutter: false,
                ..c.clone()
            });
            let Geometry::Vector { solids, .. } = &b.geometry else {
                panic!("vector")
            };
            let Geometry::Vector {
                solids: plain_solids,
                ..
            } = &plain.geometry
            else {
                panic!("vector")
            };
            assert!(solids.len() > plain_solids.len(), "no clutter placed");
            check_building(&b);
        }
    }
}

#[test]
fn rotation_turns_the_start_and_keeps_the_area() {
    let mut c = config(3, 1200.0, BuildingKind::Office);
    let a = generate(&c);
    c.rotation_rad = std::f64::consts::FRAC_PI_2;
    let b = generate(&c);
    let (sa, sb) = (a.start.unwrap(), b.start.unwrap());
    let turn = crate::geom::wrap_angle(sb.theta_rad - sa.theta_rad);
    assert!((turn - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
    assert!((a.free_area_m2() / b.free_area_m2() - 1.0).abs() < 0.01);
    assert_eq!(a.rooms.len(), b.rooms.len());
}

#[test]
fn odd_areas_do_not_panic() {
    for area in [0.0, -5.0, f64::NAN, 1e9] {
        let b = generate(&config(1, area, BuildingKind::School));
        assert!(!b.rooms.is_empty());
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
    #[test]
    fn any_area_from_300_to_5000_is_met(seed in 0u64..10_000, area in 300.0f64..5000.0, school: bool) {
        let kind = if school { BuildingKind::School } else { BuildingKind::Office };
        let got = generate(&config(seed, area, kind)).free_area_m2();
        proptest::prop_assert!((got / area - 1.0).abs() <= 0.15, "{got} for {area}");
    }
}
