//! Regular grids over the world plane: frames, cells, occupancy.
//!
//! Convention: cell `(0, 0)` is the *lower-left* cell; its lower-left corner is the frame's
//! `origin`. Rows grow with world `y` (so an image's top row is the grid's last row). Storage is
//! row-major: index `y * width + x`.

use crate::geom::{floor_i32, Aabb, Vec2};

/// A grid cell. Signed so that neighbours of border cells can be formed and then rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Cell {
    pub x: i32,
    pub y: i32,
}

impl Cell {
    pub const fn new(x: i32, y: i32) -> Self {
        Self { x, y }
    }
    /// 4-neighbours.
    pub fn neighbours4(self) -> [Cell; 4] {
        [
            Cell::new(self.x + 1, self.y),
            Cell::new(self.x - 1, self.y),
            Cell::new(self.x, self.y + 1),
            Cell::new(self.x, self.y - 1),
        ]
    }
    /// 8-neighbours.
    pub fn neighbours8(self) -> [Cell; 8] {
        [
            Cell::new(self.x + 1, self.y),
            Cell::new(self.x - 1, self.y),
            Cell::new(self.x, self.y + 1),
            Cell::new(self.x, self.y - 1),
            Cell::new(self.x + 1, self.y + 1),
            Cell::new(self.x - 1, self.y + 1),
            Cell::new(self.x + 1, self.y - 1),
            Cell::new(self.x - 1, self.y - 1),
        ]
    }
}

/// Where a grid lies in the world and how fine it is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridFrame {
    /// World position of the lower-left corner of cell (0, 0).
    pub origin_m: Vec2,
    pub resolution_m: f64,
    pub width: u32,
    pub height: u32,
}

impl GridFrame {
    pub fn new(origin_m: Vec2, resolution_m: f64, width: u32, height: u32) -> Self {
        Self {
            origin_m,
            resolution_m,
            width,
            height,
        }
    }

    /// The smallest frame at `resolution_m` covering `bounds` plus `margin_m` on every side.
    pub fn covering(bounds: &Aabb, resolution_m: f64, margin_m: f64) -> Self {
        if bounds.is_empty() {
            return Self::new(Vec2::zeros(), resolution_m, 0, 0);
        }
        let origin = bounds.min - Vec2::new(margin_m, margin_m);
        let w = ((bounds.width_m() + 2.0 * margin_m) / resolution_m)
            .ceil()
            .max(0.0) as u32;
        let h = ((bounds.height_m() + 2.0 * margin_m) / resolution_m)
            .ceil()
            .max(0.0) as u32;
        Self::new(origin, resolution_m, w, h)
    }

    pub fn len(&self) -> usize {
        self.width as usize * self.height as usize
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    pub fn cell_area_m2(&self) -> f64 {
        self.resolution_m * self.resolution_m
    }
    pub fn contains(&self, c: Cell) -> bool {
        c.x >= 0 && c.y >= 0 && (c.x as u32) < self.width && (c.y as u32) < self.height
    }
    /// Row-major index of a cell that is inside the grid.
    pub fn index(&self, c: Cell) -> Option<usize> {
        self.contains(c)
            .then(|| c.y as usize * self.width as usize + c.x as usize)
    }
    pub fn cell_of_index(&self, i: usize) -> Cell {
        let w = self.width as usize;
        Cell::new((i % w) as i32, (i / w) as i32)
    }
    /// The cell containing a world point (may be outside the grid).
    pub fn cell_from_world(&self, p: Vec2) -> Cell {
        let q = (p - self.origin_m) / self.resolution_m;
        Cell::new(floor_i32(q.x), floor_i32(q.y))
    }
    /// World position of a cell's centre.
    pub fn world_from_cell(&self, c: Cell) -> Vec2 {
        self.origin_m + Vec2::new(c.x as f64 + 0.5, c.y as f64 + 0.5) * self.resolution_m
    }
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: self.origin_m,
            max: self.origin_m
                + Vec2::new(self.width as f64, self.height as f64) * self.resolution_m,
        }
    }
}

/// A dense grid of values.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid<T> {
    pub frame: GridFrame,
    pub data: Vec<T>,
}

