//! Fuzzing the readers: arbitrary bytes and mutations of valid files never panic, finish fast,
//! and every error is one line naming the file. `PROPTEST_CASES` sets how many cases run (the
//! default keeps CI fast); cases found failing are kept in `tests/malformed/`.

use std::path::Path;
use std::time::{Duration, Instant};

use proptest::prelude::*;

use crate::map_server::{decode_image, parse_map_yaml, MapImage};

/// Longest any one parse may take.
const BOUND: Duration = Duration::from_secs(2);

/// The tokens that matter to the formats read here.
const TOKENS: [&[u8]; 10] = [
    b"1e300", b"-1", b"nan", b"[", b"(", b"\"", b"\n", b"0", b"1e-300", b"]",
];

fn mutate(text: &str, edits: &[(usize, u8, u8)]) -> String {
    crate::mutation::mutate(text, edits, &TOKENS)
}

fn edits() -> impl Strategy<Value = Vec<(usize, u8, u8)>> {
    proptest::collection::vec((any::<usize>(), any::<u8>(), any::<u8>()), 0..12)
}

fn check_error(e: &crate::Error, file: &str) {
    let s = e.to_string();
    assert!(!s.contains('\n'), "multi-line: {s}");
    assert!(s.starts_with(file), "does not name {file}: {s}");
}

const BUILDING: &str = r#"format = "floorcast-building"
version = 1
name = "t"
outline = [[0.0, 0.0], [10.0, 0.0], [10.0, 6.0], [0.0, 6.0], [0.0, 0.0]]
[[walls]]
from = [5.0, 0.0]
to = [5.0, 2.5]
thickness = 0.2
[[solids]]
polygon = [[2.0, 2.0], [2.5, 2.0], [2.5, 2.5], [2.0, 2.0]]
[[rooms]]
id = 1
polygon = [[0.0, 0.0], [5.0, 0.0], [5.0, 6.0], [0.0, 6.0], [0.0, 0.0]]
[[doors]]
from = [5.0, 2.5]
to = [5.0, 3.5]
rooms = [1]
[start]
x = 1.0
y = 1.0
theta_deg = 90.0
"#;

const YAML: &str = "image: m.pgm\nresolution: 0.05\norigin: [1.0, -2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n";

const WORLD: &str = "define plan model ( color \"gray\" boundary 1 )\ndefine bot position ( size [0.3 0.3 0.2] )\nplan( name \"p\" bitmap \"m.pgm\" size [8 6 1] pose [1 2 0 0] )\nbot( pose [ 1 2 0 90 ] name \"r\" )\n";

fn pgm() -> Vec<u8> {
    let mut b = b"P5\n8 6\n255\n".to_vec();
    for y in 0..6 {
        for x in 0..8 {
            b.push(if x == 0 || y == 0 || x == 7 || y == 5 {
                0
            } else {
                254
            });
        }
    }
    b
}

fn png() -> Vec<u8> {
    let img = image::GrayImage::from_fn(8, 6, |x, y| image::Luma([if x == y { 0 } else { 254 }]));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

fn bounded<T>(what: &str, f: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let r = f();
    assert!(t.elapsed() < BOUND, "{what} took {:?}", t.elapsed());
    r
}

fn world(text: &str, image: &[u8]) -> Result<sim_core::Building, crate::Error> {
    let path = Path::new("f/w.world");
    crate::stage::world_from_text(text, path, &|p, field| decode_image(path, field, p, image))
}

proptest! {
    #[test]
    fn building_toml_never_panics(e in edits()) {
        let text = mutate(BUILDING, &e);
        let r = bounded("building", || crate::parse_building_toml(&text, Path::new("f/b.toml")));
        if let Err(err) = r {
            check_error(&err, "f/b.toml: ");
        }
    }

    #[test]
    fn building_toml_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let text = format!("format = \"floorcast-building\"\nversion = 1\n{}", String::from_utf8_lossy(&bytes));
        if let Err(err) = bounded("building", || crate::parse_building_toml(&text, Path::new("f/b.toml"))) {
            check_error(&err, "f/b.toml: ");
        }
    }

    #[test]
    fn map_yaml_never_panics(e in edits()) {
        let text = mutate(YAML, &e);
        if let Err(err) = bounded("yaml", || parse_map_yaml(&text, Path::new("f/m.yaml"))) {
            check_error(&err, "f/m.yaml: ");
        }
    }

    #[test]
    fn map_images_never_panic(e in edits(), use_png in any::<bool>()) {
        let base = if use_png { png() } else { pgm() };
        // Mutate the bytes themselves (the image is binary).
        let mut b = base.clone();
        for &(pos, op, byte) in &e {
            let i = pos % (b.len() + 1);
            match op % 3 {
                0 if i < b.len() => b[i] = byte,
                1 => b.insert(i, byte),
                _ if i < b.len() => { b.remove(i); }
                _ => {}
            }
        }
        let r: Result<MapImage, _> = bounded("image", || decode_image(Path::new("f/m.yaml"), "image", Path::new("f/m.pgm"), &b));
        if let Err(err) = r {
            check_error(&err, "f/m.yaml: image: ");
        }
    }

    #[test]
    fn stage_world_never_panics(e in edits()) {
        let text = mutate(WORLD, &e);
        if let Err(err) = bounded("world", || world(&text, &pgm())) {
            check_error(&err, "f/w.world: ");
        }
    }

    #[test]
    fn stage_world_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let text = String::from_utf8_lossy(&bytes).into_owned();
        if let Err(err) = bounded("world", || world(&text, &pgm())) {
            check_error(&err, "f/w.world: ");
        }
    }
}

#[test]
fn the_seeds_of_the_fuzzers_are_valid() {
    crate::parse_building_toml(BUILDING, Path::new("f/b.toml")).unwrap();
    parse_map_yaml(YAML, Path::new("f/m.yaml")).unwrap();
    let b = world(WORLD, &pgm()).unwrap();
    assert!(b.start.is_some());
    decode_image(Path::new("f/m.yaml"), "image", Path::new("f/m.png"), &png()).unwrap();
}
