//! Reads ROS map_server maps (image + YAML) from the shared map folder.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use sim_core::{Cell, GridFrame, Occupancy, OccupancyGrid, Vec2};

/// The real maps vendored in the repository (`maps/`).
pub(crate) fn maps_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../maps")
}

/// Every map YAML under the folder, sorted.
pub(crate) fn all_maps() -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(dirs) = std::fs::read_dir(maps_dir()) else {
        return out;
    };
    for d in dirs.flatten() {
        if let Ok(files) = std::fs::read_dir(d.path()) {
            for f in files.flatten() {
                if f.path().extension().is_some_and(|e| e == "yaml") {
                    out.push(f.path());
                }
            }
        }
    }
    out.sort();
    out
}

fn yaml_value<'a>(text: &'a str, key: &str) -> Option<&'a str> {
    text.lines().find_map(|l| {
        let (k, v) = l.split_once(':')?;
        (k.trim() == key).then(|| v.trim())
    })
}

/// Loads a map as the ROS map_server does in trinary mode (occupied above `occupied_thresh`,
/// free below `free_thresh`, unknown between).
pub(crate) fn load_map(yaml: &Path) -> OccupancyGrid {
    let text = std::fs::read_to_string(yaml).unwrap();
    let image = yaml_value(&text, "image").unwrap();
    let res: f64 = yaml_value(&text, "resolution").unwrap().parse().unwrap();
    let negate = yaml_value(&text, "negate").is_some_and(|v| v == "1");
    let occ: f64 = yaml_value(&text, "occupied_thresh")
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.65);
    let free: f64 = yaml_value(&text, "free_thresh")
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.196);
    let img = image::open(yaml.parent().unwrap().join(image))
        .unwrap()
        .to_luma8();
    let (w, h) = img.dimensions();
    let frame = GridFrame::new(Vec2::zeros(), res, w, h);
    let mut g = OccupancyGrid::filled(frame, Occupancy::Unknown);
    for (x, y, p) in img.enumerate_pixels() {
        let v = p.0[0] as f64;
        let p = if negate {
            v / 255.0
        } else {
            (255.0 - v) / 255.0
        };
        let s = if p > occ {
            Occupancy::Occupied
        } else if p < free {
            Occupancy::Free
        } else {
            Occupancy::Unknown
        };
        g.set(Cell::new(x as i32, (h - 1 - y) as i32), s);
    }
    g
}
