//! Size budgets checked before anything is allocated: a building whose exploration grid (or a
//! map whose image, or a Stage floor plan whose raster) would need more cells than the budget is
//! refused with a message naming the budget and the flag that raises it.
//!
//! The budget is process-wide (the binary sets it once from `--max-cells`, before reading any
//! file); the default is met comfortably by every shipped map and the paper set.

use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use sim_core::Building;

use crate::error::{num, Error};

/// Default cell budget: the 0.05 m exploration grid of a 230 m x 230 m building (every shipped
/// map and paper building needs at most a fifth of it).
pub const DEFAULT_MAX_CELLS: u64 = 25_000_000;

/// The largest free area of a generated building (m²): a hospital or a terminal. A generated
/// office of 50000 m² spans about 820 m x 70 m, 28 million cells at 0.05 m, a school 25.6
/// million: above the default budget, explore them with `--max-cells 40000000` (docs/limits.md).
pub const MAX_GENERATED_AREA_M2: f64 = 50_000.0;

/// The command-line flag that raises the budget (named in messages).
pub const MAX_CELLS_FLAG: &str = "--max-cells";

/// Every coordinate of a building lies within this distance of its origin (metres): beyond it
/// the simulator's single-precision physics loses centimetres.
pub const COORDINATE_LIMIT_M: f64 = 100_000.0;

/// Resolution of the exploration map grid by default (the settings' `map_resolution_m`).
pub const EXPLORE_RESOLUTION_M: f64 = 0.05;

/// Deepest nesting of `( ... )` accepted in a Stage world file.
pub const MAX_WORLD_DEPTH: usize = 64;

static MAX_CELLS: AtomicU64 = AtomicU64::new(DEFAULT_MAX_CELLS);

/// The current cell budget.
pub fn max_cells() -> u64 {
    MAX_CELLS.load(Ordering::Relaxed)
}

/// Sets the cell budget for this process (from `--max-cells`).
pub fn set_max_cells(n: u64) {
    MAX_CELLS.store(n.max(1), Ordering::Relaxed);
}

/// Cells of a `width_m` x `height_m` grid at `resolution_m` (as f64: never overflows).
pub fn cells_for(width_m: f64, height_m: f64, resolution_m: f64) -> f64 {
    (width_m / resolution_m).ceil().max(1.0) * (height_m / resolution_m).ceil().max(1.0)
}

/// Refuses `cells` beyond the budget; `what` says what needs them.
pub fn check_cells(path: &Path, field: &str, cells: f64, what: &str) -> Result<(), Error> {
    let budget = max_cells();
    if cells.is_finite() && cells <= budget as f64 {
        return Ok(());
    }
    let n = if cells.is_finite() && cells < 1e18 {
        format!("{}", cells as u64)
    } else {
        format!("{cells:.3e}")
    };
    Err(Error::invalid(
        path,
        field,
        format!(
            "{what} needs {n} cells, more than the budget of {budget} cells; check the units (metres) or raise the budget with {MAX_CELLS_FLAG}"
        ),
    ))
}

/// Refuses a building whose exploration grid at `resolution_m` (over its bounds plus the
/// exploration margin) exceeds the budget, or whose coordinates lie beyond
/// [`COORDINATE_LIMIT_M`]. `field` names what sets the extent (`outline`, `resolution`...).
pub fn check_building(
    building: &Building,
    path: &Path,
    field: &str,
    resolution_m: f64,
) -> Result<(), Error> {
    let b = building.bounds();
    if b.is_empty() {
        return Ok(());
    }
    let far = [b.min.x, b.min.y, b.max.x, b.max.y]
        .into_iter()
        .fold(0.0f64, |m, v| {
            if v.is_nan() {
                f64::INFINITY
            } else {
                m.max(v.abs())
            }
        });
    if far > COORDINATE_LIMIT_M {
        return Err(Error::invalid(
            path,
            field,
            format!(
                "the building reaches {} m from the origin, beyond the limit of {} m; give coordinates in metres near the origin",
                num(far),
                num(COORDINATE_LIMIT_M)
            ),
        ));
    }
    let margin_m = sim_core::explore::map_margin_m(&b);
    let w = b.width_m() + 2.0 * margin_m;
    let h = b.height_m() + 2.0 * margin_m;
    check_cells(
        path,
        field,
        cells_for(w, h, resolution_m),
        &format!(
            "the building spans {} x {} m; exploring it on a {} m grid",
            num((b.width_m() * 100.0).round() / 100.0),
            num((b.height_m() * 100.0).round() / 100.0),
            num(resolution_m)
        ),
    )
}

