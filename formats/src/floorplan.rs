//! Annotated floor plans in the KTH floor-plan XML schema (Aydemir et al., "What can we learn
//! from 38,000 rooms?", 2012), as the data set of Luperto et al. (`goldleaf3i/generativeCMLgraphs`)
//! writes them: a `<building>` with a `<scale>` (pixels per real distance) and `<floor><spaces>`,
//! each `<space>` a room (`labels/type` R), corridor (C) or entrance, stairs or elevator (E) with
//! a `labels/label`, a `bounding_polygon` and a `space_representation` of WALL and PORTAL line
//! segments; `portals` name the two spaces a door joins.
//!
//! The plan becomes a raster world at [`PLAN_RESOLUTION_M`]: free inside the spaces' polygons,
//! walls [`WALL_THICKNESS_M`] thick centred on every WALL segment, and a doorway cut through
//! the walls at every PORTAL. The data set's portals have no width: each is a point on a wall
//! that runs straight through it (some plans mark a door's two ends, one in each space's
//! copy of the portal). The doorway lies along the stretch of wall the two spaces share nearest
//! that point: [`DOOR_WIDTH_M`] wide (as wide as the two ends are apart, up to 2.5 m), slid
//! along the wall when the point is near a corner so that the walls across stay whole; between
//! two corridors (type C: corridors, halls, lobbies; not the washrooms the data set types C too)
//! the whole shared stretch is open. It reaches from one space's outline to the
//! other's (some plans draw a wall's two faces apart) and 0.2 m beyond. A portal whose line
//! segment no space has is placed midway along the longest stretch of wall its spaces share.
//! The spaces are the ground-truth rooms (their labels, lower case, as the rooms' kinds), the
//! doorways its doors. The start is the free point farthest from the walls in the largest
//! entrance space (the plans mark no door to the outside; the paper starts at the entrance),
//! else in the largest corridor, else in the largest space, heading 0. Pixel `y` grows
//! downwards in the plans: it is turned so that the plan is not mirrored. Spaces without a
//! polygon (some offices' untyped spaces), or whose polygon is one point repeated (spaces left
//! empty), are left out, and so are portals to them. A space's polygon must have an area and
//! no edges that cross; the data set's repeated points and walls traced twice are not
//! crossings, and a polygon crossing itself by an annotator's slip (one corner clicked past its
//! neighbour edge: 2 of the data set's 70 plans) is repaired with a warning naming the space
//! ([`crate::polygon`]), refused beyond the tolerance or under `--strict`.

use std::collections::HashMap;
use std::path::Path;

use sim_core::{Bitmap, Building, Door, Geometry, GridFrame, Polygon, Pose, Room, Vec2};

use crate::error::{num, Error};
use crate::limits;
use crate::polygon::{LoadOptions, Rings};
use crate::Loaded;

/// Resolution of the raster a plan becomes.
pub const PLAN_RESOLUTION_M: f64 = 0.05;
/// Thickness of every wall (centred on its segment).
pub const WALL_THICKNESS_M: f64 = 0.15;
/// Width of the doorway cut at every portal.
pub const DOOR_WIDTH_M: f64 = 0.9;
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
/// Labels of spaces that the data set types C (connective) but that are rooms behind a door.
const ROOMS_TYPED_C: &[&str] = &["washroom", "toilet", "bathroom", "restroom", "wc"];
/// A start needs at least this clearance (m) from the walls.
const MIN_START_CLEARANCE_M: f64 = 0.3;

struct Space {
    /// The plan's id of the space (portals name it).
    id: String,
    kind: String,
    polygon: Vec<Vec2>,
    walls: Vec<(Vec2, Vec2)>,
    /// Its line segments by id (a portal's point is the one its own space gives).
    segments: HashMap<String, (Vec2, Vec2)>,
    /// Portals: the field, the line segment's id, its point (`None` when no space has that
    /// line segment), and the two spaces' ids it joins.
    portals: Vec<(String, String, Option<Vec2>, Vec<String>)>,
    /// Portals as read: the field, its line segment's id, the spaces it joins.
    portal_refs: Vec<(String, String, Vec<String>)>,
    corridor: bool,
}

