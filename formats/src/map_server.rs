//! ROS `map_server` maps: a YAML file (`image`, `resolution`, `origin`, `negate`,
//! `occupied_thresh`, `free_thresh`, optional `mode`) and the image it names (PGM P5/P2 or PNG,
//! grey or RGB(A)).
//!
//! Pixels are classified exactly as ROS `map_server` does: the channels are averaged (in trinary
//! mode an alpha channel is averaged in too, as ROS does), `negate` flips the grey, and the
//! occupancy `occ = (255 - p) / 255` is compared with the thresholds: `occ > occupied_thresh` is
//! occupied, `occ < free_thresh` is free, anything else unknown. In `raw` mode the (negated) grey
//! is the occupancy in percent: `0..=100` is thresholded the same way as `p / 100`, other values
//! are unknown. `scale` mode gives the same ternary map as `trinary` (its intermediate values are
//! neither free nor occupied).
//!
//! The image's top row is the map's top: grid row 0 (the bottom) is the image's last row. The
//! `origin` is the world position of the lower-left corner of the lower-left pixel; a non-zero
//! yaw is rejected.

use std::path::{Path, PathBuf};

use serde_yaml_ng::Value;
use sim_core::{Bitmap, Building, Cell, Geometry, Grid, GridFrame, Occupancy, OccupancyGrid, Vec2};

use crate::error::{num, Error};

/// How the pixels of a map image are interpreted (`mode` in the YAML).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapMode {
    Trinary,
    Scale,
    Raw,
}

/// A parsed and validated map YAML.
#[derive(Debug, Clone, PartialEq)]
pub struct MapMeta {
    /// The image, resolved against the YAML's directory.
    pub image_path: PathBuf,
    pub resolution_m: f64,
    /// World position of the lower-left corner of the map.
    pub origin_m: Vec2,
    pub negate: bool,
    pub occupied_thresh: f64,
    pub free_thresh: f64,
    pub mode: MapMode,
}

/// Thresholds that `write_map` writes (the ROS defaults).
pub const WRITE_OCCUPIED_THRESH: f64 = 0.65;
pub const WRITE_FREE_THRESH: f64 = 0.196;
/// Pixel values that `write_map` writes.
pub const PIXEL_FREE: u8 = 254;
pub const PIXEL_OCCUPIED: u8 = 0;
pub const PIXEL_UNKNOWN: u8 = 205;

/// Finest and coarsest map resolution accepted (metres per pixel).
pub const MIN_RESOLUTION_M: f64 = 0.001;
pub const MAX_RESOLUTION_M: f64 = 1.0;

const EXPECTED_KEYS: &str =
    "image, resolution, origin, negate, occupied_thresh, free_thresh (and optionally mode)";

/// Reads a map_server YAML and its image as a ternary occupancy grid.
pub fn read_map(yaml_path: &Path) -> Result<OccupancyGrid, Error> {
    let meta = read_map_yaml(yaml_path)?;
    // What is there decides the message: nothing, a folder, or a FIFO, device or socket (a FIFO
    // would also block a reader forever).
    let problem = match std::fs::metadata(&meta.image_path) {
        Ok(m) if m.is_file() => None,
        Ok(m) if m.is_dir() => Some("is a directory, not an image file"),
        Ok(_) => Some("is not a regular file (a FIFO, device or socket); expected an image file"),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Some("does not exist"),
        Err(_) => Some("cannot be read (its folder is not accessible)"),
    };
    if let Some(problem) = problem {
        return Err(Error::invalid(
            yaml_path,
            "image",
            format!(
                "{} {problem}; `image` is resolved relative to the YAML's directory",
                meta.image_path.display()
            ),
        ));
    }
    let img = read_image(yaml_path, "image", &meta.image_path)?;
    let (w, h) = img.rgba.dimensions();
    crate::limits::check_cells(
        yaml_path,
        "resolution",
        {
            let (w_m, h_m) = (w as f64 * meta.resolution_m, h as f64 * meta.resolution_m);
            let margin_m = sim_core::explore::map_margin_m(&sim_core::Aabb {
                min: sim_core::Vec2::zeros(),
                max: sim_core::Vec2::new(w_m, h_m),
            });
            crate::limits::cells_for(
                w_m + 2.0 * margin_m,
                h_m + 2.0 * margin_m,
                crate::limits::EXPLORE_RESOLUTION_M,
            )
        },
        &format!(
            "{w} x {h} pixels of {} m span {} x {} m; exploring them on a {} m grid",
            num(meta.resolution_m),
            num(w as f64 * meta.resolution_m),
            num(h as f64 * meta.resolution_m),
            num(crate::limits::EXPLORE_RESOLUTION_M)
        ),
    )?;
    Ok(grid_from_image(&meta, &img))
}

