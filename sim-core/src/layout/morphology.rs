//! Binary masks packed 64 cells to a word, and their dilation by a square: the thin-unknown fill
//! and the cells near a wall are dilations of a window of the map (millions of cells, every
//! layout), and a word holds 64 of them.

use crate::grid::{Cell, GridFrame, Occupancy, OccupancyGrid};

/// A `width` x `height` mask, row-major, each row in whole 64-bit words: cell `x` of a row is
/// bit `x % 64` of the row's word `x / 64`. Bits past `width` are kept zero.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BitRows {
    width: usize,
    height: usize,
    /// Words per row.
    stride: usize,
    words: Vec<u64>,
}

impl BitRows {
    /// All false.
    pub fn new(width: usize, height: usize) -> Self {
        let stride = width.div_ceil(64);
        Self {
            width,
            height,
            stride,
            words: vec![0; stride * height],
        }
    }

    /// From a row-major mask of `width` x `height` cells.
    pub fn from_bools(src: &[bool], width: usize, height: usize) -> Self {
        assert_eq!(src.len(), width * height, "the mask must be width x height");
        let mut out = Self::new(width, height);
        for (y, row) in src.chunks_exact(width.max(1)).enumerate().take(height) {
            out.set_row(y, row);
        }
        out
    }

    /// The cells of `grid` in the window `(x0, y0, width, height)` (inside the grid) for which
    /// `pred` holds.
    pub fn from_grid(
        grid: &OccupancyGrid,
        (x0, y0, width, height): (usize, usize, usize, usize),
        pred: impl Fn(Occupancy) -> bool,
    ) -> Self {
        let w = grid.frame.width as usize;
        let mut out = Self::new(width, height);
        let select = StateSelect::new(pred);
        for y in 0..height {
            let start = (y0 + y) * w + x0;
            let row = &grid.data[start..start + width];
            for (k, cells) in row.chunks(64).enumerate() {
                let word = select.pack(cells) & out.valid_bits(k);
                out.row_mut(y)[k] = word;
            }
        }
        out
    }

    /// Sets row `y` from one bool per cell of the row.
    pub(crate) fn set_row(&mut self, y: usize, cells: &[bool]) {
        assert_eq!(cells.len(), self.width, "a row has width cells");
        for (word, block) in self.row_mut(y).iter_mut().zip(cells.chunks(64)) {
            *word = pack_bools(block);
        }
    }

    /// Whether a cell of row `y` in columns `a..=b` (clamped to the mask) is true.
    pub(crate) fn any_in(&self, y: usize, a: i64, b: i64) -> bool {
        let (a, b) = (a.max(0), b.min(self.width as i64 - 1));
        if y >= self.height || a > b {
            return false;
        }
        let (a, b) = (a as usize, b as usize);
        let row = self.row(y);
        let (ka, kb) = (a / 64, b / 64);
        (ka..=kb).any(|k| {
            let lo = if k == ka { a % 64 } else { 0 };
            let hi = if k == kb { b % 64 } else { 63 };
            let mask = (u64::MAX >> (63 - hi)) & (u64::MAX << lo);
            row[k] & mask != 0
        })
    }

