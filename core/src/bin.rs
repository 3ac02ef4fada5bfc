//! Binning (pipeline stage 3): one pass over a frame's commands sorts them
//! into per-tile lists, so each tile then walks only the commands that touch
//! it — the way tile-based GPUs work. Before it, every tile decoded and
//! bounds-tested every command of the list (83% of a demo frame on the
//! Cortex-M4, measured under QEMU).
//!
//! **Memory is the user's choice.** [`Bins<CAP, TILES>`](Bins) holds `CAP`
//! (tile, command) entries and the lists of `TILES` tiles, in
//! `8 CAP + 16 TILES` bytes, with no allocation. A frame whose entries do not
//! fit is still rendered, correctly: the pass that overflows still counts
//! each tile's entries, and from those counts its tiles are cut into bands
//! that fit, each binned by one more pass over the commands, and a single tile that
//! alone overflows the bins replays the whole list (the unbinned path). [`FrameStats`](crate::frame::FrameStats) counts both. `Bins<0, 0>`
//! costs nothing and always takes the unbinned path.
//!
//! A band's tiles and their entry counts are known before its pass, so a
//! band does not link its entries: it lays each tile's keys out flat, where
//! the counts put them (a counting sort), in the link words too — `2 CAP`
//! entries a band, half as many passes (the micro:bit's demo frame: 12
//! passes before, 7 after). When every key is below 2^16 (a source of fewer
//! than 65,536 commands: keys are ordinals) two keys share a word: `4 CAP`
//! entries a band (the same frame: 4 passes, `reports/targets.md`). Binning reads
//! only what it needs of each command ([`CommandSource::each_bounds`](crate::frame::CommandSource::each_bounds)):
//! an encoded mesh's triangles, their vertices' positions.
//!
//! Entries are appended in command order, so a tile replays its commands in
//! list order and binning cannot change a pixel.

use crate::geom::Rect;

/// "No entry": the end of a tile's list.
const NONE: u32 = u32::MAX;

/// Per-tile command lists for one band of tiles: `CAP` entries, `TILES`
/// list heads. Each entry holds a command's key (its position in the
/// [`CommandSource`](crate::frame::CommandSource)) and the next entry of the
/// same tile.
///
/// ```
/// use tilerast::prelude::*;
/// use tilerast::bin::Bins;
/// // 2048 (tile, command) entries and up to 32 tiles per pass: 16.9 KB.
/// static BINS: Bins<2048, 32> = Bins::new();
/// assert_eq!(Bins::<2048, 32>::BYTES, 8 * 2048 + 16 * 32);
/// ```
#[derive(Debug, Clone)]
pub struct Bins<const CAP: usize, const TILES: usize> {
    /// Entries each tile asked for in the last pass, stored or not.
    count: [u32; TILES],
    /// The counts of the last pass that overflowed: the plan its window's
    /// bands are cut from.
    plan: [u32; TILES],
    head: [u32; TILES],
    tail: [u32; TILES],
    key: [u32; CAP],
    next: [u32; CAP],
    len: usize,
    /// Whether a push since the last reset found no room.
    full: bool,
    /// Whether the lists are flat ([`Self::reset_flat`]): tile `t`'s keys
    /// fill slots `tail[t - 1]..head[t]` of the `2 CAP` words of `key` and
    /// `next` together (`head` is its write cursor, `tail` its end).
    flat: bool,
    /// The last (largest) key pushed since the last [`Self::reset`].
    top: u32,
    /// Whether flat lists hold 16-bit keys, two a word (`4 CAP` slots):
    /// the planning pass met no key of 2^16 or more.
    narrow: bool,
}

impl<const CAP: usize, const TILES: usize> Default for Bins<CAP, TILES> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const CAP: usize, const TILES: usize> Bins<CAP, TILES> {
    /// Bytes the bins occupy.
    pub const BYTES: usize = 8 * CAP + 16 * TILES;

    /// Empty bins (`const`: they can be a `static`).
    pub const fn new() -> Self {
        Bins {
            count: [0; TILES],
            plan: [0; TILES],
            head: [NONE; TILES],
            tail: [NONE; TILES],
            key: [0; CAP],
            next: [NONE; CAP],
            len: 0,
            full: false,
            flat: false,
            top: 0,
            narrow: false,
        }
    }

    /// Whether these bins can bin anything (`CAP` and `TILES` non-zero).
    pub const fn enabled() -> bool {
        CAP > 0 && TILES > 0
    }

