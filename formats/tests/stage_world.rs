//! The real Stage world file of the shared maps.

use std::path::Path;

use floorcast_formats::stage::read_world;
use sim_core::Geometry;

#[test]
fn willow_erratic_world() {
    let p = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../maps/stage/willow-erratic.world"
    ));
    let b = read_world(p).unwrap_or_else(|e| panic!("{e}"));
    let Geometry::Raster { solid } = &b.geometry else {
        panic!("not a raster")
    };
    let f = solid.frame;
    assert!((f.resolution_m - 0.1).abs() < 1e-9, "{}", f.resolution_m);
    // size [54 58.7] turned a quarter (pose yaw 90 deg) about (-29.35, 27).
    let bb = b.bounds();
    assert_eq!((f.width, f.height), (587, 540));
    assert!(
        (bb.min.x + 58.7).abs() < 1e-6 && bb.max.x.abs() < 1e-6,
        "{bb:?}"
    );
    assert!(
        bb.min.y.abs() < 1e-6 && (bb.max.y - 54.0).abs() < 1e-6,
        "{bb:?}"
    );
    let start = b.start.expect("the world places an erratic robot");
    assert!((start.x_m + 11.277).abs() < 1e-12 && (start.y_m - 23.266).abs() < 1e-12);
    assert!((start.theta_rad - std::f64::consts::PI).abs() < 1e-12);
    assert!(b.is_free(start.position()), "robot pose lands in a wall");
    let reachable_m2 = b.reachable_free(f, start.position()).count_true() as f64 * f.cell_area_m2();
    assert!(reachable_m2 > 500.0, "{reachable_m2}");
    eprintln!(
        "willow: {} x {} cells at {} m, {:.1} x {:.1} m, free {:.1} m2 (reachable {reachable_m2:.1}), start {:?}",
        f.width,
        f.height,
        f.resolution_m,
        bb.width_m(),
        bb.height_m(),
        b.free_area_m2(),
        start
    );
}
