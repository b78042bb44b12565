//! Polygons whose edges cross by an annotator's slip are repaired with a warning naming the
//! polygon and the size of the change, and refused beyond the tolerance or when strict
//! (`formats::polygon`): real plans of `maps/plans/` with one corner slipped, and building TOML.

use std::path::{Path, PathBuf};

use floorcast_formats::{
    parse_building_toml_with, read_floorplan, read_floorplan_with, LoadOptions,
};

fn plans_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../maps/plans")
}

const LENIENT: LoadOptions = LoadOptions { strict: false };
const STRICT: LoadOptions = LoadOptions { strict: true };

/// Metres per pixel of a plan: its `<scale>`.
fn metres_per_px(doc: &roxmltree::Document) -> f64 {
    let scale = doc.descendants().find(|n| n.has_tag_name("scale")).unwrap();
    let value = |tag: &str| -> (f64, String) {
        let el = scale.descendants().find(|n| n.has_tag_name(tag)).unwrap();
        let text = |t: &str| {
            el.descendants()
                .find(|n| n.has_tag_name(t))
                .and_then(|n| n.text())
                .unwrap()
                .trim()
                .to_string()
        };
        (text("value").parse().unwrap(), text("um"))
    };
    let (px, unit) = value("represented_distance");
    assert_eq!(unit, "pixel");
    let (real, unit) = value("real_distance");
    let metres = match unit.as_str() {
        "cm" => real / 100.0,
        "mm" => real / 1000.0,
        "m" => real,
        u => panic!("unit {u}"),
    };
    metres / px
}

/// The plan's text with the first room's (type R) corner that has two edges of at least 2 m
/// and a right angle slipped as an annotator slips it: the corner's point placed `slip_m` past
/// the corner along the edge coming in (across the edge going out), and the next point
/// `back_m` before the corner on the line of the edge going out, so that the two edges cross
/// at the corner. Returns the text, the space's index among the plan's `<space>`s and id.
fn slip_a_corner(text: &str, slip_m: f64, back_m: f64) -> (String, usize, String) {
    let doc = roxmltree::Document::parse(text).unwrap();
    let mpp = metres_per_px(&doc);
    let spaces = doc.descendants().filter(|n| n.has_tag_name("space"));
    for (i, space) in spaces.enumerate() {
        let is_room = space
            .descendants()
            .find(|n| n.has_tag_name("type"))
            .and_then(|n| n.text())
            == Some("R");
        let Some(poly) = space
            .children()
            .find(|n| n.has_tag_name("bounding_polygon"))
        else {
            continue;
        };
        let mut pts: Vec<(f64, f64)> = poly
            .children()
            .filter(|n| n.has_tag_name("point"))
            .map(|p| {
                let c = |a| p.attribute(a).unwrap().trim().parse::<f64>().unwrap();
                (c("x"), c("y"))
            })
            .collect();
        pts.dedup();
        while pts.len() > 1 && pts[0] == pts[pts.len() - 1] {
            pts.pop();
        }
        let n = pts.len();
        if !is_room || n < 4 {
            continue;
        }
        for k in 0..n {
            let (p, c, q) = (pts[(k + n - 1) % n], pts[k], pts[(k + 1) % n]);
            let (din, dout) = ((c.0 - p.0, c.1 - p.1), (q.0 - c.0, q.1 - c.1));
            let (lin, lout) = (din.0.hypot(din.1), dout.0.hypot(dout.1));
            if lin * mpp < 2.0 || lout * mpp < 2.0 || (din.0 * dout.0 + din.1 * dout.1).abs() > 1e-9
            {
                continue;
            }
            let (uin, uout) = ((din.0 / lin, din.1 / lin), (dout.0 / lout, dout.1 / lout));
            let (s, b) = (slip_m / mpp, back_m / mpp);
            let past = (c.0 + uin.0 * s, c.1 + uin.1 * s);
            let before = (c.0 - uout.0 * b, c.1 - uout.1 * b);
            let mut ring: Vec<(f64, f64)> = Vec::new();
            for (j, v) in pts.iter().enumerate() {
                if j == k {
                    ring.extend([past, before]);
                } else {
                    ring.push(*v);
                }
            }
            ring.push(ring[0]);
            let inner: String = ring
                .iter()
                .map(|(x, y)| format!("<point x=\"{x}\" y=\"{y}\"/>"))
                .collect();
            let r = poly.range();
            let new = format!(
                "{}<bounding_polygon>{inner}</bounding_polygon>{}",
                &text[..r.start],
                &text[r.end..]
            );
            return (new, i, space.attribute("id").unwrap().to_string());
        }
    }
    panic!("no room with a right-angled corner between edges of 2 m");
}