impl<T: Clone> Grid<T> {
    pub fn filled(frame: GridFrame, value: T) -> Self {
        Self {
            data: vec![value; frame.len()],
            frame,
        }
    }
    pub fn get(&self, c: Cell) -> Option<&T> {
        self.frame.index(c).map(|i| &self.data[i])
    }
    pub fn get_mut(&mut self, c: Cell) -> Option<&mut T> {
        self.frame.index(c).map(move |i| &mut self.data[i])
    }
    pub fn set(&mut self, c: Cell, v: T) {
        if let Some(i) = self.frame.index(c) {
            self.data[i] = v;
        }
    }
    pub fn width(&self) -> u32 {
        self.frame.width
    }
    pub fn height(&self) -> u32 {
        self.frame.height
    }
    /// Iterates over `(cell, value)` in row-major order.
    pub fn iter(&self) -> impl Iterator<Item = (Cell, &T)> + '_ {
        self.data
            .iter()
            .enumerate()
            .map(|(i, v)| (self.frame.cell_of_index(i), v))
    }
}

/// A boolean mask (e.g. ground-truth free space).
pub type Bitmap = Grid<bool>;

impl Bitmap {
    pub fn count_true(&self) -> usize {
        self.data.iter().filter(|b| **b).count()
    }
}

/// The three states of a cell of an occupancy map.
/// (One byte, with these values: masks of many cells are made from the bytes 8 at a time.)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[repr(u8)]
pub enum Occupancy {
    #[default]
    Unknown = 0,
    Free = 1,
    Occupied = 2,
}

/// A ternary occupancy map: what the layout method and the frontier detector read.
pub type OccupancyGrid = Grid<Occupancy>;

impl OccupancyGrid {
    pub fn count(&self, state: Occupancy) -> usize {
        self.data.iter().filter(|s| **s == state).count()
    }

    pub fn is(&self, c: Cell, state: Occupancy) -> bool {
        self.get(c) == Some(&state)
    }

    /// Parses an ASCII map, for tests and examples: `#` occupied, `.` free, anything else
    /// (space, `?`) unknown. The first text line is the *top* row. Leading/trailing blank lines
    /// are dropped; lines may have different lengths (missing cells are unknown).
    pub fn from_ascii(text: &str, resolution_m: f64) -> Self {
        let lines: Vec<&str> = text
            .lines()
            .map(|l| l.trim_end_matches(['\r']))
            .skip_while(|l| l.trim().is_empty())
            .collect();
        let lines: Vec<&str> = {
            let mut v = lines;
            while v.last().is_some_and(|l| l.trim().is_empty()) {
                v.pop();
            }
            v
        };
        let indent = lines
            .iter()
            .filter(|l| !l.trim().is_empty())
            .map(|l| l.len() - l.trim_start().len())
            .min()
            .unwrap_or(0);
        let rows: Vec<Vec<char>> = lines
            .iter()
            .map(|l| l.chars().skip(indent).collect())
            .collect();
        let h = rows.len() as u32;
        let w = rows.iter().map(|r| r.len()).max().unwrap_or(0) as u32;
        let frame = GridFrame::new(Vec2::zeros(), resolution_m, w, h);
        let mut g = Grid::filled(frame, Occupancy::Unknown);
        for (r, row) in rows.iter().enumerate() {
            let y = h as i32 - 1 - r as i32;
            for (x, ch) in row.iter().enumerate() {
                let s = match ch {
                    '#' => Occupancy::Occupied,
                    '.' => Occupancy::Free,
                    _ => Occupancy::Unknown,
                };
                g.set(Cell::new(x as i32, y), s);
            }
        }
        g
    }

    /// The inverse of [`OccupancyGrid::from_ascii`] (`?` for unknown).
    pub fn to_ascii(&self) -> String {
        let mut s = String::new();
        for y in (0..self.height() as i32).rev() {
            for x in 0..self.width() as i32 {
                s.push(match self.get(Cell::new(x, y)) {
                    Some(Occupancy::Occupied) => '#',
                    Some(Occupancy::Free) => '.',
                    _ => '?',
                });
            }
            s.push('\n');
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_round_trip_and_orientation() {
        let g = OccupancyGrid::from_ascii(
            "
            ###
            #.?
            ",
            0.1,
        );
        assert_eq!((g.width(), g.height()), (3, 2));
        // Top text row is the grid's last row.
        assert_eq!(g.get(Cell::new(0, 1)), Some(&Occupancy::Occupied));
        assert_eq!(g.get(Cell::new(1, 0)), Some(&Occupancy::Free));
        assert_eq!(g.get(Cell::new(2, 0)), Some(&Occupancy::Unknown));
        assert_eq!(g.to_ascii(), "###\n#.?\n");
    }

    #[test]
    fn world_cell_round_trip() {
        let f = GridFrame::new(Vec2::new(-1.0, 2.0), 0.05, 100, 50);
        let c = Cell::new(17, 33);
        assert_eq!(f.cell_from_world(f.world_from_cell(c)), c);
        assert_eq!(f.index(Cell::new(100, 0)), None);
        assert_eq!(f.cell_of_index(f.index(c).unwrap()), c);
    }
}
