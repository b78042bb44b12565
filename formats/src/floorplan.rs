//! Annotated floor plans in the KTH floor-plan XML schema (Aydemir et al., "What can we learn
//! from 38,000 rooms?", 2012), as the data set of Luperto et al. (`goldleaf3i/generativeCMLgraphs`)
//! writes them: a `<building>` with a `<scale>` (pixels per real distance) and `<floor><spaces>`,
//! each `<space>` a room (`labels/type` R), corridor (C) or entrance, stairs or elevator (E) with
//! a `labels/label`, a `bounding_polygon` and a `space_representation` of WALL and PORTAL line
//! segments; `portals` name the two spaces a door joins.
//!
//! The plan becomes a raster world at [`PLAN_RESOLUTION_M`]: free inside the spaces' polygons,
//! walls [`WALL_THICKNESS_M`] thick centred on every WALL segment, and a doorway
//! [`DOOR_WIDTH_M`] wide cut into the wall at every PORTAL (the data set's portals are points on
//! a wall that runs straight through them, with no width of their own). The spaces are the
//! ground-truth rooms (their labels, lower case, as the rooms' kinds), the portals its doors.
//! The start is the free point farthest from the walls in the largest corridor (the plans mark
//! no door to the outside; without a corridor, the largest space), heading 0. Pixel `y` grows
//! downwards in the plans: it is turned so that the plan is not mirrored. Spaces without a
//! polygon (some offices' untyped spaces) are left out, and so are portals to them.

use std::collections::HashMap;
use std::path::Path;

use sim_core::{Bitmap, Building, Door, Geometry, GridFrame, Polygon, Pose, Room, Vec2};

use crate::error::{num, Error};
use crate::limits;

/// Resolution of the raster a plan becomes.
pub const PLAN_RESOLUTION_M: f64 = 0.05;
/// Thickness of every wall (centred on its segment).
pub const WALL_THICKNESS_M: f64 = 0.15;
/// Width of the doorway cut at every portal.
pub const DOOR_WIDTH_M: f64 = 0.9;
/// How far on either side of its portal a doorway is cut: the two faces of one wall are drawn
/// apart in some plans (each space's own segment), a few pixels from each other.
pub const DOOR_DEPTH_M: f64 = 0.5;
/// Free space kept around a plan's spaces (solid).
const MARGIN_M: f64 = 1.0;
/// Most spaces, and points of one polygon, a plan may have.
const MAX_SPACES: usize = 10_000;
const MAX_POINTS: usize = 100_000;
/// Most line segments (walls and portals) and portals a plan may have (the vendored plans have
/// at most 785 and 168): every doorway is looked for among the walls.
const MAX_SEGMENTS: usize = 50_000;
const MAX_PORTALS: usize = 5_000;
/// Most cell visits drawing a plan may take, as a multiple of the cell budget: every space's
/// bounding box times its points (a point-in-polygon test per cell) and every wall's box (the
/// vendored plans need at most 1.2 budgets; overlapping spaces or long diagonal walls could need
/// thousands).
const MAX_DRAWING_BUDGETS: f64 = 16.0;
/// Most XML nodes parsed.
const MAX_NODES: u32 = 5_000_000;
/// Deepest nesting of elements read (the plans nest 8 deep); deeper is refused before parsing.
const MAX_DEPTH: usize = 64;
/// A start needs at least this clearance (m) from the walls.
const MIN_START_CLEARANCE_M: f64 = 0.3;

struct Space {
    /// The plan's id of the space (portals name it).
    #[allow(dead_code)]
    id: String,
    kind: String,
    polygon: Vec<Vec2>,
    walls: Vec<(Vec2, Vec2)>,
    /// Portals: the point, and the two spaces' ids it joins.
    portals: Vec<(Vec2, Vec<String>)>,
    /// Portals as read: the field, its line segment's id, the spaces it joins.
    portal_refs: Vec<(String, String, Vec<String>)>,
    corridor: bool,
}

