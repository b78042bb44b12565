//! Annotated floor plans (KTH XML, `maps/plans/`): each becomes a building with its spaces as
//! ground-truth rooms, a free area close to its rooms' polygons, and rooms the robot can reach
//! through the doorways cut at the portals; malformed plans are clean one-line errors.

use std::path::{Path, PathBuf};

use floorcast_formats::read_floorplan;

fn plans_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../maps/plans")
}

#[test]
fn every_vendored_plan_is_a_building_with_its_rooms() {
    let mut plans: Vec<PathBuf> = std::fs::read_dir(plans_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "xml"))
        .collect();
    plans.sort();
    assert!(plans.len() >= 4, "{plans:?}");
    for path in plans {
        let text = std::fs::read_to_string(&path).unwrap();
        // Every space of these plans has a polygon: one room each.
        let spaces = text.matches("<space id=").count();
        let b = read_floorplan(&path).unwrap();
        let name = path.display();
        assert_eq!(b.rooms.len(), spaces, "{name}");
        assert!(b.rooms.iter().all(|r| !r.kind.is_empty()), "{name}");
        assert!(
            b.rooms.iter().any(|r| r.kind == "corridor"),
            "{name}: no corridor"
        );
        // Portals join two spaces: every door names two rooms.
        assert!(!b.doors.is_empty(), "{name}");
        assert!(
            b.doors.iter().all(|d| d.rooms.iter().all(Option::is_some)),
            "{name}"
        );
        // The free area is the rooms' area less the walls (0.15 m along every edge): within 10 %.
        let rooms_m2: f64 = b.rooms.iter().map(|r| r.polygon.area_m2()).sum();
        let free_m2 = b.free_area_m2();
        assert!(
            free_m2 <= rooms_m2 && free_m2 >= 0.9 * rooms_m2,
            "{name}: free {free_m2:.1} m2 against the rooms' {rooms_m2:.1} m2"
        );
        // The start is in a space (the largest corridor, by its type code), and the robot can
        // see nearly all of the plan from where it can drive: the doorways are cut.
        let start = b.start.expect("a start in the largest corridor");
        assert!(
            b.rooms.iter().any(|r| r.polygon.contains(start.position())),
            "{name}"
        );
        let frame = b.area_frame();
        let reachable = b.reachable_free(frame, start.position());
        let explorable =
            sim_core::building::explorable_free(&reachable, start.position(), 0.2, 6.0);
        let seen = explorable.count_true() as f64 * frame.cell_area_m2();
        assert!(
            seen >= 0.97 * free_m2,
            "{name}: {seen:.1} of {free_m2:.1} m2 explorable from the start"
        );
    }
}

/// A good plan (Lamuniere1) changed in one place: each must be refused with one line naming the
/// file and the element.
#[test]
fn malformed_plans_are_refused_naming_the_element() {
    let good = std::fs::read_to_string(plans_dir().join("Lamuniere1_updated.xml")).unwrap();
    // (what, the plan's text, words of the error)
    let cases: Vec<(&str, String, Vec<&str>)> = vec![
        ("truncated", good[..good.len() / 2].to_string(), vec!["not a well-formed XML"]),
        ("empty", String::new(), vec!["not a well-formed XML"]),
        ("not xml", "hello".into(), vec!["not a well-formed XML"]),
        (
            "another root",
            "<plan><floor/></plan>".into(),
            vec!["plan", "<building>"],
        ),
        (
            "no scale",
            good.replacen("<scale>", "<scalex>", 1).replacen("</scale>", "</scalex>", 1),
            vec!["scale", "missing"],
        ),
        (
            "scale in furlongs",
            minimal("1", "5", "furlong"),
            vec!["scale/real_distance/um", "furlong"],
        ),
        (
            "scale zero",
            minimal("0", "5", "cm"),
            vec!["scale/represented_distance/value", "positive"],
        ),
        (
            "a kilometre a pixel",
            minimal("1", "1000", "m"),
            vec!["scale", "m per pixel"],
        ),
        (
            "coordinate 1e300",
            minimal_with("1", "5", "cm", "1e300"),
            vec!["bounding_polygon/point[0]/x", "within"],
        ),
        (
            "a space without id",
            good.replacen("<space id=", "<space ident=", 1),
            vec!["space[0]", "id"],
        ),
        (
            "a portal to a missing space",
            {
                let at = good.find("<target>").unwrap();
                let id_at = at + good[at..].find("<id>").unwrap() + 4;
                format!("{}nowhere-{}", &good[..id_at], &good[id_at..])
            },
            vec!["portal", "does not have"],
        ),
        (
            "a segment of another class",
            good.replacen("<class>WALL</class>", "<class>WINDOW</class>", 1),
            vec!["class", "WINDOW", "WALL or PORTAL"],
        ),
        (
            "no spaces",
            "<building><scale><represented_distance><value>1</value><um>pixel</um></represented_distance><real_distance><value>5</value><um>cm</um></real_distance></scale><floor><spaces/></floor></building>".into(),
            vec!["no space with a polygon"],
        ),
        (
            "a zero-area room",
            "<building><scale><represented_distance><value>1</value><um>pixel</um></represented_distance><real_distance><value>5</value><um>cm</um></real_distance></scale><floor><spaces><space id=\"a\"><bounding_polygon><point x=\"0\" y=\"0\"/><point x=\"10\" y=\"0\"/><point x=\"20\" y=\"0\"/></bounding_polygon></space></spaces></floor></building>".into(),
            vec!["space[0]", "zero area"],
        ),
        (
            "deeply nested",
            format!("<building>{}{}</building>", "<a>".repeat(100_000), "</a>".repeat(100_000)),
            vec!["nested", "at most 64"],
        ),
        (
            "a DTD",
            format!("<!DOCTYPE building [<!ENTITY a \"aaaa\">]>{good}"),
            vec!["DTD", "expected a floor plan without one"],
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (what, text, words) in cases {
        let path = dir.path().join("plan.xml");
        std::fs::write(&path, &text).unwrap();
        let e = match read_floorplan(&path) {
            Ok(_) => panic!("{what}: accepted"),
            Err(e) => e.to_string(),
        };
        assert_eq!(e.lines().count(), 1, "{what}: {e}");
        assert!(e.contains("plan.xml"), "{what}: {e}");
        for w in words {
            assert!(e.contains(w), "{what}: {w:?} missing in {e}");
        }
    }
}

/// A plan of one square room, its scale `px` pixels for `real` `unit`.
fn minimal(px: &str, real: &str, unit: &str) -> String {
    minimal_with(px, real, unit, "0")
}

/// [`minimal`] with the room's first corner at x = `x0` pixels.
fn minimal_with(px: &str, real: &str, unit: &str, x0: &str) -> String {
    format!(
        "<building><scale><represented_distance><value>{px}</value><um>pixel</um>\
         </represented_distance><real_distance><value>{real}</value><um>{unit}</um>\
         </real_distance></scale><floor><spaces><space id=\"a\"><labels><type>C</type>\
         <label>CORRIDOR</label></labels><bounding_polygon><point x=\"{x0}\" y=\"0\"/>\
         <point x=\"100\" y=\"0\"/><point x=\"100\" y=\"100\"/><point x=\"0\" y=\"100\"/>\
         </bounding_polygon></space></spaces></floor></building>"
    )
}
