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
    assert!(plans.len() >= 60, "{plans:?}");
    for path in plans {
        let text = std::fs::read_to_string(&path).unwrap();
        // Every space of these plans has a polygon (one, Vieilley1's, of a point repeated: a
        // space left empty, which is left out): one room each.
        let spaces = text.matches("<space id=").count();
        let empty = text.matches("<area value=\"-1\"").count();
        let b = read_floorplan(&path).unwrap();
        let name = path.display();
        assert_eq!(b.rooms.len(), spaces - empty, "{name}");
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
        // The free area is the rooms' area less the walls (0.15 m along every edge), plus the
        // doorways through them: within 10 %.
        let rooms_m2: f64 = b.rooms.iter().map(|r| r.polygon.area_m2()).sum();
        let free_m2 = b.free_area_m2();
        assert!(
            free_m2 <= 1.02 * rooms_m2 && free_m2 >= 0.9 * rooms_m2,
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
            // The default robot: 0.2 m radius and a 0.05 m margin, a 6 m laser.
            sim_core::building::explorable_free(&reachable, start.position(), 0.25, 6.0);
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

/// A space of a synthetic plan (pixels are centimetres): its outline, and its walls as the
/// outline's edges split at its portals' points; `portals` as (line segment id, point, the two
/// spaces), the point `None` for a portal naming a line segment no space has.
struct TestSpace<'a> {
    id: &'a str,
    kind: &'a str,
    outline: Vec<(f64, f64)>,
    portals: Vec<TestPortal<'a>>,
}

/// A portal of a [`TestSpace`]: its line segment's id, its point, the two spaces it joins.
type TestPortal<'a> = (&'a str, Option<(f64, f64)>, [&'a str; 2]);

fn test_plan(spaces: &[TestSpace]) -> String {
    let mut xml = String::from(
        "<building><scale><represented_distance><value>100</value><um>pixel</um>\
         </represented_distance><real_distance><value>1</value><um>m</um></real_distance>\
         </scale><floor><spaces>",
    );
    for s in spaces {
        xml += &format!(
            "<space id=\"{}\"><labels><type>{}</type><label>{}</label></labels><bounding_polygon>",
            s.id,
            s.kind,
            if s.kind == "C" { "CORRIDOR" } else { "OFFICE" }
        );
        for (x, y) in &s.outline {
            xml += &format!("<point x=\"{x}\" y=\"{y}\"/>");
        }
        xml += "</bounding_polygon><space_representation>";
        let n = s.outline.len();
        let mut k = 0;
        for i in 0..n {
            let (a, b) = (s.outline[i], s.outline[(i + 1) % n]);
            // The portals on this edge, in order from `a`.
            let mut on: Vec<(f64, (f64, f64), &str)> = s
                .portals
                .iter()
                .filter_map(|(id, p, _)| p.map(|p| (*id, p)))
                .filter(|(_, p)| {
                    let cross = (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0);
                    let t = ((p.0 - a.0) * (b.0 - a.0) + (p.1 - a.1) * (b.1 - a.1))
                        / ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2));
                    cross.abs() < 1e-6 && (0.0..=1.0).contains(&t)
                })
                .map(|(id, p)| ((p.0 - a.0).abs() + (p.1 - a.1).abs(), p, id))
                .collect();
            on.sort_by(|x, y| x.0.total_cmp(&y.0));
            let mut from = a;
            for (_, p, id) in on {
                xml += &segment(&format!("{}-w{k}", s.id), "WALL", from, p);
                xml += &segment(id, "PORTAL", p, p);
                from = p;
                k += 1;
            }
            xml += &segment(&format!("{}-w{k}", s.id), "WALL", from, b);
            k += 1;
        }
        xml += "</space_representation><portals>";
        for (id, _, targets) in &s.portals {
            xml += &format!(
                "<portal><linesegment>{id}</linesegment><target><id>{}</id><id>{}</id></target></portal>",
                targets[0], targets[1]
            );
        }
        xml += "</portals></space>";
    }
    xml + "</spaces></floor></building>"
}

fn segment(id: &str, class: &str, a: (f64, f64), b: (f64, f64)) -> String {
    format!(
        "<linesegment id=\"{id}\"><point x=\"{}\" y=\"{}\"/><point x=\"{}\" y=\"{}\"/><class>{class}</class></linesegment>",
        a.0, a.1, b.0, b.1
    )
}

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<(f64, f64)> {
    vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
}