/// Reads and validates a map_server YAML (without loading the image).
pub fn read_map_yaml(yaml_path: &Path) -> Result<MapMeta, Error> {
    let text = crate::limits::read_text(yaml_path)?;
    parse_map_yaml(&text, yaml_path)
}

/// Parses a map_server YAML; `yaml_path` names the file in messages and anchors the image path.
pub fn parse_map_yaml(text: &str, yaml_path: &Path) -> Result<MapMeta, Error> {
    let doc: Value = serde_yaml_ng::from_str(text)
        .map_err(|e| Error::syntax(yaml_path, format!("invalid YAML: {e}")))?;
    let Value::Mapping(map) = doc else {
        return Err(Error::syntax(
            yaml_path,
            format!("expected a YAML mapping with keys {EXPECTED_KEYS}"),
        ));
    };
    let get = |key: &str| -> Result<&Value, Error> {
        map.get(key).ok_or_else(|| {
            Error::invalid(
                yaml_path,
                key,
                format!("missing; a map YAML needs {EXPECTED_KEYS}"),
            )
        })
    };
    let number = |key: &str, what: &str| -> Result<f64, Error> {
        let v = get(key)?;
        match v.as_f64() {
            Some(x) if x.is_finite() => Ok(x),
            _ => Err(Error::invalid(
                yaml_path,
                key,
                format!("expected {what}, got {}", show(v)),
            )),
        }
    };

    let image = match get("image")? {
        Value::String(s) if !s.trim().is_empty() => s.trim().to_string(),
        v => {
            return Err(Error::invalid(
                yaml_path,
                "image",
                format!(
                    "expected the image file name (relative to the YAML's directory), got {}",
                    show(v)
                ),
            ))
        }
    };
    let dir = yaml_path.parent().unwrap_or(Path::new(""));
    let image_path = dir.join(image);

    let resolution_m = number("resolution", "a positive number of metres per pixel")?;
    if !(MIN_RESOLUTION_M..=MAX_RESOLUTION_M).contains(&resolution_m) {
        return Err(Error::invalid(
            yaml_path,
            "resolution",
            format!(
                "must be between {} and {} metres per pixel, got {}",
                num(MIN_RESOLUTION_M),
                num(MAX_RESOLUTION_M),
                num(resolution_m)
            ),
        ));
    }

    let origin_m = origin_of(get("origin")?, yaml_path)?;

    let negate = match get("negate")? {
        Value::Bool(b) => *b,
        v if v.as_i64() == Some(0) => false,
        v if v.as_i64() == Some(1) => true,
        v => {
            return Err(Error::invalid(
                yaml_path,
                "negate",
                format!("expected 0 or 1, got {}", show(v)),
            ))
        }
    };

    let occupied_thresh = number("occupied_thresh", "a number between 0 and 1")?;
    let free_thresh = number("free_thresh", "a number between 0 and 1")?;
    check_thresholds(occupied_thresh, free_thresh, yaml_path)?;

    let mode = mode_of(map.get("mode"), yaml_path)?;

    Ok(MapMeta {
        image_path,
        resolution_m,
        origin_m,
        negate,
        occupied_thresh,
        free_thresh,
        mode,
    })
}

