//! Every map in the shared map folder loads, and its free area matches counting the image's free
//! pixels directly.

use std::path::{Path, PathBuf};

use floorcast_formats::map_server::{building_from_map, read_map};
use sim_core::Occupancy;

fn maps_dir() -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../maps")).to_path_buf()
}

fn all_yamls() -> Vec<PathBuf> {
    let mut out = Vec::new();
    for sub in ["schools", "partial", "radish", "stage"] {
        let dir = maps_dir().join(sub);
        let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
            .collect();
        v.sort();
        out.extend(v);
    }
    out
}

/// Free pixels counted straight from the image, with the YAML's thresholds (all these maps are
/// grey, `negate: 0`).
fn count_free_pixels(yaml: &Path) -> (usize, f64) {
    let doc: serde_yaml_ng::Value =
        serde_yaml_ng::from_str(&std::fs::read_to_string(yaml).unwrap()).unwrap();
    let image = doc["image"].as_str().unwrap();
    let res = doc["resolution"].as_f64().unwrap();
    let free_thresh = doc["free_thresh"].as_f64().unwrap();
    assert_eq!(doc["negate"].as_i64(), Some(0));
    let img = image::open(yaml.parent().unwrap().join(image))
        .unwrap()
        .to_luma8();
    let n = img
        .pixels()
        .filter(|p| (255.0 - p.0[0] as f64) / 255.0 < free_thresh)
        .count();
    (n, res)
}

#[test]
fn every_shared_map_loads_with_the_right_free_area() {
    let yamls = all_yamls();
    assert!(yamls.len() >= 19, "found only {} maps", yamls.len());
    for y in &yamls {
        let g = read_map(y).unwrap_or_else(|e| panic!("{e}"));
        let res = g.frame.resolution_m;
        let free_m2 = g.count(Occupancy::Free) as f64 * res * res;
        let (n, res_yaml) = count_free_pixels(y);
        assert_eq!(res, res_yaml);
        let direct_m2 = n as f64 * res_yaml * res_yaml;
        assert_eq!(free_m2, direct_m2, "{}", y.display());
        assert!(free_m2 > 100.0, "{}: only {free_m2} m2 free", y.display());
        let b = building_from_map(&g, "m");
        assert!((b.free_area_m2() - free_m2).abs() < 1e-9 * free_m2);
        eprintln!(
            "{:<60} {:>5} x {:<5} {:>5.2} m/px free {:>8.1} m2 occupied {:>7} unknown {:>7}",
            y.strip_prefix(maps_dir()).unwrap().display(),
            g.width(),
            g.height(),
            res,
            free_m2,
            g.count(Occupancy::Occupied),
            g.count(Occupancy::Unknown)
        );
    }
}

#[test]
fn intel_map_greys_follow_the_yaml_thresholds() {
    // Raw SLAM greys: 255 free, ~230 never seen, 127/170/191 walls. With the shipped thresholds
    // (0.65 / 0.196) 230 is free (occ 0.098) and 127 only unknown (occ 0.50): nothing is occupied.
    let intel = maps_dir().join("radish/intel_map.yaml");
    let g = read_map(&intel).unwrap();
    assert_eq!(g.width() * g.height(), 586 * 587);
    assert_eq!(g.count(Occupancy::Occupied), 0);
    // Thresholds that suit this map: 230 unknown, 127 occupied.
    let dir = tempfile::tempdir().unwrap();
    let y = dir.path().join("intel.yaml");
    let img = maps_dir()
        .join("radish/intel_map.pgm")
        .canonicalize()
        .unwrap();
    std::fs::write(
        &y,
        format!(
            "image: {}\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.4\nfree_thresh: 0.05\n",
            img.display()
        ),
    )
    .unwrap();
    let t = read_map(&y).unwrap();
    assert!(t.count(Occupancy::Occupied) > 10_000);
    assert!(t.count(Occupancy::Free) < g.count(Occupancy::Free) * 2 / 3);
    assert!(t.count(Occupancy::Unknown) > 100_000);
    eprintln!(
        "intel with 0.4/0.05: free {:.1} m2, occupied {}, unknown {}",
        t.count(Occupancy::Free) as f64 * 0.0025,
        t.count(Occupancy::Occupied),
        t.count(Occupancy::Unknown)
    );
}