/// Reads an annotated floor plan (`.xml`) as a building with its rooms and doors; a space's
/// polygon whose edges cross by a slip is repaired ([`crate::polygon`]) and the warning dropped
/// (see [`read_floorplan_with`]).
pub fn read_floorplan(path: &Path) -> Result<Building, Error> {
    read_floorplan_with(path, LoadOptions::default()).map(|l| l.building)
}

/// Reads an annotated floor plan (`.xml`) as a building with its rooms and doors, with the
/// warnings of the polygons repaired ([`crate::polygon`]; refused instead under
/// `load.strict`).
pub fn read_floorplan_with(path: &Path, load: LoadOptions) -> Result<Loaded, Error> {
    let text = limits::read_text(path)?;
    check_nesting(path, &text)?;
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
    let mut reader = SpaceReader {
        path,
        metres_per_px,
        segments: HashMap::new(),
        n_segments: 0,
        n_portals: 0,
        rings: Rings::new(load),
    };
    let mut spaces: Vec<Space> = Vec::new();
    let mut ids: HashMap<String, usize> = HashMap::new();
    for (i, s) in children(spaces_el, "space").enumerate() {
        if i >= MAX_SPACES {
            return Err(Error::invalid(
                path,
                "building/floor/spaces",
                format!("more than {MAX_SPACES} spaces; expected at most {MAX_SPACES}"),
            ));
        }
        let Some(space) = reader.space(i, s)? else {
            continue;
        };
        if ids.insert(space.id.clone(), spaces.len()).is_some() {
            return Err(Error::invalid(
                path,
                format!("space[{i}] ({})", short(&space.id)),
                "an id used by another space; expected unique ids",
            ));
        }
        spaces.push(space);
    }
    if spaces.is_empty() {
        return Err(Error::invalid(
            path,
            "building/floor/spaces",
            "no space with a polygon; expected the rooms of a floor",
        ));
    }
    resolve_portals(path, spaces_el, &mut spaces, &reader.segments)?;
    check_drawing(path, &spaces)?;
    let portals = portals(path, &spaces, &ids)?;
    let building = build(path, &spaces, &portals)?;
    Ok(Loaded {
        building,
        warnings: reader.rings.warnings,
    })
}

/// Refuses elements nested deeper than [`MAX_DEPTH`], before parsing, naming the line.
fn check_nesting(path: &Path, text: &str) -> Result<(), Error> {
    let Some((depth, at)) = nesting_beyond(text, MAX_DEPTH) else {
        return Ok(());
    };
    let line = text[..at].matches('\n').count() + 1;
    let name: String = text[at..]
        .chars()
        .take_while(|c| !c.is_whitespace() && !matches!(c, '>' | '/'))
        .collect();
    Err(Error::syntax(
        path,
        format!(
            "line {line}: element <{}> nested {depth} deep; expected elements nested at most {MAX_DEPTH} deep",
            short(&name)
        ),
    ))
}

/// Every portal's spaces must exist (one without a polygon is left out with its portals); each
/// portal gets its point: its own space's line segment, else another space's of that id.
fn resolve_portals(
    path: &Path,
    spaces_el: roxmltree::Node,
    spaces: &mut [Space],
    segments: &HashMap<String, (Vec2, Vec2)>,
) -> Result<(), Error> {
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
    for s in spaces {
        for (field, seg_id, targets) in std::mem::take(&mut s.portal_refs) {
            let point = s
                .segments
                .get(&seg_id)
                .or(segments.get(&seg_id))
                .map(|(a, b)| (*a + *b) * 0.5);
            s.portals.push((field, seg_id, point, targets));
        }
    }
    Ok(())
}

