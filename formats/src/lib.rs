//! File formats at floorcast's edge: ROS map_server maps (YAML + PGM/PNG), Stage `.world`
//! files and floorcast's own building TOML, read into `sim_core` types and validated on the way
//! in.
//!
//! Bad input never panics: every error is an [`Error`] whose message is one line naming the file,
//! the problem and what was expected. Nothing here simulates or decides anything; the kernel
//! (`sim_core`) never sees a path.

pub mod building_toml;
pub mod error;
pub mod floorplan;
pub mod limits;
pub mod map_server;
pub mod polygon;
pub mod stage;
pub mod suite;

#[cfg(test)]
mod fuzz;
#[cfg(any(test, feature = "test-support"))]
#[doc(hidden)]
pub mod mutation;

use std::path::Path;

use sim_core::{Building, GridFrame, Occupancy, OccupancyGrid};

pub use building_toml::{
    parse_building_toml, parse_building_toml_with, read_building_toml, read_building_toml_with,
    to_toml_string, write_building_toml,
};
pub use error::{Error, Warning};
pub use floorplan::{read_floorplan, read_floorplan_with};
pub use map_server::{building_from_map, read_map, write_map};
pub use polygon::LoadOptions;
pub use stage::read_world;

/// Resolution at which [`read_occupancy`] rasterises a building file.
pub const OCCUPANCY_RESOLUTION_M: f64 = 0.05;

const SUPPORTED: &str = ".yaml/.yml (ROS map_server map), .world (Stage world), .toml (floorcast building), .xml (annotated floor plan)";

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    MapServer,
    Stage,
    Toml,
    FloorPlan,
}

fn kind_of(path: &Path) -> Result<Kind, Error> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("yaml" | "yml") => Ok(Kind::MapServer),
        Some("world") => Ok(Kind::Stage),
        Some("toml") => Ok(Kind::Toml),
        Some("xml") => Ok(Kind::FloorPlan),
        Some(e) => Err(Error::unsupported(
            path,
            format!("file extension .{e}; expected one of {SUPPORTED}"),
        )),
        None => Err(Error::unsupported(
            path,
            format!("a file without an extension; expected one of {SUPPORTED}"),
        )),
    }
}

fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// A building read, with the warnings of what the reader repaired in its file.
#[derive(Debug, Clone)]
pub struct Loaded {
    pub building: Building,
    /// One line each (`path: field: message`), in the file's order.
    pub warnings: Vec<Warning>,
}

/// Reads a building from any supported file, chosen by extension. A map becomes a raster world
/// (every cell that is not free is solid). The name is the file's stem unless a TOML file names
/// the building. A polygon whose edges cross by a slip is repaired ([`polygon`]) and its warning
/// dropped: use [`read_building_with`] to show it.
pub fn read_building(path: &Path) -> Result<Building, Error> {
    read_building_with(path, LoadOptions::default()).map(|l| l.building)
}

/// Reads a building as [`read_building`] does, with the warnings of the polygons repaired
/// (refused instead under `options.strict`).
pub fn read_building_with(path: &Path, options: LoadOptions) -> Result<Loaded, Error> {
    let plain = |building| Loaded {
        building,
        warnings: Vec::new(),
    };
    match kind_of(path)? {
        Kind::MapServer => Ok(plain(building_from_map(&read_map(path)?, &stem(path)))),
        Kind::Stage => read_world(path).map(plain),
        Kind::Toml => read_building_toml_with(path, options),
        Kind::FloorPlan => read_floorplan_with(path, options),
    }
}

/// Reads an occupancy map for layout reconstruction: a map_server map as its ternary grid, any
/// other building file rasterised at [`OCCUPANCY_RESOLUTION_M`] over its bounds (free where the
/// building is free, else occupied).
pub fn read_occupancy(path: &Path) -> Result<OccupancyGrid, Error> {
    match kind_of(path)? {
        Kind::MapServer => read_map(path),
        Kind::Stage | Kind::Toml | Kind::FloorPlan => {
            let b = read_building(path)?;
            let bounds = b.bounds();
            limits::check_cells(
                path,
                "outline",
                limits::cells_for(bounds.width_m(), bounds.height_m(), OCCUPANCY_RESOLUTION_M),
                &format!("drawing the building at {OCCUPANCY_RESOLUTION_M} m"),
            )?;
            Ok(occupancy_of(&b, OCCUPANCY_RESOLUTION_M))
        }
    }
}

/// A building as a two-state occupancy grid at `resolution_m` over its bounds.
pub fn occupancy_of(building: &Building, resolution_m: f64) -> OccupancyGrid {
    let frame = GridFrame::covering(&building.bounds(), resolution_m, 0.0);
    let free = building.free_mask(frame);
    OccupancyGrid {
        frame,
        data: free
            .data
            .iter()
            .map(|&f| {
                if f {
                    Occupancy::Free
                } else {
                    Occupancy::Occupied
                }
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOML: &str = r#"
format = "floorcast-building"
version = 1
outline = [[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0], [0.0, 0.0]]
[[solids]]
polygon = [[1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [1.0, 0.0]]
"#;

    #[test]
    fn dispatches_on_extension_and_names_by_stem() {
        let dir = tempfile::tempdir().unwrap();
        let t = dir.path().join("tiny.toml");
        std::fs::write(&t, TOML).unwrap();
        let b = read_building(&t).unwrap();
        assert_eq!(b.name, "tiny");
        let g = read_occupancy(&t).unwrap();
        assert_eq!(g.frame.resolution_m, 0.05);
        assert_eq!((g.width(), g.height()), (80, 40));
        assert_eq!(g.count(Occupancy::Free), 80 * 40 - 20 * 20);
        assert_eq!(g.count(Occupancy::Unknown), 0);

        let y = dir.path().join("m.yaml");
        let grid = OccupancyGrid::from_ascii("#.?", 0.1);
        write_map(&grid, &y).unwrap();
        assert_eq!(read_occupancy(&y).unwrap(), grid);
        let b = read_building(&y).unwrap();
        assert_eq!(b.name, "m");
        assert!((b.free_area_m2() - 0.01).abs() < 1e-12);
    }

    #[test]
    fn error_unknown_extension() {
        for name in ["plan.dxf", "plan"] {
            let e = read_building(Path::new(name)).unwrap_err().to_string();
            assert!(e.starts_with(&format!("{name}: unsupported: ")), "{e}");
            assert!(e.contains(".yaml/.yml (ROS map_server map), .world (Stage world), .toml (floorcast building)"), "{e}");
        }
    }

    #[test]
    fn error_missing_file() {
        let e = read_building(Path::new("nowhere/b.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("nowhere/b.toml: cannot read: "), "{e}");
    }
}