/// Largest text file read (building, map YAML, world, grid, settings): 64 MiB.
pub const MAX_TEXT_BYTES: u64 = 64 << 20;

/// Reads a file of at most `max_bytes`, refusing what is not a regular file (a directory, a
/// device such as `/dev/zero`) or is larger, before reading it.
pub fn read_bytes(path: &Path, max_bytes: u64) -> Result<Vec<u8>, Error> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, "read", e))?;
    if !meta.is_file() {
        return Err(Error::unsupported(
            path,
            if meta.is_dir() {
                "a directory; expected a file".to_string()
            } else {
                "not a regular file; expected a file".to_string()
            },
        ));
    }
    if meta.len() > max_bytes {
        return Err(Error::unsupported(
            path,
            format!(
                "a file of {} bytes, larger than the {max_bytes} bytes read at most",
                meta.len()
            ),
        ));
    }
    let mut bytes = Vec::new();
    use std::io::Read;
    std::fs::File::open(path)
        .and_then(|f| f.take(max_bytes + 1).read_to_end(&mut bytes))
        .map_err(|e| Error::io(path, "read", e))?;
    if bytes.len() as u64 > max_bytes {
        return Err(Error::unsupported(
            path,
            format!("a file larger than the {max_bytes} bytes read at most"),
        ));
    }
    Ok(bytes)
}

/// Reads a UTF-8 text file of at most [`MAX_TEXT_BYTES`] (see [`read_bytes`]).
pub fn read_text(path: &Path) -> Result<String, Error> {
    let bytes = read_bytes(path, MAX_TEXT_BYTES)?;
    if bytes.starts_with(&[0xff, 0xfe]) || bytes.starts_with(&[0xfe, 0xff]) {
        return Err(Error::syntax(
            path,
            "UTF-16 text (it starts with a UTF-16 byte-order mark); expected UTF-8 text",
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        Error::syntax(
            path,
            format!(
                "not UTF-8 text (invalid byte at offset {}); expected a text file",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

/// Checks a coordinate against [`COORDINATE_LIMIT_M`].
pub fn coordinate_ok(v: f64) -> bool {
    v.is_finite() && v.abs() <= COORDINATE_LIMIT_M
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim_core::{Geometry, Polygon, Vec2};

    fn square(side_m: f64, at_m: f64) -> Building {
        Building {
            name: "sq".into(),
            geometry: Geometry::Vector {
                outline: Polygon::new(vec![
                    Vec2::new(at_m, at_m),
                    Vec2::new(at_m + side_m, at_m),
                    Vec2::new(at_m + side_m, at_m + side_m),
                    Vec2::new(at_m, at_m + side_m),
                ]),
                solids: Vec::new(),
            },
            rooms: Vec::new(),
            doors: Vec::new(),
            start: None,
        }
    }

    #[test]
    fn budget_cases() {
        // (side, offset, resolution, accepted, words in the message)
        let cases: &[(f64, f64, f64, bool, &str)] = &[
            (100.0, 0.0, 0.05, true, ""),
            (230.0, 0.0, 0.05, true, ""),
            (260.0, 0.0, 0.05, false, "--max-cells"),
            (35.0, 0.0, 0.01, true, ""),
            (50.0, 0.0, 0.01, false, "0.01 m grid"),
            (1e300, 0.0, 0.05, false, "beyond the limit"),
            (20_000.0, 0.0, 0.05, false, "budget of 25000000 cells"),
            (10.0, 1e6, 0.05, false, "from the origin"),
        ];
        for &(side, at, res, ok, words) in cases {
            let r = check_building(&square(side, at), Path::new("b.toml"), "outline", res);
            assert_eq!(r.is_ok(), ok, "{side} {at} {res}: {r:?}");
            if let Err(e) = r {
                let e = e.to_string();
                assert!(
                    e.starts_with("b.toml: outline: ") && e.contains(words),
                    "{e}"
                );
            }
        }
    }
}