/// Reads an annotated floor plan (`.xml`) as a building with its rooms and doors.
pub fn read_floorplan(path: &Path) -> Result<Building, Error> {
    let text = limits::read_text(path)?;
    if let Some((depth, at)) = nesting_beyond(&text, MAX_DEPTH) {
        let line = text[..at].matches('\n').count() + 1;
        let name: String = text[at..]
            .chars()
            .take_while(|c| !c.is_whitespace() && !matches!(c, '>' | '/'))
            .collect();
        return Err(Error::syntax(
            path,
            format!(
                "line {line}: element <{}> nested {depth} deep; expected elements nested at most {MAX_DEPTH} deep",
                short(&name)
            ),
        ));
    }
    let options = roxmltree::ParsingOptions {
        allow_dtd: false,
        nodes_limit: MAX_NODES,
    };
    let doc = roxmltree::Document::parse_with_options(&text, options)
        .map_err(|e| Error::syntax(path, xml_error(&e)))?;
    let root = doc.root_element();
    if root.tag_name().name() != "building" {
        return Err(Error::invalid(
            path,
            root.tag_name().name(),
            "expected a <building> root element (the KTH floor-plan schema)",
        ));
    }
    let metres_per_px = scale(path, root)?;
    let spaces_el = child(root, "floor")
        .and_then(|f| child(f, "spaces"))
        .ok_or_else(|| Error::invalid(path, "building/floor/spaces", "missing"))?;
    let mut spaces: Vec<Space> = Vec::new();
    let mut ids: HashMap<String, usize> = HashMap::new();
    // Every line segment by id: a portal may name one of the other space's.
    let mut segments: HashMap<String, (Vec2, Vec2)> = HashMap::new();
    let (mut n_segments, mut n_portals) = (0usize, 0usize);
    for (i, s) in children(spaces_el, "space").enumerate() {
        if i >= MAX_SPACES {
            return Err(Error::invalid(
                path,
                "building/floor/spaces",
                format!("more than {MAX_SPACES} spaces; expected at most {MAX_SPACES}"),
            ));
        }
        let field = format!("space[{i}]");
        let id = match s.attribute("id") {
            None => {
                return Err(Error::invalid(
                    path,
                    &field,
                    "no id attribute; expected one",
                ))
            }
            Some(v) if v.trim().is_empty() => {
                return Err(Error::invalid(path, &field, "an empty id; expected one"))
            }
            Some(v) => v.to_string(),
        };
        let field = format!("space[{i}] ({})", short(&id));
        let polygon = match child(s, "bounding_polygon") {
            Some(p) => points(path, &format!("{field}/bounding_polygon"), p, metres_per_px)?,
            None => Vec::new(),
        };
        let polygon = dedup_closed(polygon);
        if polygon.is_empty() {
            continue; // A space without a polygon (left out, as its portals).
        }
        if polygon.len() < 3 {
            return Err(Error::invalid(
                path,
                format!("{field}/bounding_polygon"),
                format!(
                    "{} distinct point{}; expected at least 3",
                    polygon.len(),
                    if polygon.len() == 1 { "" } else { "s" }
                ),
            ));
        }
        if Polygon::new(polygon.clone()).area_m2() < 0.01 {
            return Err(Error::invalid(
                path,
                format!("{field}/bounding_polygon"),
                "a polygon of zero area; expected a room's outline",
            ));
        }
        let labels = child(s, "labels");
        let kind_code = labels
            .and_then(|l| child(l, "type"))
            .and_then(|t| t.text())
            .unwrap_or("")
            .trim()
            .to_string();
        let label = labels
            .and_then(|l| child(l, "label"))
            .and_then(|t| t.text())
            .unwrap_or("")
            .trim()
            .to_lowercase();
        let mut walls = Vec::new();
        if let Some(rep) = child(s, "space_representation") {
            for (k, seg) in children(rep, "linesegment").enumerate() {
                let sf = format!("{field}/space_representation/linesegment[{k}]");
                n_segments += 1;
                if n_segments > MAX_SEGMENTS {
                    return Err(Error::invalid(
                        path,
                        sf,
                        format!("more than {MAX_SEGMENTS} line segments in the plan; expected at most {MAX_SEGMENTS}"),
                    ));
                }
                let pts = points(path, &sf, seg, metres_per_px)?;
                if pts.len() != 2 {
                    return Err(Error::invalid(
                        path,
                        sf,
                        format!("{} points; expected 2", pts.len()),
                    ));
                }
                let class = child(seg, "class").and_then(|c| c.text()).unwrap_or("");
                match class.trim() {
                    "WALL" => walls.push((pts[0], pts[1])),
                    "PORTAL" => {}
                    other => {
                        return Err(Error::invalid(
                            path,
                            format!("{sf}/class"),
                            format!("'{}'; expected WALL or PORTAL", short(other)),
                        ))
                    }
                }
                if let Some(sid) = seg.attribute("id") {
                    segments.insert(sid.to_string(), (pts[0], pts[1]));
                }
            }
        }
        let mut portal_refs = Vec::new();
        if let Some(ps) = child(s, "portals") {
            for (k, p) in children(ps, "portal").enumerate() {
                let pf = format!("{field}/portals/portal[{k}]");
                n_portals += 1;
                if n_portals > MAX_PORTALS {
                    return Err(Error::invalid(
                        path,
                        pf,
                        format!("more than {MAX_PORTALS} portals in the plan; expected at most {MAX_PORTALS}"),
                    ));
                }
                let seg_id = child(p, "linesegment")
                    .and_then(|l| l.text())
                    .unwrap_or("")
                    .trim()
                    .to_string();
                if seg_id.is_empty() {
                    return Err(Error::invalid(
                        path,
                        format!("{pf}/linesegment"),
                        "missing or empty; expected the id of the portal's line segment",
                    ));
                }
                let targets: Vec<String> = child(p, "target")
                    .map(|t| {
                        children(t, "id")
                            .filter_map(|i| i.text())
                            .map(|i| i.trim().to_string())
                            .collect()
                    })
                    .unwrap_or_default();
                if targets.is_empty() || targets.len() > 2 {
                    return Err(Error::invalid(
                        path,
                        format!("{pf}/target"),
                        format!("{} spaces; expected the one or two it joins", targets.len()),
                    ));
                }
                portal_refs.push((pf, seg_id, targets));
            }
        }
        if ids.insert(id.clone(), spaces.len()).is_some() {
            return Err(Error::invalid(
                path,
                field,
                "an id used by another space; expected unique ids",
            ));
        }
        spaces.push(Space {
            id,
            corridor: kind_code == "C",
            kind: if label.is_empty() {
                match kind_code.as_str() {
                    "C" => "corridor".into(),
                    "E" => "entrance".into(),
                    _ => "room".into(),
                }
            } else {
                label
            },
            polygon,
            walls,
            portals: Vec::new(),
            portal_refs,
        });
    }
    if spaces.is_empty() {
        return Err(Error::invalid(
            path,
            "building/floor/spaces",
            "no space with a polygon; expected the rooms of a floor",
        ));
    }
    // Every portal's spaces must exist (one without a polygon is left out with its portals).
    let all_ids: std::collections::HashSet<&str> = children(spaces_el, "space")
        .filter_map(|s| s.attribute("id"))
        .collect();
    for (field, _, targets) in spaces.iter().flat_map(|s| &s.portal_refs) {
        if let Some(t) = targets.iter().find(|t| !all_ids.contains(t.as_str())) {
            return Err(Error::invalid(
                path,
                format!("{field}/target"),
                format!(
                    "space '{}', which the plan does not have; expected the ids of the spaces the portal joins",
                    short(t)
                ),
            ));
        }
    }
    for s in &mut spaces {
        for (field, seg_id, targets) in std::mem::take(&mut s.portal_refs) {
            let (a, b) = *segments.get(&seg_id).ok_or_else(|| {
                Error::invalid(
                    path,
                    format!("{field}/linesegment"),
                    format!("'{}' is not a line segment of the plan", short(&seg_id)),
                )
            })?;
            s.portals.push(((a + b) * 0.5, targets));
        }
    }
    check_drawing(path, &spaces)?;
    build(path, &spaces, &ids)
}