    /// Empties the lists of the first `tiles` tiles.
    pub(crate) fn reset(&mut self, tiles: usize) {
        self.count[..tiles].fill(0);
        self.head[..tiles].fill(NONE);
        self.tail[..tiles].fill(NONE);
        self.len = 0;
        self.full = false;
        self.flat = false;
        self.top = 0;
        self.narrow = false;
    }

    /// Empties the lists of the first `tiles` tiles as flat lists sized by
    /// the plan from its tile `from` on ([`Self::keep_plan`]): a counting
    /// sort, no link per entry, so a band holds `2 CAP` entries, `4 CAP`
    /// when they are narrow ([`Self::keep_plan`]; its tiles are chosen by
    /// [`Self::plan_fit`]).
    pub(crate) fn reset_flat(&mut self, from: usize, tiles: usize) {
        let mut end = 0;
        for t in 0..tiles {
            self.head[t] = end;
            end += self.plan[from + t];
            self.tail[t] = end;
        }
        self.count[..tiles].fill(0);
        self.len = end as usize;
        self.flat = true;
        self.full = false;
    }

    /// Word `i` of the flat lists (`i < 2 CAP`).
    #[inline(always)]
    fn word(&mut self, i: usize) -> Option<&mut u32> {
        match i.checked_sub(CAP) {
            None => self.key.get_mut(i),
            Some(j) => self.next.get_mut(j),
        }
    }

    /// Stores `key` in slot `i` of the flat lists: word `i`, or with
    /// narrow keys half `i % 2` of word `i / 2`.
    #[inline(always)]
    fn set_slot(&mut self, i: usize, key: u32) -> bool {
        if !self.narrow {
            return self.word(i).map(|w| *w = key).is_some();
        }
        let shift = 16 * (i as u32 & 1);
        self.word(i / 2)
            .map(|w| *w = *w & !(0xFFFF << shift) | key << shift)
            .is_some()
    }

    /// The key in slot `i` of the flat lists ([`Self::set_slot`]).
    #[inline(always)]
    fn slot_key(&self, i: usize) -> Option<u32> {
        let w = if self.narrow { i / 2 } else { i };
        let word = match w.checked_sub(CAP) {
            None => self.key.get(w).copied(),
            Some(j) => self.next.get(j).copied(),
        }?;
        Some(if self.narrow {
            word >> (16 * (i as u32 & 1)) & 0xFFFF
        } else {
            word
        })
    }

    /// Entries used.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Appends `key` to tile `t`'s list, or marks the bins
    /// [full](Self::full). One copy of the binning pass serves both kinds
    /// of list: a copy per kind saved the micro:bit's demo frame 0.19 M
    /// instructions for 3.5 KB more `.text` (measured with `llvm-size`).
    #[inline(always)]
    pub(crate) fn push(&mut self, t: usize, key: u32) {
        if self.flat {
            self.push_flat(t, key)
        } else {
            self.push_linked(t, key)
        }
    }

    /// Appends `key` to tile `t`'s flat list, or marks the bins
    /// [full](Self::full). No count and no largest key: only a linked
    /// pass's plan reads them ([`Self::keep_plan`]).
    #[inline(always)]
    fn push_flat(&mut self, t: usize, key: u32) {
        let at = self.head[t];
        if at >= self.tail[t] || !self.set_slot(at as usize, key) {
            self.full = true;
            return;
        }
        self.head[t] = at + 1;
    }

    /// Appends `key` to tile `t`'s linked list, or marks the bins
    /// [full](Self::full) (the tile's count still grows).
    #[inline(always)]
    fn push_linked(&mut self, t: usize, key: u32) {
        self.count[t] += 1;
        // Keys increase (`CommandSource::each_keyed`): the last is the
        // largest.
        self.top = key;
        let n = self.len;
        if n >= CAP {
            self.full = true;
            return;
        }
        self.key[n] = key;
        self.next[n] = NONE;
        match self.tail[t] {
            NONE => self.head[t] = n as u32,
            last => self.next[last as usize] = n as u32,
        }
        self.tail[t] = n as u32;
        self.len = n + 1;
    }

    /// Whether a push since the last reset found no room (kept here, not
    /// returned: a flag per push cost the binning loop 5 instructions an
    /// entry on the Cortex-M4, measured).
    pub(crate) fn full(&self) -> bool {
        self.full
    }