/// The map's origin `[x, y, yaw]` (yaw 0 only).
fn origin_of(origin_v: &Value, yaml_path: &Path) -> Result<Vec2, Error> {
    let origin: Option<Vec<f64>> = origin_v
        .as_sequence()
        .and_then(|s| s.iter().map(Value::as_f64).collect());
    let origin = match origin {
        Some(o)
            if (2..=3).contains(&o.len())
                && o[..2].iter().all(|v| crate::limits::coordinate_ok(*v))
                && o.iter().all(|v| v.is_finite()) =>
        {
            o
        }
        _ => {
            return Err(Error::invalid(
                yaml_path,
                "origin",
                format!(
                    "expected [x, y, yaw] (metres within {} m of 0, metres, radians), got {}",
                    num(crate::limits::COORDINATE_LIMIT_M),
                    show(origin_v)
                ),
            ))
        }
    };
    let yaw_rad = origin.get(2).copied().unwrap_or(0.0);
    if yaw_rad.abs() > 1e-9 {
        return Err(Error::unsupported(
            yaml_path,
            format!(
                "origin yaw {} rad; only maps with yaw 0 are supported (rotate the image instead)",
                num(yaw_rad)
            ),
        ));
    }
    Ok(Vec2::new(origin[0], origin[1]))
}

/// Both thresholds within [0, 1], free below occupied.
fn check_thresholds(occupied_thresh: f64, free_thresh: f64, yaml_path: &Path) -> Result<(), Error> {
    for (key, v) in [
        ("occupied_thresh", occupied_thresh),
        ("free_thresh", free_thresh),
    ] {
        if !(0.0..=1.0).contains(&v) {
            return Err(Error::invalid(
                yaml_path,
                key,
                format!("must be between 0 and 1, got {}", num(v)),
            ));
        }
    }
    if free_thresh >= occupied_thresh {
        return Err(Error::invalid(
            yaml_path,
            "free_thresh",
            format!(
                "thresholds out of order: free_thresh {} must be below occupied_thresh {}",
                num(free_thresh),
                num(occupied_thresh)
            ),
        ));
    }
    Ok(())
}

/// The map's `mode` (default trinary).
fn mode_of(v: Option<&Value>, yaml_path: &Path) -> Result<MapMode, Error> {
    Ok(match v {
        None => MapMode::Trinary,
        Some(Value::String(s)) if s == "trinary" => MapMode::Trinary,
        Some(Value::String(s)) if s == "scale" => MapMode::Scale,
        Some(Value::String(s)) if s == "raw" => MapMode::Raw,
        Some(v) => {
            return Err(Error::invalid(
                yaml_path,
                "mode",
                format!("expected one of trinary, scale, raw, got {}", show(v)),
            ))
        }
    })
}

/// A YAML value as it would be written, on one line, for messages.
fn show(v: &Value) -> String {
    match v {
        Value::Null => "nothing".to_string(),
        Value::String(s) => format!("{s:?}"),
        Value::Number(n) if n.is_i64() || n.is_u64() => n.to_string(),
        Value::Number(n) => n.as_f64().map(num).unwrap_or_else(|| n.to_string()),
        Value::Sequence(items) if items.len() <= 8 => format!(
            "[{}]",
            items.iter().map(show).collect::<Vec<_>>().join(", ")
        ),
        Value::Sequence(_) => "a list".to_string(),
        _ => serde_yaml_ng::to_string(v)
            .map(|s| crate::error::one_line(&s))
            .unwrap_or_else(|_| "an unreadable value".to_string()),
    }
}

/// A decoded image: per pixel the values that map_server averages (colour channels, plus alpha
/// in trinary mode), kept as RGBA plus whether the source had colour and alpha.
#[derive(Debug)]
pub(crate) struct MapImage {
    pub rgba: image::RgbaImage,
    pub has_color: bool,
    pub has_alpha: bool,
}

/// Decodes an image file (format guessed from its content), named by `field` of `referrer` (the
/// YAML or world file) in messages. Its size is checked against the cell budget from its header,
/// before any pixel is decoded.
pub(crate) fn read_image(referrer: &Path, field: &str, path: &Path) -> Result<MapImage, Error> {
    let bytes = crate::limits::read_bytes(
        path,
        crate::limits::max_cells()
            .saturating_mul(8)
            .saturating_add(1 << 20),
    )?;
    decode_image(referrer, field, path, &bytes)
}