/// A parser's error as a message: what was found, where, and what was expected.
fn xml_error(e: &roxmltree::Error) -> String {
    use roxmltree::Error as E;
    match e {
        E::DtdDetected => "a DTD (<!DOCTYPE ...>), which is not read (its entities could expand without bound); expected a floor plan without one".into(),
        E::NodesLimitReached => format!(
            "more than {MAX_NODES} XML nodes; expected a floor plan's (the vendored plans have fewer than 10000 elements)"
        ),
        E::NoRootNode => "not a well-formed XML floor plan: no element; expected a <building> element (the KTH floor-plan schema)".into(),
        E::UnclosedRootNode | E::UnexpectedEndOfStream => format!(
            "not a well-formed XML floor plan: {e} (is the file cut short?); expected it to end with </building>"
        ),
        _ => format!("not a well-formed XML floor plan: {e}"),
    }
}

/// The nesting reached when it first passes `max` and the byte offset of the element's name
/// there (a scan of the tags, quotes aside: enough to refuse what the parser would recurse on
/// too deeply), or `None`.
fn nesting_beyond(text: &str, max: usize) -> Option<(usize, usize)> {
    let bytes = text.as_bytes();
    let mut depth = 0usize;
    let mut i = 0;
    while let Some(off) = bytes[i..].iter().position(|&b| b == b'<') {
        i += off + 1;
        match bytes.get(i) {
            Some(b'/') => depth = depth.saturating_sub(1),
            Some(b'?') | Some(b'!') | None => {}
            Some(_) => {
                let end = bytes[i..].iter().position(|&b| b == b'>').map(|e| i + e);
                if end.is_some_and(|e| e > 0 && bytes[e - 1] == b'/') {
                    continue;
                }
                depth += 1;
                if depth > max {
                    return Some((depth, i));
                }
            }
        }
    }
    None
}

