//! The per-block depth summary (seed 004 §3.2, the "pixel cache" the
//! occlusion unit reads): for each `2^SHIFT`-square block of the tile, the
//! nearest and farthest stored depth.
//!
//! It is kept **per command, not per fragment**. A tile cleared to one
//! depth starts exact ([`HiZ::reset_to`]). A depth-tested command no nearer
//! than `z` lowers its blocks' nearest depth to `z` and leaves their
//! farthest as it was ([`HiZ::touch_near`]): a passing fragment only brings
//! a pixel nearer, so each block holds *bounds* on its depths, which decide
//! as much as exact values do whenever `z` lies outside them. Anything else
//! marks its blocks stale ([`HiZ::touch`]). A test reads a block only when
//! the bounds straddle its depth (or the block is stale), and then
//! refreshes it to exact values in the same pass. The raster loops carry
//! nothing for it, and a frame that does not cull has no summary at all.
//! (Bounds instead of stale marks after each command: the M4 city walk's
//! depth reads 55,216 -> 50,694 over 8 frames.)

use crate::config::TileConfig;
use crate::fragment::DepthPlane;
use crate::geom::Rect;
use crate::tile::Tile;

/// What a box test did, summed ([`super::CullStats`] adds it up).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TestCost {
    /// Pixels the tested rectangles cover.
    pub fragments: u64,
    /// Depth values read to decide (pixels scanned plus blocks refreshed).
    pub reads: u64,
}

/// Nearest and farthest depth of each block of a tile: `4 BLOCKS` bytes.
///
/// `BLOCKS` must hold `ceil(w / 2^SHIFT) * ceil(h / 2^SHIFT)` blocks for the
/// tile's `w x h`; a tile with more blocks is tested pixel by pixel (the
/// same answers, more reads). `SHIFT` (block side `2^SHIFT`, 2..=5) is the
/// knob `tilerast-lab cull-report` measures.
///
/// ```
/// use tilerast::prelude::*;
/// use tilerast::occlusion::HiZ;
/// type T = Tile<{ groups(16, 16) }, Planes<Rgb565Format, Depth16>>;
/// let mut tile = T::new();
/// tile.begin(Rect::new(0, 0, 16, 16), &Clear::default())?;
/// let mut hiz: HiZ<4, 3> = HiZ::new();
/// hiz.reset(tile.area());
/// // A wall at depth 100 over the left half...
/// tile.draw(&Command::zfill(Rect::new(0, 0, 8, 16), 100))?;
/// hiz.touch(&Rect::new(0, 0, 8, 16));
/// // ...hides a box behind it, not one in front or beside it.
/// let mut cost = Default::default();
/// let all = u32::MAX;
/// assert_eq!(hiz.count(&tile, Rect::new(0, 0, 8, 8), 200, true, all, &mut cost), 0);
/// assert_eq!(hiz.count(&tile, Rect::new(0, 0, 8, 8), 50, true, all, &mut cost), 64);
/// assert_eq!(hiz.count(&tile, Rect::new(4, 0, 8, 1), 200, true, all, &mut cost), 4);
/// // Visible at all? The test stops at the first visible fragment.
/// assert_eq!(hiz.count(&tile, Rect::new(4, 0, 8, 1), 200, true, 1, &mut cost), 1);
/// # Ok::<(), Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct HiZ<const BLOCKS: usize, const SHIFT: u32 = 3> {
    /// Per block: bounds on the nearest and farthest depth (exact after a
    /// refresh); `min > max` marks a stale block.
    min: [u16; BLOCKS],
    max: [u16; BLOCKS],
    area: Rect,
    cols: u32,
    active: bool,
}

impl<const BLOCKS: usize, const SHIFT: u32> Default for HiZ<BLOCKS, SHIFT> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const BLOCKS: usize, const SHIFT: u32> HiZ<BLOCKS, SHIFT> {
    const SHIFT_OK: () = assert!(SHIFT >= 2 && SHIFT <= 5, "block side 4..=32");

