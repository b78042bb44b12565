//! Stage `.world` files: the floor plan bitmap becomes a raster world, a placed robot its start.
//!
//! Only what floorcast needs is read: the first model (instance) that has a `bitmap` (its own or
//! through `define`d ancestors) is the floor plan; its `size [x y (z)]` (metres) and optional
//! `pose [x y z yaw_deg]` place the image as Stage does: the image spans `size` centred at the
//! pose, rotated by the pose's yaw. A pixel darker than mid-grey (average of the colour channels
//! below 128) is an obstacle, every other pixel is free; outside the image is solid (Stage's
//! floor plans usually carry `boundary 1`). The first top-level instance of a model derived from
//! `position` that has a `pose` is the robot: its `x, y, yaw` (degrees) is the building's start.
//!
//! Stage itself scales the *obstacle* bounding box to `size`; here the whole image spans `size`
//! (the same when dark pixels reach every border of the image). A yaw that is not a multiple of
//! 90 degrees is resampled (nearest pixel) at the finer of the two pixel sizes.

use std::collections::BTreeMap;
use std::path::Path;

use sim_core::{Bitmap, Building, Geometry, GridFrame, Pose, Vec2};

use crate::error::{num, Error};
use crate::map_server::read_image;

/// Grey level below which a floor-plan pixel is an obstacle.
pub const STAGE_OBSTACLE_BELOW: f64 = 128.0;

/// Reads a Stage world as a raster building named after the file's stem.
pub fn read_world(path: &Path) -> Result<Building, Error> {
    let text = crate::limits::read_text(path)?;
    world_from_text(&text, path, &|image_path, field| {
        if !image_path.is_file() {
            return Err(Error::invalid(
                path,
                field,
                format!(
                    "{} does not exist; the bitmap is resolved relative to the world file's directory",
                    image_path.display()
                ),
            ));
        }
        read_image(path, field, image_path)
    })
}

/// A world file's text as a building; `load_image(path, field)` reads the floor plan's bitmap.
pub(crate) fn world_from_text(
    text: &str,
    path: &Path,
    load_image: &dyn Fn(&Path, &str) -> Result<crate::map_server::MapImage, Error>,
) -> Result<Building, Error> {
    let world = parse_world(text).ok_or_else(|| {
        Error::syntax(
            path,
            format!(
                "models nested more than {} deep (too many unclosed `(`); expected a Stage world file",
                crate::limits::MAX_WORLD_DEPTH
            ),
        )
    })?;
    let plan = find_floorplan(&world, path)?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let image_path = dir.join(&plan.bitmap);
    let field = format!("{}.bitmap", plan.model);
    let img = load_image(&image_path, &field)?;
    let size_field = format!("{}.size", plan.model);
    let solid = rasterise(
        &img.rgba,
        img.has_color,
        plan.size_m,
        plan.pose,
        path,
        &size_field,
    )?;
    let start = find_robot(&world, plan.index);
    let building = Building {
        name: path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        geometry: Geometry::Raster { solid },
        rooms: Vec::new(),
        doors: Vec::new(),
        start,
    };
    crate::limits::check_building(
        &building,
        path,
        &size_field,
        crate::limits::EXPLORE_RESOLUTION_M,
    )?;
    Ok(building)
}

// ---------------------------------------------------------------------------------------------
// Tokens and a tolerant parse into nested entries.

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Word(String),
    Str(String),
    Open,
    Close,
    LBracket,
    RBracket,
}

/// Splits world-file text into tokens: `#` starts a comment, `"..."` is a string (an unterminated
/// one ends at the line's end), brackets and parentheses are tokens of their own.
fn tokenize(text: &str) -> Vec<Tok> {
    let mut out = Vec::new();
    let mut chars = text.chars().peekable();
    while let Some(&c) = chars.peek() {
        match c {
            '#' => {
                while chars.peek().is_some_and(|&c| c != '\n') {
                    chars.next();
                }
            }
            '"' => {
                chars.next();
                let mut s = String::new();
                for c in chars.by_ref() {
                    if c == '"' || c == '\n' {
                        break;
                    }
                    s.push(c);
                }
                out.push(Tok::Str(s));
            }
            '(' | ')' | '[' | ']' => {
                chars.next();
                out.push(match c {
                    '(' => Tok::Open,
                    ')' => Tok::Close,
                    '[' => Tok::LBracket,
                    _ => Tok::RBracket,
                });
            }
            c if c.is_whitespace() => {
                chars.next();
            }
            _ => {
                let mut s = String::new();
                while let Some(&c) = chars.peek() {
                    if c.is_whitespace() || "#\"()[]".contains(c) {
                        break;
                    }
                    s.push(c);
                    chars.next();
                }
                out.push(Tok::Word(s));
            }
        }
    }
    out
}