/// Metres per pixel from `<scale>`.
fn scale(path: &Path, root: roxmltree::Node<'_, '_>) -> Result<f64, Error> {
    let sc = child(root, "scale").ok_or_else(|| Error::invalid(path, "scale", "missing"))?;
    let value = |what: &str| -> Result<(f64, String), Error> {
        let el = child(sc, what)
            .ok_or_else(|| Error::invalid(path, format!("scale/{what}"), "missing"))?;
        let text = child(el, "value")
            .and_then(|v| v.text())
            .unwrap_or("")
            .trim();
        let v = text
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v > 0.0)
            .ok_or_else(|| {
                Error::invalid(
                    path,
                    format!("scale/{what}/value"),
                    format!("{}; expected a positive number", found(text)),
                )
            })?;
        let um = child(el, "um")
            .and_then(|u| u.text())
            .unwrap_or("")
            .trim()
            .to_string();
        Ok((v, um))
    };
    let (px, px_unit) = value("represented_distance")?;
    if px_unit != "pixel" {
        return Err(Error::invalid(
            path,
            "scale/represented_distance/um",
            format!("'{}'; expected pixel", short(&px_unit)),
        ));
    }
    let (real, unit) = value("real_distance")?;
    let metres = match unit.as_str() {
        "mm" => real / 1000.0,
        "cm" => real / 100.0,
        "m" => real,
        other => {
            return Err(Error::invalid(
                path,
                "scale/real_distance/um",
                format!("'{}'; expected mm, cm or m", short(other)),
            ))
        }
    };
    let mpp = metres / px;
    if !(0.001..=1.0).contains(&mpp) {
        return Err(Error::invalid(
            path,
            "scale",
            format!(
                "{} m per pixel; expected 0.001 to 1 (is the real distance's unit right?)",
                num(mpp)
            ),
        ));
    }
    Ok(mpp)
}

/// The `<point x= y=>` children of `el`, in metres (`y` turned upwards).
fn points(
    path: &Path,
    field: &str,
    el: roxmltree::Node<'_, '_>,
    mpp: f64,
) -> Result<Vec<Vec2>, Error> {
    let mut out = Vec::new();
    for (k, p) in children(el, "point").enumerate() {
        if k >= MAX_POINTS {
            return Err(Error::invalid(
                path,
                field,
                format!("more than {MAX_POINTS} points"),
            ));
        }
        let coord = |a: &str| -> Result<f64, Error> {
            let text = p.attribute(a).unwrap_or("").trim();
            text.parse::<f64>()
                .ok()
                .map(|v| v * mpp)
                .filter(|v| limits::coordinate_ok(*v))
                .ok_or_else(|| {
                    Error::invalid(
                        path,
                        format!("{field}/point[{k}]/{a}"),
                        format!(
                            "{}; expected a number of pixels within {} m of the origin at this scale",
                            found(text),
                            num(limits::COORDINATE_LIMIT_M)
                        ),
                    )
                })
        };
        out.push(Vec2::new(coord("x")?, -coord("y")?));
    }
    Ok(out)
}