/// Decodes image bytes (see [`read_image`]).
pub(crate) fn decode_image(
    referrer: &Path,
    field: &str,
    path: &Path,
    bytes: &[u8],
) -> Result<MapImage, Error> {
    let err = |m: String| Error::image(referrer, field, path, m);
    let format = image::guess_format(bytes)
        .map_err(|_| err("the content is neither PGM/PNM nor PNG".into()))?;
    let reader = || image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    let (w, h) = reader()
        .into_dimensions()
        .map_err(|e| err(format!("truncated or corrupt: {e}")))?;
    if w == 0 || h == 0 {
        return Err(err("the image has no pixels".into()));
    }
    crate::limits::check_cells(
        referrer,
        field,
        w as f64 * h as f64,
        &format!("the image of {w} x {h} pixels"),
    )?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(w);
    limits.max_image_height = Some(h);
    // RGBA8 plus the decoder's own buffer of at most 16-bit RGBA.
    limits.max_alloc = Some((w as u64 * h as u64).saturating_mul(12).max(1 << 20));
    let mut r = reader();
    r.limits(limits);
    let img = r
        .decode()
        .map_err(|e| err(format!("truncated or corrupt: {e}")))?;
    let color = img.color();
    if img.width() == 0 || img.height() == 0 {
        return Err(err("the image has no pixels".into()));
    }
    Ok(MapImage {
        has_color: color.has_color(),
        has_alpha: color.has_alpha(),
        rgba: img.to_rgba8(),
    })
}

/// The grey value map_server computes for a pixel (before `negate`).
fn pixel_grey(img: &MapImage, px: &image::Rgba<u8>, mode: MapMode) -> f64 {
    let [r, g, b, a] = px.0;
    let mut sum = if img.has_color {
        r as f64 + g as f64 + b as f64
    } else {
        r as f64
    };
    let mut n = if img.has_color { 3.0 } else { 1.0 };
    if img.has_alpha && mode == MapMode::Trinary {
        sum += a as f64;
        n += 1.0;
    }
    sum / n
}

/// Classifies one grey value (0..=255, before `negate`) as map_server does.
pub fn classify_grey(grey: f64, meta: &MapMeta) -> Occupancy {
    let p = if meta.negate { 255.0 - grey } else { grey };
    let occ = match meta.mode {
        MapMode::Trinary | MapMode::Scale => (255.0 - p) / 255.0,
        MapMode::Raw => {
            // map_server stores the (truncated) value itself as the occupancy in percent.
            let v = p.trunc();
            if v > 100.0 {
                return Occupancy::Unknown;
            }
            v / 100.0
        }
    };
    if occ > meta.occupied_thresh {
        Occupancy::Occupied
    } else if occ < meta.free_thresh {
        Occupancy::Free
    } else {
        Occupancy::Unknown
    }
}

fn grid_from_image(meta: &MapMeta, img: &MapImage) -> OccupancyGrid {
    let (w, h) = img.rgba.dimensions();
    let frame = GridFrame::new(meta.origin_m, meta.resolution_m, w, h);
    let mut grid = Grid::filled(frame, Occupancy::Unknown);
    for (x, row, px) in img.rgba.enumerate_pixels() {
        let y = h - 1 - row;
        let state = classify_grey(pixel_grey(img, px, meta.mode), meta);
        grid.data[y as usize * w as usize + x as usize] = state;
    }
    grid
}

/// A raster world from a map: every cell that is not free is solid.
pub fn building_from_map(grid: &OccupancyGrid, name: &str) -> Building {
    let solid = Bitmap {
        frame: grid.frame,
        data: grid.data.iter().map(|s| *s != Occupancy::Free).collect(),
    };
    Building {
        name: name.to_string(),
        geometry: Geometry::Raster { solid },
        rooms: Vec::new(),
        doors: Vec::new(),
        start: None,
    }
}