/// (plan, slip (m), back (m)): each plan loads with one warning naming the room, its area
/// changed by the slip's triangle and the corner moved by the slip; the room repaired is the
/// room as drawn before the slip; strict, the plan is refused naming the room.
#[test]
fn a_vendored_plan_with_a_slipped_corner_loads_with_a_warning() {
    let cases: &[(&str, f64, f64)] = &[
        ("Borchen4_updated.xml", 0.4, 0.2),
        ("Lamuniere1_updated.xml", 0.2, 0.05),
        ("ED21.xml", 0.6, 0.3),
        ("AtlanticSuites.xml", 0.4, 0.4),
    ];
    let dir = tempfile::tempdir().unwrap();
    for &(plan, slip, back) in cases {
        let original = plans_dir().join(plan);
        let text = std::fs::read_to_string(&original).unwrap();
        let (slipped, i, id) = slip_a_corner(&text, slip, back);
        let path = dir.path().join(plan);
        std::fs::write(&path, &slipped).unwrap();
        let before = read_floorplan(&original).unwrap();
        let loaded = read_floorplan_with(&path, LENIENT).unwrap_or_else(|e| panic!("{plan}: {e}"));
        assert_eq!(loaded.warnings.len(), 1, "{plan}: {:?}", loaded.warnings);
        let w = loaded.warnings[0].to_string();
        let short: String = id.chars().take(40).collect();
        for word in [
            format!("{}: space[{i}] ({short}", path.display()),
            "/bounding_polygon: the '".into(),
            "(type R): the edge from (".into(),
            "1 crossing; the loop beyond it dropped: the area changed by ".into(),
            format!("a corner moved by up to {slip} m"),
            "--strict".into(),
        ] {
            assert!(w.contains(&word), "{plan}: {word:?} not in {w}");
        }
        assert!(!w.contains('\n') && !w.contains("00000"), "{plan}: {w}");
        // The dropped triangle's area, to the millimetre's rounding.
        let area = format!(
            "changed by {} m²",
            (slip * back / 2.0 * 1000.0).round() / 1000.0
        );
        assert!(w.contains(&area), "{plan}: {area:?} not in {w}");
        // The room as it was drawn before the slip (the crossing is its corner).
        let b = &loaded.building;
        assert_eq!(b.rooms.len(), before.rooms.len(), "{plan}");
        for (r, s) in b.rooms.iter().zip(&before.rooms) {
            let (x, y) = (r.polygon.area_m2(), s.polygon.area_m2());
            assert!(
                (x - y).abs() < 1e-6,
                "{plan}: room {} {x} m² vs {y} m²",
                r.id
            );
        }
        let (x, y) = (b.free_area_m2(), before.free_area_m2());
        assert!((x - y).abs() <= 0.01 * y, "{plan}: free area {x} vs {y}");
        let e = read_floorplan_with(&path, STRICT).unwrap_err().to_string();
        for word in [
            format!("{}: space[{i}] ({short}", path.display()),
            "polygon's edges cross each other".into(),
            "refused under --strict".into(),
        ] {
            assert!(e.contains(&word), "{plan}: {word:?} not in {e}");
        }
    }
}

const HEADER: &str = "format = \"floorcast-building\"\nversion = 1\n";