/// The polygon without its closing repeat and repeated points.
fn dedup_closed(mut pts: Vec<Vec2>) -> Vec<Vec2> {
    pts.dedup_by(|a, b| (*a - *b).norm() < 1e-9);
    while pts.len() > 1 && (pts[0] - pts[pts.len() - 1]).norm() < 1e-9 {
        pts.pop();
    }
    pts
}

fn child<'a, 'i>(n: roxmltree::Node<'a, 'i>, name: &str) -> Option<roxmltree::Node<'a, 'i>> {
    n.children().find(|c| c.has_tag_name(name))
}

fn children<'a, 'i: 'a>(
    n: roxmltree::Node<'a, 'i>,
    name: &'a str,
) -> impl Iterator<Item = roxmltree::Node<'a, 'i>> + 'a {
    n.children().filter(move |c| c.has_tag_name(name))
}

/// Most characters of outside text a message quotes.
const EXCERPT_CHARS: usize = 80;

/// Outside text as a message quotes it (the project's rule, `floorcast_worker::text::excerpt`):
/// control characters escaped, at most [`EXCERPT_CHARS`] characters, a longer text cut with
/// "..." and its length.
fn short(s: &str) -> String {
    let escaped = |s: &str| -> String {
        s.chars()
            .map(|c| match c {
                '\n' => "\\n".to_string(),
                '\r' => "\\r".to_string(),
                '\t' => "\\t".to_string(),
                c if c.is_control() && (c as u32) < 0x100 => format!("\\x{:02x}", c as u32),
                c => c.to_string(),
            })
            .collect()
    };
    match s.char_indices().nth(EXCERPT_CHARS) {
        None => escaped(s),
        Some((cut, _)) => format!(
            "{}... ({} characters in all)",
            escaped(&s[..cut]),
            s.chars().count()
        ),
    }
}

/// What a value's text was, for a message: "missing" or "got '...'".
fn found(text: &str) -> String {
    if text.is_empty() {
        "missing".into()
    } else {
        format!("got '{}'", short(text))
    }
}

/// Refuses a plan whose drawing would take more than [`MAX_DRAWING_BUDGETS`] cell budgets of
/// work (see there), before anything is drawn.
fn check_drawing(path: &Path, spaces: &[Space]) -> Result<(), Error> {
    let cells = |w: f64, h: f64| limits::cells_for(w.max(0.0), h.max(0.0), PLAN_RESOLUTION_M);
    let bounds_of = |pts: &mut dyn Iterator<Item = &Vec2>| {
        let mut b = sim_core::Aabb::empty();
        pts.for_each(|p| b.grow(*p));
        b
    };
    let all = bounds_of(&mut spaces.iter().flat_map(|s| s.polygon.iter()));
    let (w, h) = (
        all.width_m() + 2.0 * MARGIN_M,
        all.height_m() + 2.0 * MARGIN_M,
    );
    if cells(w, h) > limits::max_cells() as f64 {
        return Ok(()); // Refused for its extent, which `build` names.
    }
    let mut work = 0.0;
    for s in spaces {
        let b = bounds_of(&mut s.polygon.iter());
        work += cells(b.width_m(), b.height_m()) * s.polygon.len() as f64;
        // A wall's box, within the plan's (the raster ends there).
        for &(a, z) in &s.walls {
            let h = WALL_THICKNESS_M + MARGIN_M;
            let w = a.x.max(z.x).min(all.max.x + h) - a.x.min(z.x).max(all.min.x - h);
            let t = a.y.max(z.y).min(all.max.y + h) - a.y.min(z.y).max(all.min.y - h);
            work += cells(w + WALL_THICKNESS_M, t + WALL_THICKNESS_M);
        }
    }
    let most = MAX_DRAWING_BUDGETS * limits::max_cells() as f64;
    if work <= most {
        return Ok(());
    }
    Err(Error::invalid(
        path,
        "floor/spaces",
        format!(
            "drawing the spaces (overlapping, or with long diagonal walls) would visit {work:.3e} cells, more than {} times the budget of {} cells; expected spaces side by side, or raise the budget with {}",
            num(MAX_DRAWING_BUDGETS),
            limits::max_cells(),
            limits::MAX_CELLS_FLAG
        ),
    ))
}