#[derive(Debug, Clone, PartialEq)]
enum Value {
    Atom(String),
    List(Vec<String>),
}

/// A model instance `kind( ... )` or the body of a `define`.
#[derive(Debug, Clone, Default)]
struct Entry {
    kind: String,
    props: Vec<(String, Value)>,
    children: Vec<Entry>,
}

#[derive(Debug, Default)]
struct World {
    /// Top-level properties and instances.
    top: Entry,
    /// `define NAME PARENT ( body )`: NAME -> (PARENT, body).
    defines: BTreeMap<String, (String, Entry)>,
}

/// The parsed world, or `None` when models nest deeper than [`crate::limits::MAX_WORLD_DEPTH`].
fn parse_world(text: &str) -> Option<World> {
    let toks = tokenize(text);
    let mut i = 0;
    let mut world = World::default();
    let mut top = Entry::default();
    let mut too_deep = false;
    // A stray `)` at the top level is skipped; parse again until the tokens are used up.
    while i < toks.len() {
        parse_body(
            &toks,
            &mut i,
            0,
            &mut top,
            &mut world.defines,
            &mut too_deep,
        );
        if too_deep {
            return None;
        }
        if i < toks.len() {
            i += 1;
        }
    }
    world.top = top;
    Some(world)
}

/// Parses entries into `into` until a `)` closes the body (depth > 0) or the tokens end
/// (a missing `)` is forgiven).
fn parse_body(
    toks: &[Tok],
    i: &mut usize,
    depth: usize,
    into: &mut Entry,
    defines: &mut BTreeMap<String, (String, Entry)>,
    too_deep: &mut bool,
) {
    if depth > crate::limits::MAX_WORLD_DEPTH {
        *too_deep = true;
        *i = toks.len();
        return;
    }
    while *i < toks.len() {
        match &toks[*i] {
            Tok::Close => {
                if depth > 0 {
                    *i += 1;
                }
                return;
            }
            Tok::Word(w) if w == "define" => {
                *i += 1;
                let name = word_at(toks, *i);
                let parent = word_at(toks, *i + 1);
                if let (Some(name), Some(parent), Some(Tok::Open)) =
                    (name, parent, toks.get(*i + 2))
                {
                    *i += 3;
                    let mut body = Entry {
                        kind: parent.clone(),
                        ..Entry::default()
                    };
                    parse_body(toks, i, depth + 1, &mut body, defines, too_deep);
                    defines.insert(name.clone(), (parent.clone(), body));
                }
            }
            Tok::Word(w) => {
                let key = w.clone();
                *i += 1;
                match toks.get(*i) {
                    Some(Tok::Open) => {
                        *i += 1;
                        let mut child = Entry {
                            kind: key,
                            ..Entry::default()
                        };
                        parse_body(toks, i, depth + 1, &mut child, defines, too_deep);
                        into.children.push(child);
                    }
                    Some(Tok::Word(v)) | Some(Tok::Str(v)) => {
                        into.props.push((key, Value::Atom(v.clone())));
                        *i += 1;
                    }
                    Some(Tok::LBracket) => {
                        *i += 1;
                        let mut items = Vec::new();
                        while let Some(t) = toks.get(*i) {
                            match t {
                                Tok::RBracket => {
                                    *i += 1;
                                    break;
                                }
                                Tok::Word(v) | Tok::Str(v) => items.push(v.clone()),
                                Tok::Close | Tok::Open => break,
                                Tok::LBracket => {}
                            }
                            *i += 1;
                        }
                        into.props.push((key, Value::List(items)));
                    }
                    _ => {}
                }
            }
            _ => *i += 1,
        }
    }
}