    /// Keeps the last pass's counts of its first `tiles` tiles as the plan;
    /// its bands' keys are narrow when every key it met was below 2^16.
    pub(crate) fn keep_plan(&mut self, tiles: usize) {
        self.plan[..tiles].copy_from_slice(&self.count[..tiles]);
        self.narrow = self.top <= 0xFFFF;
    }

    /// How many planned tiles from `from` (of `len`) fit the bins together
    /// as flat lists ([`Self::reset_flat`]).
    pub(crate) fn plan_fit(&self, from: usize, len: usize) -> usize {
        let mut sum = 0usize;
        self.plan[from..from + len]
            .iter()
            .take_while(|&&c| {
                sum += c as usize;
                sum <= if self.narrow { 4 * CAP } else { 2 * CAP }
            })
            .count()
    }

    /// Tile `t`'s keys, in the order they were pushed.
    pub(crate) fn keys(&self, t: usize) -> impl Iterator<Item = u32> + '_ {
        let flat = self.flat;
        let (mut at, end) = match (flat, t.checked_sub(1)) {
            (false, _) => (self.head[t], NONE),
            (true, None) => (0, self.head[t]),
            (true, Some(p)) => (self.tail[p], self.head[t]),
        };
        core::iter::from_fn(move || {
            if flat {
                if at >= end {
                    return None;
                }
                at += 1;
                return self.slot_key(at as usize - 1);
            }
            let i = *self.key.get(at as usize)?;
            at = self.next[at as usize];
            Some(i)
        })
    }
}

/// A screen's tile grid: which tiles a rectangle touches.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Grid {
    /// Screen size.
    pub w: u32,
    /// Screen size.
    pub h: u32,
    /// Tile size.
    pub tw: u32,
    /// Tile size.
    pub th: u32,
    /// Tiles per row.
    pub cols: u32,
    /// Tile rows.
    pub rows: u32,
}

/// A divisor that is a shift when it is a power of two (nearly every tile
/// size): a division is a library call of ~100 instructions on the
/// Cortex-M0, and so is finding the shift (no `clz` there), four per command
/// per binning pass (measured) — so the shift is found once per pass.
#[derive(Debug, Clone, Copy)]
struct By {
    d: u32,
    /// `log2 d`, or 32 when `d` is not a power of two.
    shift: u32,
}

impl By {
    fn new(d: u32) -> Self {
        let shift = if d.is_power_of_two() {
            d.trailing_zeros()
        } else {
            32
        };
        By { d, shift }
    }

    #[inline(always)]
    fn div(self, v: u32) -> u32 {
        if self.shift < 32 {
            v >> self.shift
        } else {
            v / self.d
        }
    }
}

impl Grid {
    /// [`GridSpans::span`] for many rectangles: the tile sizes' shifts
    /// found once ([`By`]).
    pub fn spans(&self) -> GridSpans {
        GridSpans {
            w: self.w,
            h: self.h,
            tw: By::new(self.tw),
            th: By::new(self.th),
        }
    }
}

/// Which tiles of a [`Grid`] a rectangle touches, the divisions prepared
/// ([`Grid::spans`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct GridSpans {
    w: u32,
    h: u32,
    tw: By,
    th: By,
}

impl GridSpans {
    /// The tiles `r` touches, as inclusive column and row ranges; `None`
    /// when it is off screen.
    #[inline]
    pub fn span(&self, r: &Rect) -> Option<(u32, u32, u32, u32)> {
        let (x0, x1) = Self::axis(r.x, r.w, self.w, self.tw)?;
        let (y0, y1) = Self::axis(r.y, r.h, self.h, self.th)?;
        Some((x0, x1, y0, y1))
    }

    /// The tiles of size `by` that pixels `[at, at + len)` meet on a screen
    /// `max` pixels wide: 32-bit arithmetic only (with `i64` ends the
    /// micro:bit's demo frame binned in 0.7 M instructions more, measured).
    /// Pixels on the screen (a mesh's triangles) take the short way,
    /// `at <= last < max`, which rules out a negative start and an empty
    /// or wrapping length at once; the rest are clamped out of line, and
    /// both share the divisions (a second copy of them cost the micro:bit's
    /// demo binning 22% more, measured; the M4 teapot's binning, 215 -> 179
    /// instructions a triangle).
    #[inline(always)]
    fn axis(at: i32, len: u32, max: u32, by: By) -> Option<(u32, u32)> {
        let (a, last) = (at as u32, (at as u32).wrapping_add(len.wrapping_sub(1)));
        let (lo, hi) = if a <= last && last < max {
            (a, last)
        } else {
            Self::clamp(at, len, max)?
        };
        Some((by.div(lo), by.div(hi)))
    }