/// A doorway: its centre, the direction of its wall, and the rooms it joins.
struct Opening {
    centre: Vec2,
    along: Option<Vec2>,
    rooms: [Option<u32>; 2],
}

fn build(path: &Path, spaces: &[Space], ids: &HashMap<String, usize>) -> Result<Building, Error> {
    let mut bounds = sim_core::Aabb::empty();
    for s in spaces {
        for p in &s.polygon {
            bounds.grow(*p);
        }
    }
    limits::check_cells(
        path,
        "floor",
        limits::cells_for(
            bounds.width_m() + 2.0 * MARGIN_M,
            bounds.height_m() + 2.0 * MARGIN_M,
            PLAN_RESOLUTION_M,
        ),
        &format!(
            "the plan spans {} x {} m; drawn at {} m",
            num((bounds.width_m() * 100.0).round() / 100.0),
            num((bounds.height_m() * 100.0).round() / 100.0),
            num(PLAN_RESOLUTION_M)
        ),
    )?;
    let frame = GridFrame::covering(&bounds, PLAN_RESOLUTION_M, MARGIN_M);
    let mut free = Bitmap::filled(frame, false);
    for s in spaces {
        let poly = Polygon::new(s.polygon.clone());
        for_cells_in(&frame, &poly.aabb(), |c, p| {
            if poly.contains(p) {
                free.set(c, true);
            }
        });
    }
    // The doorways, each once (a portal appears in both spaces it joins).
    let mut openings: Vec<Opening> = Vec::new();
    for s in spaces {
        for (centre, targets) in &s.portals {
            let rooms = [
                targets.first().and_then(|t| ids.get(t)).map(|&i| i as u32),
                targets.get(1).and_then(|t| ids.get(t)).map(|&i| i as u32),
            ];
            if rooms.iter().all(Option::is_none) {
                continue;
            }
            if openings
                .iter()
                .any(|o| (o.centre - *centre).norm() < 0.05 && same_rooms(o.rooms, rooms))
            {
                continue;
            }
            let along = door_direction(s, spaces, *centre);
            openings.push(Opening {
                centre: *centre,
                along,
                rooms,
            });
        }
    }
    // The doorways' passages (between two faces of a wall drawn apart, outside both spaces).
    for o in &openings {
        let Some(u) = o.along else { continue };
        let reach = DOOR_WIDTH_M / 2.0 + DOOR_DEPTH_M;
        let area = sim_core::Aabb {
            min: o.centre - Vec2::new(reach, reach),
            max: o.centre + Vec2::new(reach, reach),
        };
        for_cells_in(&frame, &area, |c, p| {
            let d = p - o.centre;
            if (d.x * u.x + d.y * u.y).abs() <= DOOR_WIDTH_M / 2.0
                && (d.x * u.y - d.y * u.x).abs() <= DOOR_DEPTH_M
            {
                free.set(c, true);
            }
        });
    }
    // The walls, but where a doorway crosses them (a wall along the doorway's, within its
    // depth; walls across it stay).
    let half = WALL_THICKNESS_M / 2.0;
    for s in spaces {
        for &(a, b) in &s.walls {
            let len = (b - a).norm();
            let seg = sim_core::Segment::new(a, b);
            let u = if len > 1e-9 {
                (b - a) / len
            } else {
                Vec2::new(1.0, 0.0)
            };
            let doors: Vec<&Opening> = openings
                .iter()
                .filter(|o| {
                    o.along.is_some_and(|d| (d.x * u.y - d.y * u.x).abs() < 0.2)
                        && seg.distance_to(o.centre) <= DOOR_DEPTH_M
                })
                .collect();
            let band = Polygon::thick_segment(a, b, WALL_THICKNESS_M);
            for_cells_in(&frame, &band.aabb(), |c, p| {
                if seg.distance_to(p) > half {
                    return;
                }
                let in_door = doors.iter().any(|o| {
                    ((p - o.centre).x * u.x + (p - o.centre).y * u.y).abs() <= DOOR_WIDTH_M / 2.0
                });
                if !in_door {
                    free.set(c, false);
                }
            });
        }
    }
    let solid = Bitmap {
        frame,
        data: free.data.iter().map(|f| !f).collect(),
    };
    let rooms: Vec<Room> = spaces
        .iter()
        .enumerate()
        .map(|(i, s)| Room {
            id: i as u32,
            kind: s.kind.clone(),
            polygon: Polygon::new(s.polygon.clone()),
        })
        .collect();
    let doors: Vec<Door> = openings
        .iter()
        .map(|o| {
            let d = o.along.unwrap_or(Vec2::new(1.0, 0.0)) * (DOOR_WIDTH_M / 2.0);
            Door {
                a: o.centre - d,
                b: o.centre + d,
                rooms: o.rooms,
            }
        })
        .collect();
    let start = start_in(spaces, &solid);
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    Ok(Building {
        name,
        geometry: Geometry::Raster { solid },
        rooms,
        doors,
        start,
    })
}