/// Writes `grid` as `<stem>.yaml` (at `yaml_path`) and `<stem>.pgm` beside it: 254 free, 0
/// occupied, 205 unknown, `negate: 0`, thresholds 0.65 / 0.196, origin from the grid's frame.
pub fn write_map(grid: &OccupancyGrid, yaml_path: &Path) -> Result<(), Error> {
    let f = grid.frame;
    if f.is_empty() {
        return Err(Error::unsupported(
            yaml_path,
            format!(
                "cannot write an empty map ({} x {} cells)",
                f.width, f.height
            ),
        ));
    }
    let frame_ok = f.resolution_m.is_finite()
        && f.resolution_m > 0.0
        && f.origin_m.iter().all(|v| v.is_finite());
    if !frame_ok {
        return Err(Error::invalid(
            yaml_path,
            "resolution",
            format!(
                "the grid's frame must have a positive resolution and a finite origin, got resolution {} origin {}",
                num(f.resolution_m),
                crate::error::point(f.origin_m.x, f.origin_m.y)
            ),
        ));
    }
    let pgm_path = yaml_path.with_extension("pgm");
    let pgm_name = pgm_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "map.pgm".to_string());

    let mut pgm = format!("P5\n# floorcast\n{} {}\n255\n", f.width, f.height).into_bytes();
    pgm.reserve(f.len());
    for y in (0..f.height as i32).rev() {
        for x in 0..f.width as i32 {
            pgm.push(match grid.get(Cell::new(x, y)) {
                Some(Occupancy::Free) => PIXEL_FREE,
                Some(Occupancy::Occupied) => PIXEL_OCCUPIED,
                _ => PIXEL_UNKNOWN,
            });
        }
    }
    let yaml = format!(
        "image: {pgm_name}\nmode: trinary\nresolution: {:?}\norigin: [{:?}, {:?}, 0.0]\nnegate: 0\noccupied_thresh: {WRITE_OCCUPIED_THRESH:?}\nfree_thresh: {WRITE_FREE_THRESH:?}\n",
        f.resolution_m, f.origin_m.x, f.origin_m.y
    );
    std::fs::write(&pgm_path, pgm).map_err(|e| Error::io(&pgm_path, "write", e))?;
    std::fs::write(yaml_path, yaml).map_err(|e| Error::io(yaml_path, "write", e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    const GOOD_YAML: &str = "image: m.pgm\nresolution: 0.5\norigin: [1.0, -2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";

    fn err_of(yaml: &str, files: &[(&str, &[u8])]) -> String {
        let dir = tempfile::tempdir().unwrap();
        for (n, b) in files {
            write(dir.path(), n, b);
        }
        let y = write(dir.path(), "bad.yaml", yaml.as_bytes());
        let e = read_map(&y).unwrap_err().to_string();
        eprintln!("{e}");
        assert!(!e.contains('\n'), "multi-line message: {e}");
        e
    }

    #[test]
    fn reads_pgm_with_orientation_origin_and_thresholds() {
        // 3 x 2 image, top row: free occupied unknown; bottom row: 230 (occ 0.098 -> free),
        // 100 (occ 0.61 -> unknown), 80 (occ 0.69 -> occupied).
        let pgm = b"P5\n# comment\n3 2\n255\n\xfe\x00\xcd\xe6\x64\x50";
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "m.pgm", pgm);
        let y = write(dir.path(), "m.yaml", GOOD_YAML.as_bytes());
        let g = read_map(&y).unwrap();
        assert_eq!(g.frame.origin_m, Vec2::new(1.0, -2.0));
        assert_eq!(g.frame.resolution_m, 0.5);
        assert_eq!(g.to_ascii(), ".#?\n.?#\n");
    }

    #[test]
    fn negate_and_raw_modes() {
        let dir = tempfile::tempdir().unwrap();
        // Plain (P2) PGM: 0, 50, 99, 255.
        write(dir.path(), "m.pgm", b"P2\n4 1\n255\n0 50 99 255\n");
        let neg = GOOD_YAML.replace("negate: 0", "negate: 1");
        let y = write(dir.path(), "n.yaml", neg.as_bytes());
        // Negated: occ = p / 255 -> 0 free, 0.196 unknown (not < 0.196), 0.388 unknown, 1 occupied.
        assert_eq!(read_map(&y).unwrap().to_ascii(), ".??#\n");
        let raw = format!("{GOOD_YAML}mode: raw\n");
        let y = write(dir.path(), "r.yaml", raw.as_bytes());
        // Raw: percent 0 free, 50 unknown, 99 occupied, 255 unknown.
        assert_eq!(read_map(&y).unwrap().to_ascii(), ".?#?\n");
    }

    #[test]
    fn rgb_png_is_averaged() {
        let dir = tempfile::tempdir().unwrap();
        let mut img = image::RgbImage::new(2, 1);
        img.put_pixel(0, 0, image::Rgb([255, 255, 240])); // avg 250 -> free
        img.put_pixel(1, 0, image::Rgb([0, 30, 0])); // avg 10 -> occupied
        img.save(dir.path().join("m.png")).unwrap();
        let y = write(
            dir.path(),
            "m.yaml",
            GOOD_YAML.replace("m.pgm", "m.png").as_bytes(),
        );
        assert_eq!(read_map(&y).unwrap().to_ascii(), ".#\n");
    }

    #[test]
    fn write_then_read_round_trips() {
        let g0 = OccupancyGrid::from_ascii(
            "
            #####?
            #...#?
            #.?..?
            #####?
            ",
            0.05,
        );
        let mut g = g0.clone();
        g.frame.origin_m = Vec2::new(-3.25, 7.5);
        let dir = tempfile::tempdir().unwrap();
        let y = dir.path().join("out.yaml");
        write_map(&g, &y).unwrap();
        assert!(dir.path().join("out.pgm").exists());
        let back = read_map(&y).unwrap();
        assert_eq!(back, g);
        let text = std::fs::read_to_string(&y).unwrap();
        assert!(text.contains("image: out.pgm"), "{text}");
        assert!(text.contains("origin: [-3.25, 7.5, 0.0]"), "{text}");
        let b = building_from_map(&back, "out");
        assert!((b.free_area_m2() - 6.0 * 0.05 * 0.05).abs() < 1e-12);
    }

    #[test]
    fn error_truncated_pgm() {
        let e = err_of(
            GOOD_YAML,
            &[("m.pgm", b"P5\n10 10\n255\n\x00\x00\x00".as_slice())],
        );
        assert!(e.contains("m.pgm: not a readable image"), "{e}");
        assert!(e.contains("truncated"), "{e}");
    }

    #[test]
    fn error_not_an_image() {
        let e = err_of(
            GOOD_YAML,
            &[("m.pgm", b"hello, I am a text file\n".as_slice())],
        );
        assert!(e.contains("m.pgm: not a readable image"), "{e}");
        assert!(e.contains("neither PGM/PNM nor PNG"), "{e}");
        assert!(e.contains("expected a PGM (P5/P2) or PNG"), "{e}");
    }

    #[test]
    fn error_missing_resolution() {
        let e = err_of(&GOOD_YAML.replace("resolution: 0.5\n", ""), &[]);
        assert!(e.contains("bad.yaml: resolution: missing"), "{e}");
    }

    #[test]
    fn error_missing_image() {
        let e = err_of(GOOD_YAML, &[]);
        assert!(e.contains("bad.yaml: image: "), "{e}");
        assert!(e.contains("m.pgm does not exist"), "{e}");
    }

    #[test]
    fn error_non_positive_resolution() {
        let e = err_of(&GOOD_YAML.replace("0.5", "-0.05"), &[]);
        assert!(
            e.contains(
                "bad.yaml: resolution: must be between 0.001 and 1.0 metres per pixel, got -0.05"
            ),
            "{e}"
        );
        assert!(e.contains("-0.05"), "{e}");
    }

    #[test]
    fn error_thresholds_out_of_order() {
        let y = GOOD_YAML
            .replace("occupied_thresh: 0.65", "occupied_thresh: 0.1")
            .replace("free_thresh: 0.196", "free_thresh: 0.3");
        let e = err_of(&y, &[]);
        assert!(
            e.contains("bad.yaml: free_thresh: thresholds out of order"),
            "{e}"
        );
    }

    #[test]
    fn error_yaw_unsupported() {
        let e = err_of(&GOOD_YAML.replace("-2.0, 0.0]", "-2.0, 0.3]"), &[]);
        assert!(
            e.contains("bad.yaml: unsupported: origin yaw 0.3 rad"),
            "{e}"
        );
    }

    #[test]
    fn error_not_yaml_mapping() {
        let e = err_of("[1, 2", &[]);
        assert!(e.contains("bad.yaml: invalid YAML"), "{e}");
    }
}
