//! Renders a few generated buildings to PNG: `cargo run -p floorcast-render --example
//! generated_buildings -- OUT_DIR` (default `/tmp`).

use floorcast_render::building_figure;
use sim_core::generate::{generate, BuildingKind, GenerateConfig};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "/tmp".into());
    let cases = [
        ("school-2000", 1, 2000.0, BuildingKind::School, false, 0.0),
        (
            "school-2000-rotated",
            2,
            2000.0,
            BuildingKind::School,
            true,
            0.5,
        ),
        ("office-1500", 3, 1500.0, BuildingKind::Office, true, 0.0),
        ("school-3500", 4, 3500.0, BuildingKind::School, false, 0.0),
        ("office-5000", 5, 5000.0, BuildingKind::Office, false, 0.0),
        ("school-1000", 6, 1000.0, BuildingKind::School, false, 0.0),
        ("school-300", 7, 300.0, BuildingKind::School, false, 0.0),
    ];
    for (name, seed, area_m2, kind, clutter, rotation_rad) in cases {
        let config = GenerateConfig {
            seed,
            area_m2,
            kind,
            clutter,
            rotation_rad,
            name: name.into(),
        };
        let t = std::time::Instant::now();
        let b = generate(&config);
        let gen_ms = t.elapsed().as_secs_f64() * 1e3;
        let path = format!("{out}/{name}.png");
        building_figure(&b).save(&path)?;
        println!(
            "{path}: {} rooms, {} doors, free {:.0} m2 (target {area_m2}), generated in {gen_ms:.2} ms",
            b.rooms.len(),
            b.doors.len(),
            b.free_area_m2()
        );
    }
    Ok(())
}
