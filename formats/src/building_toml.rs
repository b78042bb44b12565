//! floorcast's own building format: a versioned TOML file describing a vector building
//! (see `BUILDING_FORMAT.md` beside this crate's `Cargo.toml`).
//!
//! The file types here mirror the file exactly (`deny_unknown_fields`, no `flatten`, no
//! `untagged`) and are converted by hand to and from [`sim_core::Building`], validating on the
//! way in. Rings in the file are closed (the first vertex is repeated at the end); a
//! [`Polygon`] holds them open. Walls become [`Polygon::thick_segment`] solids, listed before the
//! `[[solids]]` polygons; a building is always written with `[[solids]]` only.

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};
use sim_core::{Building, Door, Geometry, Polygon, Pose, Room, Vec2};

use crate::error::{num, point, Error};
use crate::polygon::{LoadOptions, Rings};
use crate::Loaded;

/// The value of the `format` key.
pub const FORMAT_NAME: &str = "floorcast-building";
/// The only version this crate reads and writes.
pub const FORMAT_VERSION: i64 = 1;

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct FileV1 {
    format: String,
    version: i64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    name: Option<String>,
    outline: Vec<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    walls: Vec<WallV1>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    solids: Vec<SolidV1>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    rooms: Vec<RoomV1>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    doors: Vec<DoorV1>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    start: Option<StartV1>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct WallV1 {
    from: [f64; 2],
    to: [f64; 2],
    thickness: f64,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SolidV1 {
    polygon: Vec<[f64; 2]>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RoomV1 {
    id: u32,
    #[serde(default, skip_serializing_if = "String::is_empty")]
    kind: String,
    polygon: Vec<[f64; 2]>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct DoorV1 {
    from: [f64; 2],
    to: [f64; 2],
    /// Up to two room ids; 0 or a missing entry is the outside.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    rooms: Vec<u32>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct StartV1 {
    x: f64,
    y: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    theta_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    theta_rad: Option<f64>,
}

/// Reads and validates a building TOML file; the name defaults to the file's stem. A polygon
/// whose edges cross by a slip is repaired ([`crate::polygon`]) and the warning dropped (see
/// [`read_building_toml_with`]).
pub fn read_building_toml(path: &Path) -> Result<Building, Error> {
    read_building_toml_with(path, LoadOptions::default()).map(|l| l.building)
}

/// Reads and validates a building TOML file, with the warnings of the polygons repaired
/// ([`crate::polygon`]; refused instead under `options.strict`).
pub fn read_building_toml_with(path: &Path, options: LoadOptions) -> Result<Loaded, Error> {
    let text = crate::limits::read_text(path)?;
    parse_building_toml_with(&text, path, options)
}

/// Parses and validates building TOML text; `path` names the file in messages and gives the
/// default name (its stem). Repairs as [`read_building_toml`] does.
pub fn parse_building_toml(text: &str, path: &Path) -> Result<Building, Error> {
    parse_building_toml_with(text, path, LoadOptions::default()).map(|l| l.building)
}

/// Parses and validates building TOML text, with the warnings of the polygons repaired.
pub fn parse_building_toml_with(
    text: &str,
    path: &Path,
    options: LoadOptions,
) -> Result<Loaded, Error> {
    check_header(text, path)?;
    let file: FileV1 = toml::from_str(text).map_err(|e| toml_error(text, path, &e))?;
    from_file(file, path, options)
}

/// Writes a vector building as TOML.
pub fn write_building_toml(building: &Building, path: &Path) -> Result<(), Error> {
    let text = to_toml_string(building).map_err(|e| match e {
        Error::Unsupported { what, .. } => Error::Unsupported {
            path: path.to_path_buf(),
            what,
        },
        e => e,
    })?;
    std::fs::write(path, text).map_err(|e| Error::io(path, "write", e))
}

/// A vector building as TOML text (raster buildings are refused: write them as a map).
pub fn to_toml_string(building: &Building) -> Result<String, Error> {
    let Geometry::Vector { outline, solids } = &building.geometry else {
        return Err(Error::unsupported(
            Path::new(&building.name),
            "a raster building cannot be written as floorcast TOML; write it with map_server::write_map",
        ));
    };
    let ring = |p: &Polygon| -> Vec<[f64; 2]> {
        let mut v: Vec<[f64; 2]> = p.vertices.iter().map(|v| [v.x, v.y]).collect();
        if let Some(first) = v.first().copied() {
            v.push(first);
        }
        v
    };
    let file = FileV1 {
        format: FORMAT_NAME.to_string(),
        version: FORMAT_VERSION,
        name: (!building.name.is_empty()).then(|| building.name.clone()),
        outline: ring(outline),
        walls: Vec::new(),
        solids: solids
            .iter()
            .map(|s| SolidV1 { polygon: ring(s) })
            .collect(),
        rooms: building
            .rooms
            .iter()
            .map(|r| RoomV1 {
                id: r.id,
                kind: r.kind.clone(),
                polygon: ring(&r.polygon),
            })
            .collect(),
        doors: building
            .doors
            .iter()
            .map(|d| DoorV1 {
                from: [d.a.x, d.a.y],
                to: [d.b.x, d.b.y],
                rooms: if d.rooms == [None, None] {
                    Vec::new()
                } else {
                    d.rooms.iter().map(|r| r.unwrap_or(0)).collect()
                },
            })
            .collect(),
        start: building.start.map(|p| {
            // Degrees when they read back to the very same radians, else radians.
            let deg = p.theta_rad.to_degrees();
            let exact = deg.to_radians() == p.theta_rad;
            StartV1 {
                x: p.x_m,
                y: p.y_m,
                theta_deg: exact.then_some(deg),
                theta_rad: (!exact).then_some(p.theta_rad),
            }
        }),
    };
    toml::to_string(&file).map_err(|e| {
        Error::unsupported(
            Path::new(&building.name),
            format!("cannot be written as TOML: {e}"),
        )
    })
}

/// Checks `format` and `version` before anything else, so that a file of another version gets
/// that message rather than one about a field this version does not know.
fn check_header(text: &str, path: &Path) -> Result<(), Error> {
    let table: toml::Table = toml::from_str(text).map_err(|e| toml_error(text, path, &e))?;
    match table.get("format") {
        Some(toml::Value::String(s)) if s == FORMAT_NAME => {}
        Some(v) => {
            return Err(Error::invalid(
                path,
                "format",
                format!("unknown format {v}; expected format = \"{FORMAT_NAME}\""),
            ))
        }
        None => {
            return Err(Error::invalid(
                path,
                "format",
                format!("missing; expected format = \"{FORMAT_NAME}\" as the first line"),
            ))
        }
    }
    match table.get("version") {
        Some(toml::Value::Integer(v)) if *v == FORMAT_VERSION => Ok(()),
        Some(v) => Err(Error::invalid(
            path,
            "version",
            format!("unsupported version {v}; this floorcast reads version {FORMAT_VERSION}"),
        )),
        None => Err(Error::invalid(
            path,
            "version",
            format!("missing; expected version = {FORMAT_VERSION}"),
        )),
    }
}

/// A TOML error as `file:line:col: message` on one line.
fn toml_error(text: &str, path: &Path, e: &toml::de::Error) -> Error {
    let loc = e.span().map(|s| {
        let before = &text[..s.start.min(text.len())];
        let line = before.matches('\n').count() + 1;
        let col = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
        format!("line {line} column {col}: ")
    });
    Error::syntax(path, format!("{}{}", loc.unwrap_or_default(), e.message()))
}

fn from_file(f: FileV1, path: &Path, options: LoadOptions) -> Result<Loaded, Error> {
    // The checks of the polygons for crossings (a work budget for the whole file), and the
    // warnings of those repaired.
    let rings = &mut Rings::new(options);
    let outline = ring(&f.outline, "outline", "the outline", path, rings)?;
    let (solids, solid_names) = solids_of(&f, path, rings)?;
    let (rooms, ids) = rooms_of(&f, path, rings)?;
    let doors = doors_of(&f, &ids, path)?;
    let start = match &f.start {
        None => None,
        Some(s) => Some(start_of(s, &outline, &solids, &solid_names, path)?),
    };
    let building = Building {
        name: f.name.unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        }),
        geometry: Geometry::Vector { outline, solids },
        rooms,
        doors,
        start,
    };
    crate::limits::check_building(
        &building,
        path,
        "outline",
        crate::limits::EXPLORE_RESOLUTION_M,
    )?;
    Ok(Loaded {
        building,
        warnings: std::mem::take(&mut rings.warnings),
    })
}

/// The walls (as thick segments) and solids, with the file entry each came from (for messages
/// about the start pose).
fn solids_of(
    f: &FileV1,
    path: &Path,
    rings: &mut Rings,
) -> Result<(Vec<Polygon>, Vec<String>), Error> {
    let mut solids = Vec::with_capacity(f.walls.len() + f.solids.len());
    // Which file entry each solid came from, for messages about the start pose.
    let mut solid_names = Vec::with_capacity(solids.capacity());
    for (i, w) in f.walls.iter().enumerate() {
        let field = format!("walls[{i}]");
        let a = vec2(w.from, &format!("{field}.from"), path)?;
        let b = vec2(w.to, &format!("{field}.to"), path)?;
        if !(w.thickness.is_finite() && w.thickness > 0.0 && w.thickness <= MAX_WALL_THICKNESS_M) {
            return Err(Error::invalid(
                path,
                format!("{field}.thickness"),
                format!(
                    "must be a positive number of metres up to {}, got {}",
                    num(MAX_WALL_THICKNESS_M),
                    num(w.thickness)
                ),
            ));
        }
        solids.push(Polygon::thick_segment(a, b, w.thickness));
        solid_names.push(format!("a wall ({field})"));
    }
    for (i, s) in f.solids.iter().enumerate() {
        solids.push(ring(
            &s.polygon,
            &format!("solids[{i}].polygon"),
            &format!("the solid solids[{i}]"),
            path,
            rings,
        )?);
        solid_names.push(format!("a solid (solids[{i}])"));
    }
    Ok((solids, solid_names))
}

/// The rooms, their ids checked (from 1, unique); the ids with their entries' indices.
fn rooms_of(
    f: &FileV1,
    path: &Path,
    rings: &mut Rings,
) -> Result<(Vec<Room>, BTreeMap<u32, usize>), Error> {
    let mut rooms = Vec::with_capacity(f.rooms.len());
    let mut seen: BTreeMap<u32, usize> = BTreeMap::new();
    for (i, r) in f.rooms.iter().enumerate() {
        let field = format!("rooms[{i}]");
        if r.id == 0 {
            return Err(Error::invalid(
                path,
                format!("{field}.id"),
                "room id 0 is reserved for the outside; use ids from 1",
            ));
        }
        if let Some(j) = seen.insert(r.id, i) {
            return Err(Error::invalid(
                path,
                format!("{field}.id"),
                format!(
                    "duplicate room id {} (also rooms[{j}]); ids must be unique",
                    r.id
                ),
            ));
        }
        rooms.push(Room {
            id: r.id,
            kind: r.kind.clone(),
            polygon: ring(
                &r.polygon,
                &format!("{field}.polygon"),
                &format!("the room {} ('{}')", r.id, r.kind),
                path,
                rings,
            )?,
        });
    }
    Ok((rooms, seen))
}

/// The doors, each joining at most two known rooms (0: the outside).
fn doors_of(f: &FileV1, seen: &BTreeMap<u32, usize>, path: &Path) -> Result<Vec<Door>, Error> {
    let mut doors = Vec::with_capacity(f.doors.len());
    for (i, d) in f.doors.iter().enumerate() {
        let field = format!("doors[{i}]");
        let a = vec2(d.from, &format!("{field}.from"), path)?;
        let b = vec2(d.to, &format!("{field}.to"), path)?;
        if d.rooms.len() > 2 {
            return Err(Error::invalid(
                path,
                format!("{field}.rooms"),
                format!(
                    "a door joins at most 2 rooms, got {}; use 0 for the outside",
                    d.rooms.len()
                ),
            ));
        }
        let mut joined = [None, None];
        for (k, &id) in d.rooms.iter().enumerate() {
            if id == 0 {
                continue;
            }
            if !seen.contains_key(&id) {
                let known: Vec<String> = seen.keys().map(u32::to_string).collect();
                return Err(Error::invalid(
                    path,
                    format!("{field}.rooms"),
                    format!(
                        "unknown room id {id}; expected one of the [[rooms]] ids ({}) or 0 for the outside",
                        if known.is_empty() { "none defined".to_string() } else { known.join(", ") }
                    ),
                ));
            }
            joined[k] = Some(id);
        }
        doors.push(Door {
            a,
            b,
            rooms: joined,
        });
    }
    Ok(doors)
}

/// The start pose: one heading, in free space (inside the outline, in no solid).
fn start_of(
    s: &StartV1,
    outline: &Polygon,
    solids: &[Polygon],
    solid_names: &[String],
    path: &Path,
) -> Result<Pose, Error> {
    let p = vec2([s.x, s.y], "start", path)?;
    let theta_rad = match (s.theta_deg, s.theta_rad) {
        (Some(_), Some(_)) => {
            return Err(Error::invalid(
                path,
                "start",
                "give either theta_deg or theta_rad, not both",
            ))
        }
        (Some(d), None) => d.to_radians(),
        (None, Some(r)) => r,
        (None, None) => 0.0,
    };
    if !theta_rad.is_finite() {
        return Err(Error::invalid(
            path,
            "start",
            "the heading is not a finite number",
        ));
    }
    let at = point(p.x, p.y);
    if !outline.contains(p) {
        return Err(Error::invalid(
            path,
            "start",
            format!("start pose {at} is outside the outline; expected a point in free space"),
        ));
    }
    if let Some(k) = solids.iter().position(|s| s.contains(p)) {
        return Err(Error::invalid(
            path,
            "start",
            format!(
                "start pose {at} is inside {}; expected a point in free space",
                solid_names[k]
            ),
        ));
    }
    Ok(Pose::new(p.x, p.y, theta_rad))
}

/// Thickest wall accepted (m).
pub const MAX_WALL_THICKNESS_M: f64 = 100.0;

fn vec2(p: [f64; 2], field: &str, path: &Path) -> Result<Vec2, Error> {
    if p.iter().all(|v| v.is_finite()) {
        if !p.iter().all(|v| crate::limits::coordinate_ok(*v)) {
            return Err(Error::invalid(
                path,
                field,
                format!(
                    "point {} is more than {} m from the origin; expected metres near the origin",
                    point(p[0], p[1]),
                    num(crate::limits::COORDINATE_LIMIT_M)
                ),
            ));
        }
        Ok(Vec2::new(p[0], p[1]))
    } else {
        Err(Error::invalid(
            path,
            field,
            format!("not a finite point: [{}, {}]; expected metres", p[0], p[1]),
        ))
    }
}

/// A closed ring of the file as an (implicitly closed) polygon: at least 3 distinct vertices,
/// an area, and no edges that cross, or repaired when they cross by a slip ([`crate::polygon`],
/// within the file's work budget; `name` names it in the repair's warning).
fn ring(
    pts: &[[f64; 2]],
    field: &str,
    name: &str,
    path: &Path,
    rings: &mut Rings,
) -> Result<Polygon, Error> {
    for (i, p) in pts.iter().enumerate() {
        vec2(*p, &format!("{field}[{i}]"), path)?;
    }
    let (Some(first), Some(last)) = (pts.first(), pts.last()) else {
        return Err(Error::invalid(
            path,
            field,
            "polygon has no vertices; expected a closed ring of at least 3 distinct vertices",
        ));
    };
    if first != last || pts.len() < 2 {
        return Err(Error::invalid(
            path,
            field,
            format!(
                "polygon is not closed (first vertex {} != last vertex {}); close the ring by repeating the first vertex",
                point(first[0], first[1]),
                point(last[0], last[1])
            ),
        ));
    }
    let open = &pts[..pts.len() - 1];
    // The distinct vertices in order (by value: 0.0 and -0.0 are one), in linear time: a ring
    // may have hundreds of thousands of vertices.
    let mut seen = std::collections::HashSet::with_capacity(open.len());
    let distinct: Vec<[f64; 2]> = open
        .iter()
        .filter(|p| seen.insert([(p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits()]))
        .copied()
        .collect();
    if distinct.len() < 3 {
        return Err(Error::invalid(
            path,
            field,
            format!(
                "polygon has {} distinct vertices; expected at least 3",
                distinct.len()
            ),
        ));
    }
    let poly = Polygon::new(open.iter().map(|p| Vec2::new(p[0], p[1])).collect());
    if poly.area_m2() <= 0.0 {
        let a = distinct[0];
        let b = distinct[1];
        let collinear = distinct.iter().all(|p| {
            let cross = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
            let len = |q: [f64; 2]| (q[0] - a[0]).hypot(q[1] - a[1]);
            cross.abs() <= 1e-9 * len(b) * len(*p)
        });
        return Err(Error::invalid(
            path,
            field,
            if collinear {
                "polygon has zero area (its vertices are collinear)"
            } else {
                "polygon has zero area: its edges cross each other (a figure-eight); list the vertices in order around the polygon"
            },
        ));
    }
    Ok(Polygon::new(rings.check(
        path,
        field,
        name,
        poly.vertices,
    )?))
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
format = "floorcast-building"
version = 1
name = "two-rooms"
outline = [[0.0, 0.0], [10.0, 0.0], [10.0, 6.0], [0.0, 6.0], [0.0, 0.0]]

[[walls]]
from = [0.0, 0.0]
to = [10.0, 0.0]
thickness = 0.2

[[walls]]
from = [5.0, 0.0]
to = [5.0, 2.5]
thickness = 0.2

[[solids]]
polygon = [[2.0, 2.0], [2.5, 2.0], [2.5, 2.5], [2.0, 2.0]]

[[rooms]]
id = 1
kind = "office"
polygon = [[0.0, 0.0], [5.0, 0.0], [5.0, 6.0], [0.0, 6.0], [0.0, 0.0]]

[[rooms]]
id = 2
polygon = [[5.0, 0.0], [10.0, 0.0], [10.0, 6.0], [5.0, 6.0], [5.0, 0.0]]

[[doors]]
from = [5.0, 2.5]
to = [5.0, 3.5]
rooms = [1, 2]

[[doors]]
from = [0.0, 1.0]
to = [0.0, 2.0]
rooms = [1]

[start]
x = 1.0
y = 1.0
theta_deg = 90.0
"#;

    fn parse(text: &str) -> Result<Building, String> {
        parse_building_toml(text, Path::new("buildings/x.toml")).map_err(|e| {
            let s = e.to_string();
            assert!(!s.contains('\n'), "{s}");
            assert!(s.starts_with("buildings/x.toml: "), "{s}");
            s
        })
    }

    fn bad(from: &str, to: &str) -> String {
        assert!(GOOD.contains(from), "{from}");
        parse(&GOOD.replacen(from, to, 1)).unwrap_err()
    }

    #[test]
    fn reads_a_full_file() {
        let b = parse(GOOD).unwrap();
        assert_eq!(b.name, "two-rooms");
        let Geometry::Vector { outline, solids } = &b.geometry else {
            panic!()
        };
        assert_eq!(outline.vertices.len(), 4);
        assert_eq!(solids.len(), 3);
        assert_eq!(
            solids[0],
            Polygon::thick_segment(Vec2::new(0.0, 0.0), Vec2::new(10.0, 0.0), 0.2)
        );
        assert_eq!(b.rooms[1].kind, "");
        assert_eq!(b.doors[0].rooms, [Some(1), Some(2)]);
        assert_eq!(b.doors[1].rooms, [Some(1), None]);
        let s = b.start.unwrap();
        assert_eq!((s.x_m, s.y_m), (1.0, 1.0));
        assert!((s.theta_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    }

    #[test]
    fn name_defaults_to_the_stem() {
        let b = parse(&GOOD.replace("name = \"two-rooms\"\n", "")).unwrap();
        assert_eq!(b.name, "x");
    }

    #[test]
    fn round_trip() {
        let mut b = parse(GOOD).unwrap();
        b.start = Some(Pose::new(1.0 / 3.0, 0.7, 0.123456789));
        let text = to_toml_string(&b).unwrap();
        assert!(
            text.contains("[[solids]]") && !text.contains("[[walls]]"),
            "{text}"
        );
        let back = parse(&text).unwrap();
        assert_eq!(back, b);
        // A heading in whole degrees is written as degrees.
        b.start = Some(Pose::new(1.0, 1.0, 90f64.to_radians()));
        let text = to_toml_string(&b).unwrap();
        assert!(text.contains("theta_deg = 90.0"), "{text}");
        assert_eq!(parse(&text).unwrap(), b);
        // And through a file.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("b.toml");
        write_building_toml(&b, &p).unwrap();
        assert_eq!(read_building_toml(&p).unwrap(), b);
    }

    #[test]
    fn raster_is_not_written() {
        let g = sim_core::OccupancyGrid::from_ascii("#.#", 1.0);
        let b = crate::map_server::building_from_map(&g, "r");
        let e = write_building_toml(&b, Path::new("out/r.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("out/r.toml: unsupported: a raster building"),
            "{e}"
        );
    }

    #[test]
    fn error_unknown_format() {
        let e = bad("format = \"floorcast-building\"", "format = \"house\"");
        assert!(
            e.contains("x.toml: format: unknown format \"house\""),
            "{e}"
        );
    }

    #[test]
    fn error_unknown_version() {
        let e = bad("version = 1", "version = 2");
        assert!(e.contains("x.toml: version: unsupported version 2"), "{e}");
    }

    #[test]
    fn error_unclosed_ring() {
        let e = bad(
            "polygon = [[2.0, 2.0], [2.5, 2.0], [2.5, 2.5], [2.0, 2.0]]",
            "polygon = [[0.0, 0.0], [2.5, 2.0], [4.0, 2.0]]",
        );
        assert!(
            e.contains("x.toml: solids[0].polygon: polygon is not closed (first vertex (0.0, 0.0) != last vertex (4.0, 2.0)); close the ring by repeating the first vertex"),
            "{e}"
        );
    }

    #[test]
    fn error_too_few_vertices() {
        let e = bad(
            "outline = [[0.0, 0.0], [10.0, 0.0], [10.0, 6.0], [0.0, 6.0], [0.0, 0.0]]",
            "outline = [[0.0, 0.0], [10.0, 0.0], [10.0, 0.0], [0.0, 0.0]]",
        );
        assert!(
            e.contains("x.toml: outline: polygon has 2 distinct vertices; expected at least 3"),
            "{e}"
        );
        // -0 is 0: one vertex.
        let e = bad(
            "outline = [[0.0, 0.0], [10.0, 0.0], [10.0, 6.0], [0.0, 6.0], [0.0, 0.0]]",
            "outline = [[0.0, 0.0], [-0.0, 0.0], [10.0, 0.0], [0.0, -0.0], [0.0, 0.0]]",
        );
        assert!(e.contains("polygon has 2 distinct vertices"), "{e}");
    }

    #[test]
    fn error_non_finite() {
        let e = bad("from = [5.0, 0.0]", "from = [nan, 0.0]");
        assert!(
            e.contains("x.toml: walls[1].from: not a finite point: [NaN, 0]"),
            "{e}"
        );
        let e = bad("[2.5, 2.5]", "[2.5, inf]");
        assert!(
            e.contains("x.toml: solids[0].polygon[2]: not a finite point"),
            "{e}"
        );
    }

    #[test]
    fn error_non_positive_thickness() {
        let e = bad("thickness = 0.2", "thickness = -0.2");
        assert!(
            e.contains("x.toml: walls[0].thickness: must be a positive number of metres up to 100.0, got -0.2"),
            "{e}"
        );
    }

    #[test]
    fn error_duplicate_room_ids() {
        let e = bad("id = 2", "id = 1");
        assert!(
            e.contains("x.toml: rooms[1].id: duplicate room id 1 (also rooms[0])"),
            "{e}"
        );
    }

    #[test]
    fn error_door_names_unknown_room() {
        let e = bad("rooms = [1, 2]", "rooms = [1, 7]");
        assert!(e.contains("x.toml: doors[0].rooms: unknown room id 7; expected one of the [[rooms]] ids (1, 2) or 0 for the outside"), "{e}");
    }

    #[test]
    fn error_start_outside_outline() {
        let e = bad("x = 1.0", "x = 11.0");
        assert!(
            e.contains("x.toml: start: start pose (11.0, 1.0) is outside the outline"),
            "{e}"
        );
    }

    #[test]
    fn error_start_inside_wall() {
        let e = bad("x = 1.0\ny = 1.0", "x = 3.0\ny = 0.05");
        assert!(
            e.contains("x.toml: start: start pose (3.0, 0.05) is inside a wall (walls[0])"),
            "{e}"
        );
        let e = bad("x = 1.0\ny = 1.0", "x = 2.4\ny = 2.1");
        assert!(
            e.contains("start pose (2.4, 2.1) is inside a solid (solids[0])"),
            "{e}"
        );
    }

    #[test]
    fn error_unknown_key() {
        let e = bad("thickness = 0.2", "thickness = 0.2\ncolour = \"red\"");
        assert!(e.contains("x.toml: line 11 column 1: unknown field `colour`, expected one of `from`, `to`, `thickness`"), "{e}");
        let e = bad("[start]", "[begin]");
        assert!(e.contains("unknown field `begin`"), "{e}");
    }

    #[test]
    fn error_bad_toml_and_wrong_types() {
        let e = parse("format = \"floorcast-building\"\nversion = 1\noutline = [[0.0, 0.0]")
            .unwrap_err();
        assert!(e.contains("x.toml: line 3 column"), "{e}");
        let e = bad("thickness = 0.2", "thickness = \"thin\"");
        assert!(
            e.contains("x.toml: line 10 column 13: invalid type: string \"thin\", expected f64"),
            "{e}"
        );
    }
}

#[cfg(test)]
mod doc_example {
    #[test]
    fn the_documented_example_parses() {
        let md = include_str!("../BUILDING_FORMAT.md");
        let start = md.find("```toml\n").unwrap() + "```toml\n".len();
        let len = md[start..].find("```").unwrap();
        let b = super::parse_building_toml(
            &md[start..start + len],
            std::path::Path::new("BUILDING_FORMAT.md"),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(b.name, "two-rooms");
        assert_eq!((b.rooms.len(), b.doors.len()), (2, 1));
        assert!(b.start.is_some());
    }
}