    /// The on-screen pixels of `[at, at + len)` (inclusive), `None` when
    /// there are none.
    #[cold]
    #[inline(never)]
    fn clamp(at: i32, len: u32, max: u32) -> Option<(u32, u32)> {
        if at >= max as i32 {
            return None;
        }
        // The last pixel, when it is on screen.
        let last = match u32::try_from(at) {
            Ok(a) => a.saturating_add(len.checked_sub(1)?),
            Err(_) => len.checked_sub(at.unsigned_abs() + 1)?,
        };
        Some((at.max(0) as u32, last.min(max - 1)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::xorshift;

    /// The tiles a rectangle meets, from its pixels in `i64`: every pixel
    /// of the rectangle on the screen, its tile column and row.
    fn reference(g: &Grid, r: &Rect) -> Option<(u32, u32, u32, u32)> {
        let clip = |at: i32, len: u32, max: u32| {
            let (lo, hi) = (
                (at as i64).max(0),
                (at as i64 + len as i64 - 1).min(max as i64 - 1),
            );
            (lo <= hi).then_some((lo as u32, hi as u32))
        };
        let (x0, x1) = clip(r.x, r.w, g.w)?;
        let (y0, y1) = clip(r.y, r.h, g.h)?;
        Some((x0 / g.tw, x1 / g.tw, y0 / g.th, y1 / g.th))
    }

    /// [`GridSpans::span`]'s short way (on screen) and its clamped way
    /// give the tiles of the rectangle's on-screen pixels, for tile sizes
    /// that are powers of two and others, over rectangles on the screen,
    /// across its edges, off it, empty, and with extreme corners and sizes.
    #[test]
    fn spans_are_the_on_screen_pixels_tiles() {
        let mut next = xorshift(0x5eed_b175);
        let (mut short, mut clamped) = (0, 0);
        for (w, h, tw, th) in [
            (240u32, 240u32, 64u32, 32u32),
            (96, 64, 32, 16),
            (100, 75, 24, 10),
            (1, 1, 1, 1),
        ] {
            let rows = h.div_ceil(th);
            let cols = w.div_ceil(tw);
            let g = Grid {
                w,
                h,
                tw,
                th,
                cols,
                rows,
            };
            let spans = g.spans();
            for i in 0..20_000u32 {
                let v: [u64; 4] = core::array::from_fn(|_| next());
                let r = if i % 4 == 0 {
                    // Extreme corners and sizes.
                    let at = [i32::MIN, -1, 0, 1, w as i32 - 1, w as i32, i32::MAX];
                    let size = [0, 1, 2, u32::MAX / 2, u32::MAX - 1, u32::MAX];
                    let (a, s) = (|k: u64| at[k as usize % 7], |k: u64| size[k as usize % 6]);
                    Rect::new(a(v[0]), a(v[1]), s(v[2]), s(v[3]))
                } else if i % 4 == 1 {
                    // On the screen.
                    let (x, y) = ((v[0] % w as u64) as u32, (v[1] % h as u64) as u32);
                    let (rw, rh) = (1 + v[2] % (w - x) as u64, 1 + v[3] % (h - y) as u64);
                    Rect::new(x as i32, y as i32, rw as u32, rh as u32)
                } else {
                    // Around the screen.
                    let at = |k: u64, m: u32| (k % (3 * m as u64 + 8)) as i32 - m as i32 - 4;
                    let len = |k: u64, m: u32| (k % (2 * m as u64 + 2)) as u32;
                    Rect::new(at(v[0], w), at(v[1], h), len(v[2], w), len(v[3], h))
                };
                let got = spans.span(&r);
                assert_eq!(got, reference(&g, &r), "{r:?} in {g:?}");
                let on = r.x >= 0
                    && r.y >= 0
                    && r.w > 0
                    && r.h > 0
                    && r.x as u64 + r.w as u64 <= w as u64
                    && r.y as u64 + r.h as u64 <= h as u64;
                if on {
                    short += 1
                } else {
                    clamped += 1
                }
            }
        }
        // Both ways were taken, many times.
        assert!(short > 20_000 && clamped > 20_000, "{short} {clamped}");
    }
}