/// How doorways are cut where the plans give a point: each case a corridor (10 x 2 m, pixels
/// 0-1000 x 0-200) and a second space below it, the door expected (centre x in m, width in m),
/// and the robot must be able to see at least 97 % of the plan from the start.
#[test]
fn doorways_are_cut_where_the_robot_fits() {
    let corridor = |portals| TestSpace {
        id: "c",
        kind: "C",
        outline: rect(0.0, 0.0, 1000.0, 200.0),
        portals,
    };
    let room = |portals| TestSpace {
        id: "r",
        kind: "R",
        outline: rect(0.0, 200.0, 500.0, 700.0),
        portals,
    };
    let both = ["c", "r"];
    // (what, spaces, the door's centre x and width)
    let cases: Vec<(&str, Vec<TestSpace>, f64, f64)> = vec![
        (
            "a door mid-wall",
            vec![
                corridor(vec![("p", Some((250.0, 200.0)), both)]),
                room(vec![("p", Some((250.0, 200.0)), both)]),
            ],
            2.5,
            0.9,
        ),
        (
            "a door at a corner slides clear of the wall across",
            vec![
                corridor(vec![("p", Some((10.0, 200.0)), both)]),
                room(vec![("p", Some((10.0, 200.0)), both)]),
            ],
            0.075 + 0.45,
            0.9,
        ),
        (
            "a door whose two ends the spaces mark",
            vec![
                corridor(vec![("p", Some((300.0, 200.0)), both)]),
                room(vec![("p", Some((420.0, 200.0)), both)]),
            ],
            3.6,
            1.2,
        ),
        (
            "a portal naming a line segment no space has: midway along the shared wall",
            vec![
                corridor(vec![("gone", None, both)]),
                room(vec![("gone", None, both)]),
            ],
            2.5,
            0.9,
        ),
        (
            "two corridors open to each other along all they share",
            vec![
                corridor(vec![("p", Some((100.0, 200.0)), ["c", "d"])]),
                TestSpace {
                    id: "d",
                    kind: "C",
                    outline: rect(0.0, 200.0, 200.0, 1000.0),
                    portals: vec![("p", Some((100.0, 200.0)), ["c", "d"])],
                },
            ],
            1.0,
            2.0 - 0.15,
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (what, spaces, x, width) in cases {
        let path = dir.path().join("plan.xml");
        std::fs::write(&path, test_plan(&spaces)).unwrap();
        let b = read_floorplan(&path).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!(b.rooms.len(), 2, "{what}");
        assert_eq!(b.doors.len(), 1, "{what}");
        let d = &b.doors[0];
        let centre = (d.a + d.b) * 0.5;
        assert!(
            (centre.x - x).abs() < 0.01,
            "{what}: door at x {}",
            centre.x
        );
        assert!(
            (centre.y + 2.0).abs() < 0.05,
            "{what}: door at y {}",
            centre.y
        );
        let w = (d.b - d.a).norm();
        assert!((w - width).abs() < 0.01, "{what}: door {w} m wide");
        let start = b.start.unwrap().position();
        let frame = b.area_frame();
        let seen =
            sim_core::building::explorable_free(&b.reachable_free(frame, start), start, 0.25, 6.0)
                .count_true() as f64
                * frame.cell_area_m2();
        assert!(
            seen >= 0.97 * b.free_area_m2(),
            "{what}: {seen:.1} of {:.1} m2",
            b.free_area_m2()
        );
    }
}

/// Plans the reader mends or refuses: a space left empty (one point repeated) is left out; a
/// portal naming a missing line segment between spaces that share no wall cannot be placed.
#[test]
fn spaces_left_empty_are_left_out_and_unplaceable_portals_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("plan.xml");
    let corridor = TestSpace {
        id: "c",
        kind: "C",
        outline: rect(0.0, 0.0, 1000.0, 200.0),
        portals: vec![],
    };
    let empty = TestSpace {
        id: "e",
        kind: "R",
        outline: vec![(50.0, 50.0); 3],
        portals: vec![],
    };
    std::fs::write(&path, test_plan(&[corridor, empty])).unwrap();
    let b = read_floorplan(&path).unwrap();
    assert_eq!(b.rooms.len(), 1);
    let apart = vec![
        TestSpace {
            id: "c",
            kind: "C",
            outline: rect(0.0, 0.0, 1000.0, 200.0),
            portals: vec![("gone", None, ["c", "r"])],
        },
        TestSpace {
            id: "r",
            kind: "R",
            outline: rect(0.0, 500.0, 500.0, 900.0),
            portals: vec![("gone", None, ["c", "r"])],
        },
    ];
    std::fs::write(&path, test_plan(&apart)).unwrap();
    let e = read_floorplan(&path).unwrap_err().to_string();
    for w in [
        "plan.xml",
        "portals/portal[0]/linesegment",
        "gone",
        "share no wall",
    ] {
        assert!(e.contains(w), "{w:?} missing in {e}");
    }
}