/// (what, outline, room polygon, strict, the warning's or error's words; error when the first
/// word is "error")
#[test]
fn building_toml_polygons_are_repaired_or_refused() {
    let square = "[[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0], [0.0, 0.0]]";
    // The corner (0, 0) slipped: 0.4 m past it down the edge coming in, then 0.2 m before it.
    let slipped_outline =
        "[[-0.2, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0], [0.0, -0.4], [-0.2, 0.0]]";
    let slipped_room = "[[0.8, 1.0], [6.0, 1.0], [6.0, 6.0], [1.0, 6.0], [1.0, 0.6], [0.8, 1.0]]";
    let room = "[[1.0, 1.0], [6.0, 1.0], [6.0, 6.0], [1.0, 6.0], [1.0, 1.0]]";
    let eight = "[[1.0, 1.0], [9.0, 9.0], [9.0, 1.0], [1.0, 5.0], [1.0, 1.0]]";
    type Case<'a> = (&'a str, &'a str, &'a str, bool, &'a [&'a str]);
    let cases: &[Case] = &[
        ("simple", square, room, false, &[]),
        (
            "a room's corner slipped",
            square,
            slipped_room,
            false,
            &[
                "b.toml: rooms[0].polygon: the room 1 ('office'): the edge from (0.8, 1.0) to (6.0, 1.0) crosses the edge from (1.0, 6.0) to (1.0, 0.6) at (1.0, 1.0)",
                "the area changed by 0.04 m² (0.2 % of the 25.0 m² kept) and a corner moved by up to 0.4 m",
            ],
        ),
        (
            "the outline's corner slipped",
            slipped_outline,
            room,
            false,
            &["b.toml: outline: the outline: ", "at (0.0, 0.0)", "a corner moved by up to 0.4 m"],
        ),
        (
            "a room's corner slipped, strict",
            square,
            slipped_room,
            true,
            &["error", "b.toml: rooms[0].polygon: polygon's edges cross each other", "refused under --strict"],
        ),
        (
            "a figure-eight room",
            square,
            eight,
            false,
            &[
                "error",
                "b.toml: rooms[0].polygon: polygon's edges cross each other",
                "at (3.667, 3.667)",
                "not repaired: the repair would be too large a change",
                "beyond the tolerance of a corner moved by 1.5 m and an area changed by 2.0 m² or 5 %",
            ],
        ),
    ];
    let reference = parse_building_toml_with(
        &format!(
            "{HEADER}outline = {square}\n[[rooms]]\nid = 1\nkind = \"office\"\npolygon = {room}\n"
        ),
        Path::new("b.toml"),
        LENIENT,
    )
    .unwrap()
    .building;
    for (what, outline, polygon, strict, words) in cases {
        let text = format!(
            "{HEADER}outline = {outline}\n[[rooms]]\nid = 1\nkind = \"office\"\npolygon = {polygon}\n"
        );
        let got =
            parse_building_toml_with(&text, Path::new("b.toml"), LoadOptions { strict: *strict });
        if words.first() == Some(&"error") {
            let e = got.unwrap_err().to_string();
            assert_eq!(e.lines().count(), 1, "{what}: {e}");
            for w in &words[1..] {
                assert!(e.contains(w), "{what}: {w:?} not in {e}");
            }
            continue;
        }
        let l = got.unwrap_or_else(|e| panic!("{what}: {e}"));
        if words.is_empty() {
            assert!(l.warnings.is_empty(), "{what}: {:?}", l.warnings);
            continue;
        }
        assert_eq!(l.warnings.len(), 1, "{what}: {:?}", l.warnings);
        let w = l.warnings[0].to_string();
        for word in *words {
            assert!(w.contains(word), "{what}: {word:?} not in {w}");
        }
        // Rooms and outline are the shapes before the slip.
        let b = &l.building;
        assert!((b.rooms[0].polygon.area_m2() - 25.0).abs() < 1e-9, "{what}");
        let (x, y) = (b.free_area_m2(), reference.free_area_m2());
        assert!((x - y).abs() <= 0.01 * y, "{what}: free area {x} vs {y}");
    }
}