/// Reads the plan's spaces one by one, counting its line segments and portals against their
/// limits and keeping every line segment by id (a portal may name one of another space's).
struct SpaceReader<'a> {
    path: &'a Path,
    metres_per_px: f64,
    segments: HashMap<String, (Vec2, Vec2)>,
    n_segments: usize,
    n_portals: usize,
    /// The checks of the spaces' outlines for crossings (the plan's work budget), and the
    /// warnings of those repaired.
    rings: Rings,
}

impl SpaceReader<'_> {
    /// The `i`-th `<space>`, or `None` for one without a polygon, or with every point of it the
    /// same (the data set's spaces left empty, area -1): left out, as its portals.
    fn space(&mut self, i: usize, s: roxmltree::Node) -> Result<Option<Space>, Error> {
        let path = self.path;
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
            Some(p) => points(
                path,
                &format!("{field}/bounding_polygon"),
                p,
                self.metres_per_px,
            )?,
            None => Vec::new(),
        };
        let polygon = dedup_closed(polygon);
        if polygon.len() <= 1 {
            return Ok(None);
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
        let name = format!(
            "the {} (type {})",
            if label.is_empty() {
                "space".to_string()
            } else {
                format!("'{}'", short(&label))
            },
            if kind_code.is_empty() {
                "none".to_string()
            } else {
                short(&kind_code)
            }
        );
        let polygon = check_outline(path, &field, &name, polygon, &mut self.rings)?;
        let (walls, own) = match child(s, "space_representation") {
            Some(rep) => self.segments_of(&field, rep)?,
            None => (Vec::new(), HashMap::new()),
        };
        let portal_refs = match child(s, "portals") {
            Some(ps) => self.portal_refs(&field, ps)?,
            None => Vec::new(),
        };
        Ok(Some(Space {
            id,
            // Type C is the data set's connective space (corridors, halls, lobbies), but it
            // types washrooms C too: those keep their doors.
            corridor: kind_code == "C" && !ROOMS_TYPED_C.contains(&label.as_str()),
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
            segments: own,
            portals: Vec::new(),
            portal_refs,
        }))
    }

    /// A space's line segments: its walls, and its segments by id.
    #[allow(clippy::type_complexity)]
    fn segments_of(
        &mut self,
        field: &str,
        rep: roxmltree::Node,
    ) -> Result<(Vec<(Vec2, Vec2)>, HashMap<String, (Vec2, Vec2)>), Error> {
        let path = self.path;
        let mut walls = Vec::new();
        let mut own = HashMap::new();
        for (k, seg) in children(rep, "linesegment").enumerate() {
            let sf = format!("{field}/space_representation/linesegment[{k}]");
            self.n_segments += 1;
            if self.n_segments > MAX_SEGMENTS {
                return Err(Error::invalid(
                    path,
                    sf,
                    format!("more than {MAX_SEGMENTS} line segments in the plan; expected at most {MAX_SEGMENTS}"),
                ));
            }
            let pts = points(path, &sf, seg, self.metres_per_px)?;
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
                self.segments.insert(sid.to_string(), (pts[0], pts[1]));
                own.insert(sid.to_string(), (pts[0], pts[1]));
            }
        }
        Ok((walls, own))
    }

    /// A space's portals as read: the field, the line segment's id, the spaces it joins.
    fn portal_refs(
        &mut self,
        field: &str,
        ps: roxmltree::Node,
    ) -> Result<Vec<(String, String, Vec<String>)>, Error> {
        let path = self.path;
        let mut refs = Vec::new();
        for (k, p) in children(ps, "portal").enumerate() {
            let pf = format!("{field}/portals/portal[{k}]");
            self.n_portals += 1;
            if self.n_portals > MAX_PORTALS {
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
            refs.push((pf, seg_id, targets));
        }
        Ok(refs)
    }
}