    /// Row-major, one bool per cell.
    pub fn to_bools(&self) -> Vec<bool> {
        (0..self.height)
            .flat_map(|y| (0..self.width).map(move |x| (x, y)))
            .map(|(x, y)| self.get(x, y))
            .collect()
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    /// Cell `(x, y)`; false outside the mask.
    pub fn get(&self, x: usize, y: usize) -> bool {
        x < self.width && y < self.height && {
            let word = self.words[y * self.stride + x / 64];
            word >> (x % 64) & 1 == 1
        }
    }

    /// The words of row `y`.
    pub fn row(&self, y: usize) -> &[u64] {
        &self.words[y * self.stride..(y + 1) * self.stride]
    }

    fn row_mut(&mut self, y: usize) -> &mut [u64] {
        &mut self.words[y * self.stride..(y + 1) * self.stride]
    }

    /// The bits of word `k` of a row that are cells (not past the width).
    pub(crate) fn valid_bits(&self, k: usize) -> u64 {
        let end = self.width - (k * 64).min(self.width);
        if end >= 64 {
            u64::MAX
        } else {
            (1u64 << end) - 1
        }
    }

    /// Number of true cells.
    pub fn count_ones(&self) -> usize {
        self.words.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// Every cell flipped.
    pub(crate) fn invert(&mut self) {
        self.words.iter_mut().for_each(|w| *w = !*w);
        self.clear_padding();
    }

    fn clear_padding(&mut self) {
        if self.stride == 0 {
            return;
        }
        let last = self.valid_bits(self.stride - 1);
        for row in self.words.chunks_exact_mut(self.stride) {
            row[self.stride - 1] &= last;
        }
    }

    /// Dilated by a square of half-side `radius` cells (cells outside the mask are false): the
    /// result of `dilate_reference` (test support), cell for cell. Separable; each axis is a few passes that OR
    /// the mask shifted both ways (radii 1, 2, 4...: a dilation by `R` followed by one by
    /// `{-s, 0, s}`, `s <= R + 1`, is one by `R + s`, also where the mask's edge clips it), a
    /// word of 64 cells at a time.
    pub(crate) fn dilate(&self, radius: usize) -> BitRows {
        let mut a = self.clone();
        if radius == 0 || self.width == 0 || self.height == 0 {
            return a;
        }
        let n = self.stride;
        let mut b = a.clone();
        // Rows.
        let mut r = 0;
        while r < radius {
            let s = (r + 1).min(radius - r);
            if s < self.width {
                for (ra, rb) in a.words.chunks_exact(n).zip(b.words.chunks_exact_mut(n)) {
                    rb.copy_from_slice(ra);
                    or_shifted_bits(rb, ra, s);
                }
                std::mem::swap(&mut a, &mut b);
                a.clear_padding();
            } else {
                for y in 0..self.height {
                    let any = a.row(y).iter().any(|w| *w != 0);
                    a.row_mut(y).fill(if any { u64::MAX } else { 0 });
                }
                a.clear_padding();
            }
            r += s;
        }
        // Columns: whole words, rows `s` apart.
        let mut r = 0;
        while r < radius {
            let s = (r + 1).min(radius - r);
            if s < self.height {
                b.words.copy_from_slice(&a.words);
                or_shifted_words(&mut b.words, &a.words, s * n);
                std::mem::swap(&mut a, &mut b);
            } else {
                let mut any = vec![0u64; n];
                for row in a.words.chunks_exact(n) {
                    any.iter_mut().zip(row).for_each(|(x, v)| *x |= *v);
                }
                for row in a.words.chunks_exact_mut(n) {
                    row.copy_from_slice(&any);
                }
            }
            r += s;
        }
        a
    }
}

/// The bits of up to 64 bools, bool `i` in bit `i`, 8 at a time (a bool is a byte of 0 or 1).
#[inline]
fn pack_bools(cells: &[bool]) -> u64 {
    let mut out = 0u64;
    for (k, eight) in cells.chunks(8).enumerate() {
        let mut bytes = [0u8; 8];
        for (b, c) in bytes.iter_mut().zip(eight) {
            *b = *c as u8;
        }
        out |= gather_low_bits(u64::from_le_bytes(bytes)) << (8 * k);
    }
    out
}

/// Bit `i`: the low bit of byte `i` of `x`, whose bytes are 0 or 1.
#[inline(always)]
fn gather_low_bits(x: u64) -> u64 {
    x.wrapping_mul(0x0102_0408_1020_4080) >> 56
}

/// Which of the three states a mask selects, applied to the cells' bytes 8 at a time.
struct StateSelect {
    /// Per state (by its byte value), whether it is selected.
    table: [bool; 3],
}

impl StateSelect {
    fn new(pred: impl Fn(Occupancy) -> bool) -> Self {
        Self {
            table: [Occupancy::Unknown, Occupancy::Free, Occupancy::Occupied].map(pred),
        }
    }

    /// Bit `i` of the result: whether cell `i` is selected (up to 64 cells).
    #[inline]
    fn pack(&self, cells: &[Occupancy]) -> u64 {
        if let Ok(whole) = <&[Occupancy; 64]>::try_from(cells) {
            // (Fixed lengths: the compiler unrolls the loops and loads 8 bytes at once.)
            let mut out = 0u64;
            for k in 0..8 {
                let bytes: [u8; 8] = std::array::from_fn(|i| whole[8 * k + i] as u8);
                out |= self.pack8(bytes) << (8 * k);
            }
            return out;
        }
        let mut out = 0u64;
        for (k, eight) in cells.chunks(8).enumerate() {
            let mut bytes = [0u8; 8];
            for (b, c) in bytes.iter_mut().zip(eight) {
                *b = *c as u8;
            }
            out |= self.pack8(bytes) << (8 * k);
        }
        out
    }

    /// Bit `i`: whether the state of byte `i` is selected.
    #[inline(always)]
    fn pack8(&self, bytes: [u8; 8]) -> u64 {
        const ONES: u64 = 0x0101_0101_0101_0101;
        // Per byte (0, 1 or 2): 1 where the state is selected, then the bytes' low bits
        // gathered into eight bits.
        let x = u64::from_le_bytes(bytes);
        let (one, two) = (x & ONES, (x >> 1) & ONES);
        let zero = !(one | two) & ONES;
        let sel = (zero * self.table[0] as u64)
            | (one * self.table[1] as u64)
            | (two * self.table[2] as u64);
        gather_low_bits(sel)
    }
}

/// `dst[i] |= src[i - s] | src[i + s]` on whole words, where those exist.
fn or_shifted_words(dst: &mut [u64], src: &[u64], s: usize) {
    let n = src.len();
    if s >= n {
        return;
    }
    for (d, v) in dst[s..].iter_mut().zip(&src[..n - s]) {
        *d |= *v;
    }
    for (d, v) in dst[..n - s].iter_mut().zip(&src[s..]) {
        *d |= *v;
    }
}

/// On one row of words: `dst` gets the cells of `src` moved `s` cells right and `s` cells left
/// (cells moved past either end of the row's words are dropped).
fn or_shifted_bits(dst: &mut [u64], src: &[u64], s: usize) {
    let n = src.len();
    let (q, r) = (s / 64, (s % 64) as u32);
    if q >= n {
        return;
    }
    // Cell x to x + s: word i takes word i - q shifted up, and the top of word i - q - 1.
    for i in q..n {
        let lo = src[i - q] << r;
        let carry = if r > 0 && i > q {
            src[i - q - 1] >> (64 - r)
        } else {
            0
        };
        dst[i] |= lo | carry;
    }
    // Cell x to x - s: word i takes word i + q shifted down, and the bottom of word i + q + 1.
    for i in 0..n - q {
        let hi = src[i + q] >> r;
        let carry = if r > 0 && i + q + 1 < n {
            src[i + q + 1] << (64 - r)
        } else {
            0
        };
        dst[i] |= hi | carry;
    }
}

/// A mask over a window of a grid's frame: cells outside the window are false.
#[derive(Debug, Clone, PartialEq)]
pub struct WindowMask {
    pub frame: GridFrame,
    /// The window's first cell.
    x0: usize,
    y0: usize,
    bits: BitRows,
}

impl WindowMask {
    /// Nothing true.
    pub fn empty(frame: GridFrame) -> Self {
        Self {
            frame,
            x0: 0,
            y0: 0,
            bits: BitRows::new(0, 0),
        }
    }

    /// `bits` placed with its first cell at `(x0, y0)` of `frame`.
    pub fn new(frame: GridFrame, x0: usize, y0: usize, bits: BitRows) -> Self {
        Self {
            frame,
            x0,
            y0,
            bits,
        }
    }

    pub fn get(&self, c: Cell) -> bool {
        // (A cell left of or above the window wraps to a column or row far past it.)
        let x = (c.x as i64 - self.x0 as i64) as usize;
        let y = (c.y as i64 - self.y0 as i64) as usize;
        self.bits.get(x, y)
    }

    pub fn count_true(&self) -> usize {
        self.bits.count_ones()
    }
}

/// The reference dilation (per cell, the last true cell before and after in each row, then in
/// each column, over the whole mask): what [`BitRows::dilate`] replaced; kept to check it.
#[cfg(any(test, feature = "test-support"))]
pub(crate) fn dilate_reference(src: &[bool], w: usize, h: usize, radius: usize) -> Vec<bool> {
    let mut rows = vec![false; w * h];
    let mut line = Vec::new();
    for y in 0..h {
        dilate_1d(&src[y * w..(y + 1) * w], radius, &mut line);
        rows[y * w..(y + 1) * w].copy_from_slice(&line);
    }
    let mut out = rows.clone();
    let mut last = vec![usize::MAX; w];
    for y in 0..h {
        let row = &rows[y * w..(y + 1) * w];
        for x in 0..w {
            if row[x] {
                last[x] = y;
            }
            if last[x] != usize::MAX && y - last[x] <= radius {
                out[y * w + x] = true;
            }
        }
    }
    last.fill(usize::MAX);
    for y in (0..h).rev() {
        let row = &rows[y * w..(y + 1) * w];
        for x in 0..w {
            if row[x] {
                last[x] = y;
            }
            if last[x] != usize::MAX && last[x] - y <= radius {
                out[y * w + x] = true;
            }
        }
    }
    out
}

/// `out[i]` is true when some `src[j]` with `|i - j| <= radius` is.
#[cfg(any(test, feature = "test-support"))]
fn dilate_1d(src: &[bool], radius: usize, out: &mut Vec<bool>) {
    let n = src.len();
    out.clear();
    out.resize(n, false);
    // Distance to the last true on the left, then on the right.
    let mut last: Option<usize> = None;
    for i in 0..n {
        if src[i] {
            last = Some(i);
        }
        if last.is_some_and(|j| i - j <= radius) {
            out[i] = true;
        }
    }
    last = None;
    for i in (0..n).rev() {
        if src[i] {
            last = Some(i);
        }
        if last.is_some_and(|j| j - i <= radius) {
            out[i] = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The packed dilation is the reference's, on masks of any width (less than a word, a
        /// word and a bit, several words), density and radius (past the width and height too).
        #[test]
        fn dilation_is_the_reference(
            w in 1usize..200,
            h in 1usize..12,
            density in 0.0f64..0.2,
            radius in 0usize..140,
            seed in any::<u64>(),
        ) {
            use rand::{Rng, SeedableRng};
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let src: Vec<bool> = (0..w * h).map(|_| rng.random_bool(density)).collect();
            let bits = BitRows::from_bools(&src, w, h);
            prop_assert_eq!(bits.to_bools(), src.clone());
            let got = bits.dilate(radius);
            prop_assert_eq!(got.to_bools(), dilate_reference(&src, w, h, radius));
            // Bits past the width stay clear.
            prop_assert_eq!(got.count_ones(), got.to_bools().iter().filter(|b| **b).count());
            let mut inverted = got.clone();
            inverted.invert();
            prop_assert_eq!(inverted.count_ones(), w * h - got.count_ones());
        }
    }

    proptest! {
        /// `any_in` is a scan of the cells, for any span (empty, past either end, across words);
        /// `set_row` sets exactly the row's cells.
        #[test]
        fn any_in_is_a_scan(
            w in 1usize..200,
            density in 0.0f64..0.05,
            a in -10i64..210,
            len in -3i64..140,
            seed in any::<u64>(),
        ) {
            use rand::{Rng, SeedableRng};
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let row: Vec<bool> = (0..w).map(|_| rng.random_bool(density)).collect();
            let mut bits = BitRows::new(w, 2);
            bits.set_row(1, &row);
            prop_assert_eq!(bits.to_bools(), [vec![false; w], row.clone()].concat());
            let b = a + len;
            let want = (a.max(0)..=b.min(w as i64 - 1)).any(|x| row[x as usize]);
            prop_assert_eq!(bits.any_in(1, a, b), want);
            prop_assert!(!bits.any_in(0, a, b));
            prop_assert!(!bits.any_in(2, a, b));
        }
    }

    #[test]
    fn dilation_is_square() {
        let mut out = Vec::new();
        dilate_1d(&[false, false, true, false, false, false], 2, &mut out);
        assert_eq!(out, vec![true, true, true, true, true, false]);
        let bits = BitRows::from_bools(&[false, false, true, false, false, false], 6, 1);
        assert_eq!(bits.dilate(2).to_bools(), out);
    }

    #[test]
    fn a_window_mask_is_false_outside_its_window() {
        let frame = GridFrame::new(crate::geom::Vec2::zeros(), 0.1, 10, 10);
        let bits = BitRows::from_bools(&[true; 6], 3, 2);
        let m = WindowMask::new(frame, 4, 5, bits);
        let inside: Vec<Cell> = (0..10)
            .flat_map(|y| (0..10).map(move |x| Cell::new(x, y)))
            .filter(|c| m.get(*c))
            .collect();
        assert_eq!(inside.len(), 6);
        assert!(inside
            .iter()
            .all(|c| (4..7).contains(&c.x) && (5..7).contains(&c.y)));
        assert!(!m.get(Cell::new(-1, 5)) && !m.get(Cell::new(4, -1)));
        assert!(!WindowMask::empty(frame).get(Cell::new(0, 0)));
    }
}