/// The direction of the wall a portal at `centre` opens: that of the space's own wall segments
/// that end there (the plans split a wall at its portals), a straight pair first; else that of
/// any wall through it; `None` for a portal in no wall.
fn door_direction(space: &Space, spaces: &[Space], centre: Vec2) -> Option<Vec2> {
    let unit = |(a, b): &(Vec2, Vec2)| {
        let d = *b - *a;
        (d.norm() > 1e-6).then(|| d / d.norm())
    };
    let ending: Vec<Vec2> = space
        .walls
        .iter()
        .filter(|(a, b)| (*a - centre).norm() < 0.01 || (*b - centre).norm() < 0.01)
        .filter_map(unit)
        .collect();
    for (i, u) in ending.iter().enumerate() {
        if ending[i + 1..]
            .iter()
            .any(|v| (u.x * v.y - u.y * v.x).abs() < 0.1)
        {
            return Some(*u);
        }
    }
    if let Some(u) = ending.first() {
        return Some(*u);
    }
    spaces
        .iter()
        .flat_map(|o| o.walls.iter())
        .filter(|(a, b)| sim_core::Segment::new(*a, *b).distance_to(centre) < 0.01)
        .find_map(unit)
}

fn same_rooms(a: [Option<u32>; 2], b: [Option<u32>; 2]) -> bool {
    a == b || a == [b[1], b[0]]
}

/// Calls `f` with every cell of `frame` whose centre lies in `aabb`, and that centre.
fn for_cells_in(frame: &GridFrame, aabb: &sim_core::Aabb, mut f: impl FnMut(sim_core::Cell, Vec2)) {
    let lo = frame.cell_from_world(aabb.min);
    let hi = frame.cell_from_world(aabb.max);
    for y in lo.y.max(0)..=hi.y.min(frame.height as i32 - 1) {
        for x in lo.x.max(0)..=hi.x.min(frame.width as i32 - 1) {
            let c = sim_core::Cell::new(x, y);
            f(c, frame.world_from_cell(c));
        }
    }
}

/// The free cell farthest from the walls in the largest corridor (else the largest space),
/// lowest cell first among equals; `None` when none has [`MIN_START_CLEARANCE_M`].
fn start_in(spaces: &[Space], solid: &Bitmap) -> Option<Pose> {
    let area = |s: &Space| Polygon::new(s.polygon.clone()).area_m2();
    let pick = spaces
        .iter()
        .filter(|s| s.corridor)
        .max_by(|a, b| area(a).total_cmp(&area(b)))
        .or_else(|| spaces.iter().max_by(|a, b| area(a).total_cmp(&area(b))))?;
    let clearance = sim_core::distance::distance_to(solid);
    let poly = Polygon::new(pick.polygon.clone());
    let mut best: Option<(f32, sim_core::Cell)> = None;
    for_cells_in(&solid.frame, &poly.aabb(), |c, p| {
        let Some(&d) = clearance.get(c) else { return };
        if poly.contains(p) && best.is_none_or(|(bd, _)| d > bd) {
            best = Some((d, c));
        }
    });
    let (d, c) = best?;
    if f64::from(d) * solid.frame.resolution_m < MIN_START_CLEARANCE_M {
        return None;
    }
    let p = solid.frame.world_from_cell(c);
    Some(Pose::new(p.x, p.y, 0.0))
}