fn word_at(toks: &[Tok], i: usize) -> Option<&String> {
    match toks.get(i) {
        Some(Tok::Word(w)) => Some(w),
        _ => None,
    }
}

impl World {
    /// `kind`, its parent, grandparent... (stops at undefined kinds and at cycles).
    fn chain(&self, kind: &str) -> Vec<String> {
        let mut out = vec![kind.to_string()];
        let mut k = kind.to_string();
        while let Some((parent, _)) = self.defines.get(&k) {
            if out.contains(parent) || out.len() > 64 {
                break;
            }
            out.push(parent.clone());
            k = parent.clone();
        }
        out
    }

    /// A property of an instance: its own (last one wins), else inherited from its defines.
    fn prop<'a>(&'a self, e: &'a Entry, key: &str) -> Option<&'a Value> {
        if let Some((_, v)) = e.props.iter().rev().find(|(k, _)| k == key) {
            return Some(v);
        }
        for kind in self.chain(&e.kind) {
            if let Some((_, body)) = self.defines.get(&kind) {
                if let Some((_, v)) = body.props.iter().rev().find(|(k, _)| k == key) {
                    return Some(v);
                }
            }
        }
        None
    }
}

fn numbers(v: &Value) -> Option<Vec<f64>> {
    let items: Vec<&String> = match v {
        Value::Atom(a) => vec![a],
        Value::List(l) => l.iter().collect(),
    };
    items
        .iter()
        .map(|s| s.parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect()
}

// ---------------------------------------------------------------------------------------------
// The floor plan and the robot.

#[derive(Debug)]
struct Floorplan {
    /// Index among the top-level instances.
    index: usize,
    /// How the model is named in messages (`floorplan` or `floorplan "willow"`).
    model: String,
    bitmap: String,
    size_m: Vec2,
    pose: Pose,
}

fn find_floorplan(world: &World, path: &Path) -> Result<Floorplan, Error> {
    let Some((index, e, bitmap)) =
        world
            .top
            .children
            .iter()
            .enumerate()
            .find_map(|(i, e)| match world.prop(e, "bitmap") {
                Some(Value::Atom(b)) => Some((i, e, b.clone())),
                _ => None,
            })
    else {
        return Err(Error::invalid(
            path,
            "floorplan",
            "no model with a `bitmap`; expected e.g. floorplan( bitmap \"map.pgm\" size [20 15 0.5] pose [0 0 0 0] )",
        ));
    };
    let model = match world.prop(e, "name") {
        Some(Value::Atom(n)) => format!("{}(name \"{n}\")", e.kind),
        _ => e.kind.clone(),
    };
    let size = world.prop(e, "size").and_then(numbers);
    let size_m = match size.as_deref() {
        Some([x, y, ..]) if *x > 0.0 && *y > 0.0 => Vec2::new(*x, *y),
        Some(s) => {
            return Err(Error::invalid(
                path,
                format!("{model}.size"),
                format!(
                    "expected [x y (z)] with positive x and y in metres, got [{}]",
                    s.iter().map(|v| num(*v)).collect::<Vec<_>>().join(" ")
                ),
            ))
        }
        None => return Err(Error::invalid(
            path,
            format!("{model}.size"),
            "missing or not numbers; expected size [x y (z)] in metres, the extent of the bitmap",
        )),
    };
    let pose = match world.prop(e, "pose") {
        None => Pose::new(0.0, 0.0, 0.0),
        Some(v) => stage_pose(v).ok_or_else(|| {
            Error::invalid(
                path,
                format!("{model}.pose"),
                "expected pose [x y z yaw_deg] (or [x y yaw_deg]) of numbers",
            )
        })?,
    };
    Ok(Floorplan {
        index,
        model,
        bitmap,
        size_m,
        pose,
    })
}

/// `pose [x y z a]` (Stage 4) or `[x y a]` (Stage 3), yaw in degrees.
fn stage_pose(v: &Value) -> Option<Pose> {
    match numbers(v)?.as_slice() {
        [x, y, _, a] | [x, y, a] => Some(Pose::new(*x, *y, a.to_radians())),
        [x, y] => Some(Pose::new(*x, *y, 0.0)),
        _ => None,
    }
}

/// The first top-level instance (other than the floor plan) of a `position` model with a pose.
fn find_robot(world: &World, floorplan_index: usize) -> Option<Pose> {
    world
        .top
        .children
        .iter()
        .enumerate()
        .filter(|(i, e)| {
            *i != floorplan_index && world.chain(&e.kind).iter().any(|k| k == "position")
        })
        .find_map(|(_, e)| world.prop(e, "pose").and_then(stage_pose))
}

/// The bitmap placed in the world: spans `size_m` centred at `pose`, rotated by its yaw.
fn rasterise(
    img: &image::RgbaImage,
    has_color: bool,
    size_m: Vec2,
    pose: Pose,
    path: &Path,
    field: &str,
) -> Result<Bitmap, Error> {
    let (w, h) = img.dimensions();
    let px_w = size_m.x / w as f64;
    let px_h = size_m.y / h as f64;
    let res = px_w.min(px_h);
    let (s, c) = pose.theta_rad.sin_cos();
    let centre = pose.position();
    let half = size_m / 2.0;
    let mut bounds = sim_core::Aabb::empty();
    for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        let l = Vec2::new(sx * half.x, sy * half.y);
        bounds.grow(centre + Vec2::new(c * l.x - s * l.y, s * l.x + c * l.y));
    }
    let cells = |extent: f64| -> u32 {
        let n = extent / res;
        let r = n.round();
        (if (n - r).abs() < 1e-6 { r } else { n.ceil() }).max(1.0) as u32
    };
    crate::limits::check_cells(
        path,
        field,
        crate::limits::cells_for(bounds.width_m(), bounds.height_m(), res),
        &format!(
            "a floor plan of {} x {} m drawn with {w} x {h} pixels (pixels of {} m)",
            num(size_m.x),
            num(size_m.y),
            num(res)
        ),
    )?;
    if !crate::limits::coordinate_ok(
        bounds
            .min
            .x
            .abs()
            .max(bounds.min.y.abs())
            .max(bounds.max.x.abs())
            .max(bounds.max.y.abs()),
    ) {
        return Err(Error::invalid(
            path,
            field,
            format!(
                "the floor plan reaches beyond {} m from the origin; expected size and pose in metres near the origin",
                num(crate::limits::COORDINATE_LIMIT_M)
            ),
        ));
    }
    let frame = GridFrame::new(
        bounds.min,
        res,
        cells(bounds.width_m()),
        cells(bounds.height_m()),
    );
    let dark = |x: u32, y: u32| -> bool {
        let [r, g, b, _] = img.get_pixel(x, y).0;
        let grey = if has_color {
            (r as f64 + g as f64 + b as f64) / 3.0
        } else {
            r as f64
        };
        grey < STAGE_OBSTACLE_BELOW
    };
    let mut solid = Bitmap::filled(frame, true);
    for i in 0..frame.len() {
        let d = frame.world_from_cell(frame.cell_of_index(i)) - centre;
        let l = Vec2::new(c * d.x + s * d.y, -s * d.x + c * d.y);
        let u = ((l.x + half.x) / px_w).floor();
        let v = ((half.y - l.y) / px_h).floor();
        if u >= 0.0 && v >= 0.0 && u < w as f64 && v < h as f64 {
            solid.data[i] = dark(u as u32, v as u32);
        }
    }
    Ok(solid)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny_pgm(dir: &Path) {
        // 4 x 3, a dark border and free inside (2 x 1), grey 206 counts as free.
        std::fs::write(
            dir.join("plan.pgm"),
            b"P5\n4 3\n255\n\x00\x00\x00\x00\x00\xce\xff\x00\x00\x00\x00\x00",
        )
        .unwrap();
    }

    fn read(world: &str) -> Result<Building, String> {
        let dir = tempfile::tempdir().unwrap();
        tiny_pgm(dir.path());
        let p = dir.path().join("w.world");
        std::fs::write(&p, world).unwrap();
        read_world(&p).map_err(|e| {
            let s = e.to_string();
            assert!(!s.contains('\n'));
            assert!(s.contains("w.world"), "{s}");
            s
        })
    }

    #[test]
    fn tokenizer_handles_comments_strings_and_nesting() {
        let t = tokenize("a( b \"x y\" # c ) \n c [1 2] d(e(f 1)))");
        assert_eq!(t.len(), 18, "{t:?}");
        let w =
            parse_world("define r position ( size [1 1] )\nr( pose [1 2 0 90] n( x 1 ) ) )) q 3")
                .unwrap();
        assert_eq!(w.top.children.len(), 1);
        assert_eq!(w.chain("r"), vec!["r".to_string(), "position".to_string()]);
        assert_eq!(find_robot(&w, usize::MAX).unwrap().y_m, 2.0);
    }

    #[test]
    fn nesting_is_bounded() {
        // (depth, parsed)
        for (depth, ok) in [(10, true), (64, true), (66, false), (20_000, false)] {
            let text = "a(".repeat(depth);
            assert_eq!(parse_world(&text).is_some(), ok, "{depth}");
        }
        let e = read(&"m(".repeat(20_000)).unwrap_err();
        assert!(e.contains("nested more than 64 deep"), "{e}");
    }

    #[test]
    fn places_bitmap_and_robot() {
        let b = read(
            "define plan model ( color \"gray\" )\n\
             define bot position ( size [0.3 0.3 0.2] )\n\
             plan( bitmap \"plan.pgm\" size [8 6 1] pose [10 20 0 0] ) # 2 m pixels\n\
             bot( pose [ 10 20 0 90 ] name \"r\" )\n",
        )
        .unwrap();
        let Geometry::Raster { solid } = &b.geometry else {
            panic!()
        };
        assert_eq!(solid.frame.resolution_m, 2.0);
        assert_eq!(solid.frame.origin_m, Vec2::new(6.0, 17.0));
        assert_eq!((solid.frame.width, solid.frame.height), (4, 3));
        assert_eq!(b.free_area_m2(), 8.0);
        let start = b.start.unwrap();
        assert_eq!((start.x_m, start.y_m), (10.0, 20.0));
        assert!((start.theta_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!(b.is_free(start.position()));
        assert_eq!(b.name, "w");
    }

    #[test]
    fn rotated_floorplan_swaps_axes() {
        let b = read("floorplan( bitmap \"plan.pgm\" size [4 3] pose [0 0 0 90] )").unwrap();
        let f = b.bounds();
        assert!((f.width_m() - 3.0).abs() < 1e-9 && (f.height_m() - 4.0).abs() < 1e-9);
        assert_eq!(b.free_area_m2(), 2.0);
        // The free pixels (row 1, columns 1..3) lie along x = 0 after the quarter turn.
        assert!(b.is_free(Vec2::new(0.0, -0.5)) && b.is_free(Vec2::new(0.0, 0.5)));
        assert!(b.start.is_none());
    }

    #[test]
    fn error_no_bitmap() {
        let e = read("floorplan( size [4 3] )\nerratic( pose [0 0 0 0] )").unwrap_err();
        assert!(e.contains("floorplan: no model with a `bitmap`"), "{e}");
    }

    #[test]
    fn error_missing_bitmap_file() {
        let e = read("floorplan( name \"x\" bitmap \"nope.pgm\" size [4 3] )").unwrap_err();
        assert!(e.contains("floorplan(name \"x\").bitmap: "), "{e}");
        assert!(e.contains("nope.pgm does not exist"), "{e}");
    }

    #[test]
    fn error_missing_size() {
        let e = read("floorplan( bitmap \"plan.pgm\" pose [0 0 0 0] )").unwrap_err();
        assert!(e.contains("floorplan.size: missing"), "{e}");
        let e = read("floorplan( bitmap \"plan.pgm\" size [0 3] )").unwrap_err();
        assert!(
            e.contains("floorplan.size: expected [x y (z)] with positive"),
            "{e}"
        );
    }
}
