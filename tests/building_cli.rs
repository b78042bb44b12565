//! `floorcast building` end to end: real maps, generated buildings, bad input.

mod common;

use common::*;

fn check_json(path: &std::path::Path) -> serde_json::Value {
    let o = run(&["building", "check", path.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}: {}", path.display(), stderr(&o));
    serde_json::from_str(&stdout(&o)).unwrap()
}

/// Free pixels of a map_server map counted directly from its image and YAML thresholds.
fn count_free_pixels(yaml: &std::path::Path) -> (usize, f64) {
    let text = std::fs::read_to_string(yaml).unwrap();
    let field = |k: &str| -> Option<String> {
        text.lines().find_map(|l| {
            l.trim()
                .strip_prefix(&format!("{k}:"))
                .map(|v| v.trim().to_string())
        })
    };
    let image = field("image").unwrap();
    let res: f64 = field("resolution").unwrap().parse().unwrap();
    let negate = field("negate").map(|v| v == "1").unwrap_or(false);
    let free_thresh: f64 = field("free_thresh").unwrap().parse().unwrap();
    let img = image::open(yaml.parent().unwrap().join(image))
        .unwrap()
        .to_luma8();
    let free = img
        .pixels()
        .filter(|p| {
            let v = p.0[0] as f64;
            let occ = if negate {
                v / 255.0
            } else {
                (255.0 - v) / 255.0
            };
            occ < free_thresh
        })
        .count();
    (free, res * res)
}

#[test]
fn check_reports_free_area_of_real_maps_within_5_percent() {
    let mut maps: Vec<_> = std::fs::read_dir(maps_dir().join("schools"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "yaml"))
        .collect();
    maps.push(maps_dir().join("stage/willow-full.yaml"));
    maps.sort();
    assert!(maps.len() >= 12);
    for m in maps {
        let j = check_json(&m);
        let (free, cell) = count_free_pixels(&m);
        let expected = free as f64 * cell;
        let got = j["free_area_m2"].as_f64().unwrap();
        assert!(
            (got - expected).abs() <= 0.05 * expected,
            "{}: {got} m2 vs {expected} m2 counted",
            m.display()
        );
        assert_eq!(j["hash"].as_str().unwrap().len(), 32);
    }
}

#[test]
fn stage_world_loads_with_its_robot_pose() {
    let j = check_json(&maps_dir().join("stage/willow-erratic.world"));
    let w = j["width_m"].as_f64().unwrap();
    let h = j["height_m"].as_f64().unwrap();
    assert!(
        (50.0..60.0).contains(&w) && (54.0..64.0).contains(&h),
        "{w} x {h}"
    );
    assert_eq!(j["start_source"], "file");
}

/// `floorcast building generate --seed SEED --area-m2 AREA --out OUT`.
fn generate(seed: u64, area: f64, out: &std::path::Path) -> std::process::Output {
    run(&[
        "building",
        "generate",
        "--seed",
        &seed.to_string(),
        "--area-m2",
        &area.to_string(),
        "--out",
        out.to_str().unwrap(),
    ])
}

#[test]
fn generated_buildings_hit_their_area_and_are_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    for (area, seed) in [(1000.0, 1u64), (2000.0, 2), (3500.0, 3)] {
        let a = dir.path().join(format!("a{seed}.toml"));
        let b = dir.path().join(format!("b{seed}.toml"));
        for out in [&a, &b] {
            let o = generate(seed, area, out);
            assert!(o.status.success(), "{}", stderr(&o));
        }
        let ta = std::fs::read_to_string(&a).unwrap();
        // Same seed, same building; only the name (from the file stem) differs.
        assert_eq!(
            ta.replace(&format!("a{seed}"), "X"),
            std::fs::read_to_string(&b)
                .unwrap()
                .replace(&format!("b{seed}"), "X")
        );
        let j = check_json(&a);
        let got = j["free_area_m2"].as_f64().unwrap();
        assert!((got - area).abs() <= 0.15 * area, "area {area}: got {got}");
        assert!(j["rooms"].as_u64().unwrap() >= 5);
        assert_eq!(j["start_source"], "file");
    }
}