/// A space's outline has at least three distinct points and an area, and its edges do not cross
/// or cross by a slip, repaired ([`crate::polygon`], within the plan's work budget): the outline
/// as it is, or repaired; `name` names the space in a repair's warning.
fn check_outline(
    path: &Path,
    field: &str,
    name: &str,
    polygon: Vec<Vec2>,
    rings: &mut Rings,
) -> Result<Vec<Vec2>, Error> {
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
    if Polygon::new(polygon.to_vec()).area_m2() < 0.01 {
        return Err(Error::invalid(
            path,
            format!("{field}/bounding_polygon"),
            "a polygon of zero area; expected a room's outline",
        ));
    }
    rings.check(path, &format!("{field}/bounding_polygon"), name, polygon)
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

/// A portal as the spaces give it: the points its spaces mark (a door's two ends in some
/// plans, one point in most), and the rooms it joins.
struct Portal {
    segment: String,
    points: Vec<Vec2>,
    rooms: [Option<u32>; 2],
}

/// A doorway cut into the walls: a rectangle `half_width` either side of `centre` along `u`,
/// from `across.0` to `across.1` along the normal (it spans the wall, or the gap between the
/// two spaces' outlines where a plan draws a wall's two faces apart).
struct Doorway {
    centre: Vec2,
    u: Vec2,
    half_width: f64,
    across: (f64, f64),
    rooms: [Option<u32>; 2],
}

impl Doorway {
    fn contains(&self, p: Vec2) -> bool {
        let d = p - self.centre;
        let n = Vec2::new(-self.u.y, self.u.x);
        d.dot(&self.u).abs() <= self.half_width
            && (self.across.0..=self.across.1).contains(&d.dot(&n))
    }

    fn aabb(&self) -> sim_core::Aabb {
        let r = self.half_width + self.across.0.abs().max(self.across.1.abs());
        sim_core::Aabb {
            min: self.centre - Vec2::new(r, r),
            max: self.centre + Vec2::new(r, r),
        }
    }

    /// The door as the building records it: across the doorway, midway through the wall.
    fn door(&self) -> Door {
        let n = Vec2::new(-self.u.y, self.u.x);
        let mid = self.centre + n * ((self.across.0 + self.across.1) / 2.0);
        Door {
            a: mid - self.u * self.half_width,
            b: mid + self.u * self.half_width,
            rooms: self.rooms,
        }
    }
}

fn build(path: &Path, spaces: &[Space], portals: &[Portal]) -> Result<Building, Error> {
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
    let half = WALL_THICKNESS_M / 2.0;
    for s in spaces {
        for &(a, b) in &s.walls {
            let seg = sim_core::Segment::new(a, b);
            let band = Polygon::thick_segment(a, b, WALL_THICKNESS_M);
            for_cells_in(&frame, &band.aabb(), |c, p| {
                if seg.distance_to(p) <= half {
                    free.set(c, false);
                }
            });
        }
    }
    let doorways: Vec<Doorway> = portals.iter().map(|p| doorway(p, spaces)).collect();
    for d in &doorways {
        for_cells_in(&frame, &d.aabb(), |c, p| {
            if d.contains(p) {
                free.set(c, true);
            }
        });
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
    let doors: Vec<Door> = doorways.iter().map(Doorway::door).collect();
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

/// Two of a portal's points farther apart than this are two doors (between the same spaces).
const SAME_DOOR_M: f64 = 1.5;
/// A portal's wall is the space's outline within this distance of its point.
const NEAR_WALL_M: f64 = 1.0;
/// Widest door a portal's two points make (farther apart, the door is [`DOOR_WIDTH_M`]).
const MAX_DOOR_M: f64 = 2.5;
/// How far a doorway reaches past the outlines of the spaces it joins: through the wall.
const THROUGH_WALL_M: f64 = 0.2;

/// The portals of the plan, each once: a portal appears in both spaces it joins, with the same
/// line segment's id (its point may differ: some plans mark a door's two ends, one in each
/// space), or with points less than [`SAME_DOOR_M`] apart. A portal whose line segment no
/// space has is the other space's portal between the same two if there is one; else it is
/// placed midway along the longest stretch of wall its two spaces share; one whose spaces
/// share none is an error.
fn portals(
    path: &Path,
    spaces: &[Space],
    ids: &HashMap<String, usize>,
) -> Result<Vec<Portal>, Error> {
    let mut out: Vec<Portal> = Vec::new();
    let mut unplaced: Vec<(&str, usize)> = Vec::new();
    for s in spaces {
        for (field, segment, point, targets) in &s.portals {
            let rooms = [
                targets.first().and_then(|t| ids.get(t)).map(|&i| i as u32),
                targets.get(1).and_then(|t| ids.get(t)).map(|&i| i as u32),
            ];
            if rooms.iter().all(Option::is_none) {
                continue;
            }
            let same = out.iter().position(|o| {
                same_rooms(o.rooms, rooms)
                    && (o.segment == *segment
                        || point.is_some_and(|p| {
                            o.points.iter().any(|q| (*q - p).norm() < SAME_DOOR_M)
                        }))
            });
            let at = match same {
                Some(i) => i,
                None => {
                    out.push(Portal {
                        segment: segment.clone(),
                        points: Vec::new(),
                        rooms,
                    });
                    out.len() - 1
                }
            };
            match point {
                Some(p) if out[at].points.iter().all(|q| (*q - *p).norm() > 1e-6) => {
                    out[at].points.push(*p)
                }
                Some(_) => {}
                None => unplaced.push((field, at)),
            }
        }
    }
    for (field, at) in unplaced {
        // Placed by its own segment in the other space, or the other space's portal between
        // the same two under an id of its own.
        if out
            .iter()
            .any(|o| !o.points.is_empty() && same_rooms(o.rooms, out[at].rooms))
        {
            continue;
        }
        let [Some(a), Some(b)] = out[at].rooms else {
            return Err(Error::invalid(
                path,
                format!("{field}/linesegment"),
                format!(
                    "'{}' is not a line segment of the plan; expected one, or a portal \
                     joining two spaces that share a wall",
                    short(&out[at].segment)
                ),
            ));
        };
        let p = shared_wall_midpoint(&spaces[a as usize].polygon, &spaces[b as usize].polygon)
            .ok_or_else(|| {
                Error::invalid(
                    path,
                    format!("{field}/linesegment"),
                    format!(
                        "'{}' is not a line segment of the plan, and the two spaces it joins \
                         share no wall to place it on",
                        short(&out[at].segment)
                    ),
                )
            })?;
        out[at].points.push(p);
    }
    out.retain(|o| !o.points.is_empty());
    Ok(out)
}

/// Where an edge of one outline and an edge of another run side by side: parallel, at most
/// [`NEAR_WALL_M`] apart, overlapping; `from`-`to` is the overlap, midway between them.
struct SharedWall {
    a: (Vec2, Vec2),
    b: (Vec2, Vec2),
    from: Vec2,
    to: Vec2,
}

/// Every place where an edge of `a` and an edge of `b` run side by side.
fn shared_walls<'p>(a: &'p [Vec2], b: &'p [Vec2]) -> impl Iterator<Item = SharedWall> + 'p {
    edges(a).flat_map(move |(a0, a1)| {
        let len = (a1 - a0).norm();
        edges(b).filter_map(move |(b0, b1)| {
            if len < 1e-6 {
                return None;
            }
            let u = (a1 - a0) / len;
            let n = Vec2::new(-u.y, u.x);
            let d = b1 - b0;
            if d.norm() < 1e-6 || (d.x * u.y - d.y * u.x).abs() / d.norm() >= 0.2 {
                return None;
            }
            let gap = ((b0 + b1) * 0.5 - a0).dot(&n);
            let (s, t) = ((b0 - a0).dot(&u), (b1 - a0).dot(&u));
            let (lo, hi) = (s.min(t).max(0.0), s.max(t).min(len));
            (gap.abs() <= NEAR_WALL_M && hi - lo > 1e-6).then(|| SharedWall {
                a: (a0, a1),
                b: (b0, b1),
                from: a0 + u * lo + n * (gap / 2.0),
                to: a0 + u * hi + n * (gap / 2.0),
            })
        })
    })
}

/// The middle of the longest place where the outlines `a` and `b` run side by side, if any.
fn shared_wall_midpoint(a: &[Vec2], b: &[Vec2]) -> Option<Vec2> {
    shared_walls(a, b)
        .max_by(|x, y| (x.to - x.from).norm().total_cmp(&(y.to - y.from).norm()))
        .map(|w| (w.from + w.to) * 0.5)
}

/// Where a portal's doorway is cut. Its wall is the outline edge of its spaces nearest to its
/// point; the doorway runs along that edge, [`DOOR_WIDTH_M`] wide (or as wide as the portal's
/// two points are apart, up to [`MAX_DOOR_M`]), slid along the wall, when the point is near a
/// corner, so that it stays clear of the walls at the ends of the stretch the two spaces share;
/// between two corridors the whole shared stretch is open. Across, it reaches from one space's
/// outline to the other's and [`THROUGH_WALL_M`] beyond. A portal far from any outline opens a
/// square [`DOOR_WIDTH_M`] wide around its point.
fn doorway(portal: &Portal, spaces: &[Space]) -> Doorway {
    let c = portal.points.iter().fold(Vec2::zeros(), |a, p| a + *p) / portal.points.len() as f64;
    let span = portal
        .points
        .iter()
        .flat_map(|p| portal.points.iter().map(move |q| (*p - *q).norm()))
        .fold(0.0, f64::max);
    let members: Vec<&Space> = portal
        .rooms
        .iter()
        .flatten()
        .map(|&i| &spaces[i as usize])
        .collect();
    // The wall the door is in: where the two spaces' outlines run side by side nearest the
    // point; for a portal of one space, or of two that share no wall near it, the outline edge
    // nearest the point.
    let side_by_side = match members[..] {
        [x, y] => shared_walls(&x.polygon, &y.polygon)
            .map(|w| (sim_core::Segment::new(w.from, w.to).distance_to(c), w))
            .filter(|(d, _)| *d <= NEAR_WALL_M)
            .min_by(|x, y| x.0.total_cmp(&y.0))
            .map(|(_, w)| vec![Some(w.a), Some(w.b)]),
        _ => None,
    };
    let chosen = side_by_side.or_else(|| {
        let nearest = members
            .iter()
            .flat_map(|s| edges(&s.polygon))
            .filter(|(a, b)| (*b - *a).norm() > 1e-6)
            .map(|(a, b)| (sim_core::Segment::new(a, b).distance_to(c), a, b))
            .filter(|(d, _, _)| *d <= NEAR_WALL_M)
            .min_by(|x, y| x.0.total_cmp(&y.0))?;
        Some(vec![Some((nearest.1, nearest.2)); 1])
    });
    let Some(chosen) = chosen else {
        return Doorway {
            centre: c,
            u: Vec2::new(1.0, 0.0),
            half_width: DOOR_WIDTH_M / 2.0,
            across: (-DOOR_WIDTH_M / 2.0, DOOR_WIDTH_M / 2.0),
            rooms: portal.rooms,
        };
    };
    let (a, b) = chosen[0].expect("the first wall is always chosen");
    let u = (b - a) / (b - a).norm();
    let n = Vec2::new(-u.y, u.x);
    // Each space's stretch of wall along the door: its outline's edges parallel to it and in
    // line with its edge chosen above (or the one nearest the point), merged; (from, to) along
    // `u`, and the offset across.
    let stretches: Vec<((f64, f64), (Vec2, Vec2))> = members
        .iter()
        .enumerate()
        .filter_map(|(i, s)| {
            let edge = if chosen.len() == members.len() {
                chosen[i]
            } else {
                None
            };
            stretch(&s.polygon, edge, c, u, n)
        })
        .collect();
    let shared = stretches
        .iter()
        .map(|(r, _)| *r)
        .reduce(|x, y| (x.0.max(y.0), x.1.min(y.1)))
        .filter(|r| r.1 > r.0)
        .or_else(|| stretches.first().map(|(r, _)| *r));
    let corridors = members.len() == 2 && members.iter().all(|s| s.corridor);
    let clear = |(lo, hi): (f64, f64)| (lo + WALL_THICKNESS_M / 2.0, hi - WALL_THICKNESS_M / 2.0);
    let (t, width) = match shared.map(clear) {
        Some((lo, hi)) if corridors && hi - lo >= DOOR_WIDTH_M => ((lo + hi) / 2.0, hi - lo),
        Some((lo, hi)) => {
            let w = span
                .clamp(DOOR_WIDTH_M, MAX_DOOR_M)
                .min((hi - lo).max(DOOR_WIDTH_M));
            let (first, last) = (lo + w / 2.0, hi - w / 2.0);
            if first <= last {
                (0.0f64.clamp(first, last), w)
            } else {
                ((lo + hi) / 2.0, w)
            }
        }
        None => (0.0, DOOR_WIDTH_M),
    };
    // Across: from the point to each space's wall line, where the door's ends and middle are
    // (a wall slanted against the door's direction is farther at one end).
    let offsets: Vec<f64> = stretches
        .iter()
        .flat_map(|(_, (a, b))| {
            [t - width / 2.0, t, t + width / 2.0]
                .into_iter()
                .filter_map(move |along| offset_at(*a, *b, c, u, n, along))
        })
        .collect();
    let across = (
        offsets.iter().copied().fold(0.0, f64::min) - THROUGH_WALL_M,
        offsets.iter().copied().fold(0.0, f64::max) + THROUGH_WALL_M,
    );
    Doorway {
        centre: c + u * t,
        u,
        half_width: width / 2.0,
        across,
        rooms: portal.rooms,
    }
}

/// Where the line through `a` and `b` crosses the normal to `u` at `along` (from `c`): its
/// offset along `n`, within [`NEAR_WALL_M`]; `None` for a line across the door, or farther.
fn offset_at(a: Vec2, b: Vec2, c: Vec2, u: Vec2, n: Vec2, along: f64) -> Option<f64> {
    let v = b - a;
    let vu = v.dot(&u);
    if vu.abs() < 1e-9 {
        return None;
    }
    let q = a + v * ((along - (a - c).dot(&u)) / vu);
    let offset = (q - c).dot(&n);
    (offset.abs() <= NEAR_WALL_M).then_some(offset)
}

/// The stretch of `polygon`'s outline along `u` near `c`: the edges parallel to `u` in line
/// with `edge` (or, without one, with the parallel edge nearest `c`, within [`NEAR_WALL_M`]),
/// merged where they touch, the piece holding that edge; as (from, to) along `u` from `c`, and
/// that edge.
fn stretch(
    polygon: &[Vec2],
    edge: Option<(Vec2, Vec2)>,
    c: Vec2,
    u: Vec2,
    n: Vec2,
) -> Option<((f64, f64), (Vec2, Vec2))> {
    let parallel: Vec<(Vec2, Vec2)> = edges(polygon)
        .filter(|(a, b)| {
            let d = *b - *a;
            d.norm() > 1e-6 && (d.x * u.y - d.y * u.x).abs() / d.norm() < 0.2
        })
        .collect();
    let (a0, b0) = match edge {
        Some(e) => e,
        None => parallel
            .iter()
            .map(|&(a, b)| (sim_core::Segment::new(a, b).distance_to(c), a, b))
            .filter(|(d, _, _)| *d <= NEAR_WALL_M)
            .min_by(|x, y| x.0.total_cmp(&y.0))
            .map(|(_, a, b)| (a, b))?,
    };
    let offset = ((a0 + b0) * 0.5 - c).dot(&n);
    let mut pieces: Vec<(f64, f64)> = parallel
        .iter()
        .filter(|(a, b)| (((*a + *b) * 0.5 - c).dot(&n) - offset).abs() <= 0.1)
        .map(|(a, b)| {
            let (s, t) = ((*a - c).dot(&u), (*b - c).dot(&u));
            (s.min(t), s.max(t))
        })
        .collect();
    pieces.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut merged: Vec<(f64, f64)> = Vec::new();
    for p in pieces {
        match merged.last_mut() {
            Some(m) if p.0 <= m.1 + 0.1 => m.1 = m.1.max(p.1),
            _ => merged.push(p),
        }
    }
    let at = {
        let (s, t) = ((a0 - c).dot(&u), (b0 - c).dot(&u));
        (s.min(t) + s.max(t)) / 2.0
    };
    merged
        .into_iter()
        .find(|m| m.0 <= at && at <= m.1)
        .map(|m| (m, (a0, b0)))
}

/// The edges of a closed polygon.
fn edges(polygon: &[Vec2]) -> impl Iterator<Item = (Vec2, Vec2)> + '_ {
    (0..polygon.len()).map(move |i| (polygon[i], polygon[(i + 1) % polygon.len()]))
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

/// The start: the free cell farthest from the walls (lowest cell first among equals) in the
/// largest entrance (a space labelled ENTRANCE, as the paper's runs start at the entrance)
/// from which the default robot can see at least [`ENTRANCE_REACH`] of what it sees from the
/// largest corridor; else in the largest corridor; else in the largest space. A space whose
/// best cell has less than [`MIN_START_CLEARANCE_M`] is passed over; `None` when none has it.
fn start_in(spaces: &[Space], solid: &Bitmap) -> Option<Pose> {
    let area = |s: &Space| Polygon::new(s.polygon.clone()).area_m2();
    let clearance = sim_core::distance::distance_to(solid);
    let best_cell = |s: &Space| -> Option<sim_core::Cell> {
        let poly = Polygon::new(s.polygon.clone());
        let mut best: Option<(f32, sim_core::Cell)> = None;
        for_cells_in(&solid.frame, &poly.aabb(), |c, p| {
            let Some(&d) = clearance.get(c) else { return };
            if poly.contains(p) && best.is_none_or(|(bd, _)| d > bd) {
                best = Some((d, c));
            }
        });
        let (d, c) = best?;
        (f64::from(d) * solid.frame.resolution_m >= MIN_START_CLEARANCE_M).then_some(c)
    };
    let largest_first = |keep: &dyn Fn(&Space) -> bool| {
        let mut v: Vec<&Space> = spaces.iter().filter(|s| keep(s)).collect();
        v.sort_by(|a, b| area(b).total_cmp(&area(a)));
        v
    };
    let inside = sim_core::Bitmap {
        frame: solid.frame,
        data: solid.data.iter().map(|s| !s).collect(),
    };
    // What the default robot (0.2 m and a 0.05 m margin, a 6 m laser) can see from a cell.
    let reach = |c: sim_core::Cell| {
        let p = solid.frame.world_from_cell(c);
        let free = sim_core::building::flood_fill(&inside, c);
        sim_core::building::explorable_free(&free, p, 0.25, 6.0).count_true()
    };
    let fallback = largest_first(&|s| s.corridor)
        .into_iter()
        .chain(largest_first(&|_| true))
        .find_map(best_cell);
    let entrance = largest_first(&|s| s.kind == "entrance")
        .into_iter()
        .filter_map(best_cell)
        .find(|&c| fallback.is_none_or(|f| reach(c) as f64 >= ENTRANCE_REACH * reach(f) as f64));
    let c = entrance.or(fallback)?;
    let p = solid.frame.world_from_cell(c);
    Some(Pose::new(p.x, p.y, 0.0))
}

/// An entrance is a start when the default robot can see at least this share of what it sees
/// from the largest corridor (an entrance behind a doorway it does not fit is not).
const ENTRANCE_REACH: f64 = 0.95;