    /// An empty summary (call [`HiZ::reset`] for each tile). `const`, so it
    /// can be a `static`.
    pub const fn new() -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::SHIFT_OK;
        HiZ {
            min: [1; BLOCKS],
            max: [0; BLOCKS],
            area: Rect::new(0, 0, 0, 0),
            cols: 0,
            active: false,
        }
    }

    /// Bytes the summary holds.
    pub const fn bytes() -> usize {
        4 * BLOCKS
    }

    /// Starts a tile: every block stale.
    pub fn reset(&mut self, area: Rect) {
        self.start(area, 1, 0);
    }

    /// Starts a tile whose depth plane was cleared to `depth`: every block
    /// exact, nothing to read until something is drawn.
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// use tilerast::occlusion::{HiZ, TestCost};
    /// type T = Tile<{ groups(16, 16) }, Planes<Rgb565Format, Depth16>>;
    /// let mut tile = T::new();
    /// tile.begin(Rect::new(0, 0, 16, 16), &Clear::default())?;
    /// let mut hiz: HiZ<4, 3> = HiZ::new();
    /// hiz.reset_to(tile.area(), u16::MAX);
    /// let mut cost = TestCost::default();
    /// assert_eq!(hiz.count(&tile, Rect::new(0, 0, 16, 16), 7, true, u32::MAX, &mut cost), 256);
    /// assert_eq!(cost.reads, 0); // decided from the summary alone
    /// # Ok::<(), Error>(())
    /// ```
    pub fn reset_to(&mut self, area: Rect, depth: u16) {
        self.start(area, depth, depth);
    }

    /// Starts a tile with every block's bounds `lo..=hi`.
    fn start(&mut self, area: Rect, lo: u16, hi: u16) {
        let side = 1u32 << SHIFT;
        let (cols, rows) = (area.w.div_ceil(side), area.h.div_ceil(side));
        self.area = area;
        self.cols = cols;
        self.active = (cols * rows) as usize <= BLOCKS;
        if self.active {
            let n = (cols * rows) as usize;
            self.min[..n].fill(lo);
            self.max[..n].fill(hi);
        }
    }

    /// Notes depth-tested drawing inside `r` (screen pixels) whose
    /// fragments are no nearer than `z`: each up-to-date block's nearest
    /// depth becomes at most `z`, its farthest stays (a passing fragment
    /// only brings a pixel nearer), so the block keeps bounds and needs no
    /// refresh until a test's depth falls between them. For drawing that is
    /// not depth-tested, or whose depth is unknown, call [`HiZ::touch`].
    ///
    /// ```
    /// use tilerast::prelude::*;
    /// use tilerast::occlusion::{HiZ, TestCost};
    /// type T = Tile<{ groups(16, 16) }, Planes<Rgb565Format, Depth16>>;
    /// let mut tile = T::new();
    /// tile.begin(Rect::new(0, 0, 16, 16), &Clear::default())?;
    /// let mut hiz: HiZ<4, 3> = HiZ::new();
    /// hiz.reset_to(tile.area(), u16::MAX);
    /// // A depth-tested wall at depth 100 over the left half.
    /// let v = |x: i32, y: i32| Vertex::new(Coord::from_num(x), Coord::from_num(y), 100, Rgb::default());
    /// for t in [[v(0, 0), v(8, 0), v(8, 16)], [v(0, 0), v(8, 16), v(0, 16)]] {
    ///     tile.draw(&Command::Triangle { v: t, state: State::default() })?;
    /// }
    /// hiz.touch_near(&Rect::new(0, 0, 8, 16), 100);
    /// let mut cost = TestCost::default();
    /// // Nearer than anything there: decided without a read.
    /// assert_eq!(hiz.count(&tile, Rect::new(0, 0, 8, 8), 50, true, u32::MAX, &mut cost), 64);
    /// assert_eq!(cost.reads, 0);
    /// // Behind the wall: the block is read once and becomes exact...
    /// assert_eq!(hiz.count(&tile, Rect::new(0, 0, 8, 8), 200, true, u32::MAX, &mut cost), 0);
    /// let reads = cost.reads;
    /// // ...so the next test behind it reads nothing.
    /// assert_eq!(hiz.count(&tile, Rect::new(0, 0, 8, 8), 300, true, u32::MAX, &mut cost), 0);
    /// assert_eq!(cost.reads, reads);
    /// # Ok::<(), Error>(())
    /// ```
    pub fn touch_near(&mut self, r: &Rect, z: u16) {
        self.each_block_run(r, |min, max| {
            for (lo, &hi) in min.iter_mut().zip(max.iter()) {
                // (A stale block, `lo > hi`, stays stale.)
                if *lo <= hi {
                    *lo = (*lo).min(z);
                }
            }
        });
    }

    /// Marks the blocks under `r` (screen pixels) stale: call it after
    /// drawing anything inside `r` that may write depth.
    pub fn touch(&mut self, r: &Rect) {
        self.each_block_run(r, |min, max| {
            min.fill(1);
            max.fill(0);
        });
    }

    /// Calls `f` with the nearest and farthest bounds of the blocks under
    /// `r` (screen pixels), one block row at a time; not at all when the
    /// summary is off or `r` misses the tile.
    #[inline(always)]
    fn each_block_run(&mut self, r: &Rect, mut f: impl FnMut(&mut [u16], &mut [u16])) {
        if !self.active {
            return;
        }
        let Some(r) = r.intersect(&self.area) else {
            return;
        };
        let (bx0, by0, bx1, by1) = self.blocks(&r);
        for by in by0..=by1 {
            let row = (by * self.cols) as usize;
            let run = row + bx0 as usize..=row + bx1 as usize;
            f(&mut self.min[run.clone()], &mut self.max[run]);
        }
    }

    /// Block columns and rows `(x0, y0, x1, y1)` (inclusive) under `r`,
    /// which lies inside the tile.
    fn blocks(&self, r: &Rect) -> (u32, u32, u32, u32) {
        let (ox, oy) = ((r.x - self.area.x) as u32, (r.y - self.area.y) as u32);
        (
            ox >> SHIFT,
            oy >> SHIFT,
            (ox + r.w - 1) >> SHIFT,
            (oy + r.h - 1) >> SHIFT,
        )
    }

    /// How many pixels of `r` hold a depth farther than `z`: the visible
    /// fragments of a box at depth `z` over `r`, nothing written — counted
    /// up to `limit` (the test stops there; `u32::MAX` for the exact
    /// count). With `summary`, blocks whose bounds lie on one side of `z`
    /// are decided from them and only blocks that straddle `z` (or are
    /// stale) are read, row by row, and refreshed to exact bounds when the
    /// test read all of it. Without, every pixel up to the limit is read (what
    /// an occlusion query's pass over the box costs). The count is the
    /// same either way. A summary last reset for another rectangle than
    /// `tile`'s is reset to the tile's first.
    pub fn count<const N: usize, C: TileConfig>(
        &mut self,
        tile: &Tile<N, C>,
        r: Rect,
        z: u16,
        summary: bool,
        limit: u32,
        cost: &mut TestCost,
    ) -> u32 {
        // A summary reset for another rectangle than the tile's would
        // index the depth plane wrongly: it follows the tile instead.
        if self.area != tile.area {
            self.reset(tile.area);
        }
        let Some(r) = r.intersect(&self.area) else {
            return 0;
        };
        cost.fragments += r.area();
        if !summary || !self.active {
            return Self::scan(tile, &r, z, limit, cost);
        }
        // Tile-local pixel bounds, half-open.
        let a = self.area;
        let (ox, oy) = ((r.x - a.x) as u32, (r.y - a.y) as u32);
        let (ex, ey) = (ox + r.w, oy + r.h);
        let (bx0, by0, bx1, by1) = (
            ox >> SHIFT,
            oy >> SHIFT,
            (ex - 1) >> SHIFT,
            (ey - 1) >> SHIFT,
        );
        let cols = self.cols as usize;
        // First the up-to-date blocks nearer-than-`z` everywhere: a test
        // that only asks "visible at all?" ends here, having read nothing.
        let mut n = 0;
        for by in by0..=by1 {
            let h = ey.min((by + 1) << SHIFT) - oy.max(by << SHIFT);
            for bx in bx0..=bx1 {
                let b = by as usize * cols + bx as usize;
                if self.min[b] <= self.max[b] && self.min[b] > z {
                    n += h * (ex.min((bx + 1) << SHIFT) - ox.max(bx << SHIFT));
                    if n >= limit {
                        return n;
                    }
                }
            }
        }
        let w = a.w as usize;
        for by in by0..=by1 {
            let (y0, y1) = (oy.max(by << SHIFT), ey.min((by + 1) << SHIFT));
            let whole_y = y0 == by << SHIFT && y1 == a.h.min((by + 1) << SHIFT);
            for bx in bx0..=bx1 {
                let b = by as usize * cols + bx as usize;
                let (lo, hi) = (self.min[b], self.max[b]);
                let fresh = lo <= hi;
                if fresh && (hi <= z || lo > z) {
                    // Hidden, or counted above.
                    continue;
                }
                let (x0, x1) = (ox.max(bx << SHIFT), ex.min((bx + 1) << SHIFT));
                let rows = (y0..y1).map(|y| {
                    let at = y as usize * w + x0 as usize;
                    at..at + (x1 - x0) as usize
                });
                if whole_y && x0 == bx << SHIFT && x1 == a.w.min((bx + 1) << SHIFT) {
                    // Stale or loose, and wholly tested: count and refresh
                    // in one pass, row by row, stopping at the limit (the
                    // block then keeps what it had).
                    let (mut l, mut h, mut whole) = (u16::MAX, 0, true);
                    for run in rows {
                        cost.reads += run.len() as u64;
                        let (c, rl, rh) = tile.depth.farther_min_max(run, z);
                        (n, l, h) = (n + c, l.min(rl), h.max(rh));
                        if n >= limit {
                            whole = false;
                            break;
                        }
                    }
                    if whole {
                        (self.min[b], self.max[b]) = (l, h);
                    }
                } else {
                    for run in rows {
                        if n >= limit {
                            break;
                        }
                        cost.reads += run.len() as u64;
                        n += tile.depth.farther(run, z, limit - n);
                    }
                }
                if n >= limit {
                    return n;
                }
            }
        }
        n
    }

    /// Pixels of `r` (inside the tile) farther than `z`, up to `limit`.
    fn scan<const N: usize, C: TileConfig>(
        tile: &Tile<N, C>,
        r: &Rect,
        z: u16,
        limit: u32,
        cost: &mut TestCost,
    ) -> u32 {
        let mut n = 0;
        for run in Self::runs(tile, r) {
            if n >= limit {
                break;
            }
            cost.reads += run.len() as u64;
            n += tile.depth.farther(run, z, limit - n);
        }
        n
    }

    /// The depth-plane index ranges of `r`'s rows (clipped to the tile: a
    /// summary reset for another rectangle reads nothing outside it).
    #[inline(always)]
    fn runs<const N: usize, C: TileConfig>(
        tile: &Tile<N, C>,
        r: &Rect,
    ) -> impl Iterator<Item = core::ops::Range<usize>> {
        let a = tile.area;
        let w = a.w as usize;
        let r = r.intersect(&a).unwrap_or(Rect::new(a.x, a.y, 0, 0));
        let (x0, len) = ((r.x - a.x) as usize, r.w as usize);
        (r.y..r.y + r.h as i32).map(move |y| {
            let at = (y - a.y) as usize * w + x0;
            at..at + len
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::command::Command;
    use crate::config::Planes;
    use crate::format::Rgb565Format;
    use crate::fragment::Depth16;
    use crate::tile::Clear;

    /// A summary reset for a larger rectangle than the tile's counts the
    /// tile's pixels, not past its depth plane.
    #[test]
    fn summary_for_another_rectangle_follows_the_tile() {
        let mut tile: Tile<32, Planes<Rgb565Format, Depth16>> = Tile::new();
        tile.begin(Rect::new(0, 0, 16, 16), &Clear::default())
            .unwrap();
        tile.draw(&Command::zfill(Rect::new(0, 0, 8, 16), 100))
            .unwrap();
        let mut hiz: HiZ<64, 3> = HiZ::new();
        hiz.reset(Rect::new(-40, -40, 64, 64));
        let mut cost = TestCost::default();
        let all = u32::MAX;
        for summary in [true, false] {
            let n = hiz.count(
                &tile,
                Rect::new(-8, -8, 64, 64),
                200,
                summary,
                all,
                &mut cost,
            );
            assert_eq!(n, 16 * 8);
        }
    }
}