#[test]
fn a_generated_building_above_the_cell_budget_is_written_with_a_note() {
    // (area m², whether its 0.05 m grid exceeds the default budget of 25 million cells)
    let cases = [(2000.0, false), (50000.0, true)];
    let dir = tempfile::tempdir().unwrap();
    for (area, above) in cases {
        let out = dir.path().join(format!("g{area}.toml"));
        let o = generate(77, area, &out);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(out.is_file());
        let err = stderr(&o);
        assert_eq!(
            err.contains("note: ") && err.contains("--max-cells"),
            above,
            "{err}"
        );
        // The note says what a run will need: checked with the default budget, accepted with
        // a raised one.
        let check = run(&["building", "check", out.to_str().unwrap()]);
        assert_eq!(
            check.status.code(),
            Some(if above { 2 } else { 0 }),
            "{}",
            stderr(&check)
        );
        let raised = run(&[
            "--max-cells",
            "40000000",
            "building",
            "check",
            out.to_str().unwrap(),
        ]);
        assert!(raised.status.success(), "{}", stderr(&raised));
    }
}

#[test]
fn render_writes_png_and_svg() {
    let dir = tempfile::tempdir().unwrap();
    let b = repo().join("buildings/small.toml");
    for ext in ["png", "svg"] {
        let out = dir.path().join(format!("small.{ext}"));
        let o = run(&[
            "building",
            "render",
            b.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let bytes = std::fs::read(&out).unwrap();
        if ext == "png" {
            assert!(image::load_from_memory(&bytes).is_ok());
        } else {
            assert!(String::from_utf8_lossy(&bytes).contains("<svg"));
        }
    }
}

#[test]
fn bad_inputs_fail_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let write = |name: &str, text: &[u8]| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    // Truncated PGM.
    write("trunc.pgm", b"P5\n100 100\n255\n\x00\x00\x00");
    let y = write("trunc.yaml", b"image: trunc.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n");
    assert_clean_failure(
        &run(&["building", "check", y.to_str().unwrap()]),
        &["trunc"],
    );
    // Not an image.
    write("text.pgm", b"hello, I am not an image");
    let y = write("text.yaml", b"image: text.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n");
    assert_clean_failure(
        &run(&["building", "check", y.to_str().unwrap()]),
        &["text.pgm"],
    );
    // YAML without resolution.
    let y = write("nores.yaml", b"image: trunc.pgm\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n");
    assert_clean_failure(
        &run(&["building", "check", y.to_str().unwrap()]),
        &["nores.yaml", "resolution"],
    );
    // YAML pointing at a missing image.
    let y = write("missing.yaml", b"image: nowhere.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n");
    assert_clean_failure(
        &run(&["building", "check", y.to_str().unwrap()]),
        &["nowhere.pgm"],
    );
    // TOML with an unclosed polygon.
    let t = write(
        "open.toml",
        b"format = \"floorcast-building\"\nversion = 1\nname = \"x\"\noutline = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]\n",
    );
    assert_clean_failure(
        &run(&["building", "check", t.to_str().unwrap()]),
        &["open.toml", "closed"],
    );
    // TOML with the start inside a wall.
    let t = write(
        "wallstart.toml",
        b"format = \"floorcast-building\"\nversion = 1\nname = \"x\"\noutline = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0], [0.0, 0.0]]\n[[walls]]\nfrom = [5.0, 0.0]\nto = [5.0, 10.0]\nthickness = 0.4\n[start]\nx = 5.0\ny = 5.0\ntheta_deg = 0.0\n",
    );
    assert_clean_failure(
        &run(&["building", "check", t.to_str().unwrap()]),
        &["wallstart.toml", "wall"],
    );
    // Stage world without a bitmap.
    let w = write(
        "nobitmap.world",
        b"floorplan( name \"x\" size [10 10 1] )\n",
    );
    assert_clean_failure(
        &run(&["building", "check", w.to_str().unwrap()]),
        &["nobitmap.world", "bitmap"],
    );
    // Unknown extension.
    let w = write("what.txt", b"");
    assert_clean_failure(
        &run(&["building", "check", w.to_str().unwrap()]),
        &["what.txt"],
    );
}

#[test]
fn a_closed_stdout_pipe_is_not_a_panic() {
    let b = repo().join("buildings/small.toml");
    let mut child = floorcast()
        .args(["building", "check", b.to_str().unwrap()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{:?}", out.status);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));
}
