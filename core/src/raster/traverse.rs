//! Traversal (pipeline stage 4): which pixels of each row a triangle covers.
//!
//! Each edge bounds a row on one side: `a px + B(py) - bias >= 0` gives
//! `px >= ceil(-(B - bias) / a)` for `a > 0` and `px <= floor((B - bias) / -a)`
//! for `a < 0` (a horizontal edge admits the whole row or none of it). The
//! floor is tracked from row to row with an exact quotient/remainder walk
//! (Bresenham's idea applied to the edge), so traversal costs two divisions
//! per edge per tile, none per row, and no test per pixel: each covered row
//! becomes one call of the span DDA ([`crate::span`]), exactly like the
//! seed's span generation.

use crate::geom::Rect;
use crate::setup::{EdgeAt, EdgeInt};

/// `floor(num / den)` as `num` grows by `step` each row (`den > 0`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct FloorWalk<T> {
    pub(crate) q: T,
    r: T,
    den: T,
    sq: T,
    sr: T,
}

impl<T: EdgeInt> FloorWalk<T> {
    #[inline(always)]
    pub(crate) fn new(num: T, den: T, step: T) -> Self {
        let q = num.div_floor(den);
        let sq = step.div_floor(den);
        FloorWalk {
            q,
            r: num - q * den,
            den,
            sq,
            sr: step - sq * den,
        }
    }

    #[inline(always)]
    pub(crate) fn next(&mut self) {
        self.q += self.sq;
        self.r += self.sr;
        if crate::numeric::MCU32 {
            if self.r >= self.den {
                self.r = self.r - self.den;
                self.q += T::ONE;
            }
        } else {
            // Selects, not a branch: the carry follows the edge's slope,
            // a pattern a host's branch predictor misses (host, 1,077-px
            // flat triangles: 0.377 -> 0.357 ns/px, measured). The
            // microcontrollers predict no branch; a skipped branch is
            // cheaper there than conditional instructions.
            let carry = self.r >= self.den;
            self.r = self.r - if carry { self.den } else { T::ZERO };
            self.q += if carry { T::ONE } else { T::ZERO };
        }
    }
}

/// Which side of an edge's walk a row's pixels must lie on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    /// Left bound: `px >= -q`.
    Lower,
    /// Right bound: `px <= q`.
    Upper,
    /// Horizontal edge: the row is inside iff `q >= 0` (the edge's value
    /// itself, walked with `den = 1`).
    Flat,
}

/// One edge's bound on each row: a walk every kind of edge steps alike
/// (no dispatch per row; a horizontal edge's walk adds its step and never
/// carries), read by its side. With an enum of walks, dispatched in each
/// row's step, the host's large flat triangles took 1.12 ns/px against
/// 0.36 (its walks lived on the stack); the Cortex-M4 demo frame 270,878
/// -> 266,668 ticks, the micro:bit's 526,995 -> 525,142 (measured).
#[derive(Debug, Clone, Copy)]
struct EdgeRows<T> {
    side: Side,
    w: FloorWalk<T>,
}

impl<T: EdgeInt> EdgeRows<T> {
    /// The edge's bound on rows from `y0` on, in pixels right of the
    /// anchor column.
    #[inline(always)]
    fn new(e: &EdgeAt<T>, dy0: T) -> Self {
        let num = e.b + e.step * dy0 - e.bias;
        if e.a > T::ZERO {
            EdgeRows {
                side: Side::Lower,
                w: FloorWalk::new(num, e.a, e.step),
            }
        } else if e.a < T::ZERO {
            EdgeRows {
                side: Side::Upper,
                w: FloorWalk::new(num, -e.a, e.step),
            }
        } else {
            EdgeRows {
                side: Side::Flat,
                w: FloorWalk {
                    q: num,
                    r: T::ZERO,
                    den: T::ONE,
                    sq: e.step,
                    sr: T::ZERO,
                },
            }
        }
    }

    #[inline(always)]
    fn clip(&self, lo: &mut T, hi: &mut T) {
        match self.side {
            Side::Lower => *lo = (*lo).max(-self.w.q),
            Side::Upper => *hi = (*hi).min(self.w.q + T::ONE),
            Side::Flat => {
                if self.w.q < T::ZERO {
                    *hi = *lo;
                }
            }
        }
    }

    #[inline(always)]
    fn next(&mut self) {
        self.w.next();
    }
}

/// One covered row of a triangle inside a clip rectangle ([`Spans`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Row {
    /// The row.
    pub py: i64,
    /// The restart point: the row's first covered pixel at or right of
    /// `min(clip.x, 0)`, which does not depend on how the screen is cut
    /// into tiles (`xr <= x0`).
    pub xr: i64,
    /// First covered pixel inside the clip.
    pub x0: i64,
    /// One past the last.
    pub x1: i64,
    /// One past the row's last covered pixel, unclipped (`xe >= x1`):
    /// with `xr`, the whole span, whatever the tile.
    pub xe: i64,
    /// Unbiased value of edge 1 at `(xr, py)`.
    pub e1: i64,
    /// Unbiased value of edge 2 at `(xr, py)`.
    pub e2: i64,
}

/// The rows of `clip` a triangle covers, top to bottom: a small pure
/// iterator, so the span loop runs inline in the caller's `for`.
///
/// Edge values are kept relative to the anchor, the top-left pixel of the
/// triangle's `bounds`: in `T = i32` whenever the triangle's box allows
/// ([`crate::setup`]), with exactly the values `i64` would give.
#[derive(Debug, Clone)]
pub(crate) struct Spans<'a, T> {
    e: &'a [EdgeAt<T>; 3],
    rows: [EdgeRows<T>; 3],
    ax: i64,
    py: i64,
    y1: i64,
    dy: T,
    left: T,
    right: T,
    cx0: T,
    cx1: T,
}

impl<'a, T: EdgeInt> Spans<'a, T> {
    #[inline(always)]
    pub(crate) fn new(e: &'a [EdgeAt<T>; 3], bounds: &Rect, clip: &Rect) -> Self {
        let r = bounds.intersect(clip).unwrap_or(Rect::new(0, 0, 0, 0));
        let (ax, ay) = (bounds.x as i64, bounds.y as i64);
        let (y0, y1) = (r.y as i64, r.y as i64 + r.h as i64);
        let dy = T::from_i64(y0 - ay);
        Spans {
            e,
            rows: [
                EdgeRows::new(&e[0], dy),
                EdgeRows::new(&e[1], dy),
                EdgeRows::new(&e[2], dy),
            ],
            ax,
            py: y0,
            y1,
            dy,
            // In anchor-relative pixels: the restart floor, the box's right
            // end and the clip's columns.
            left: T::from_i64((clip.x as i64).min(0).max(ax) - ax),
            right: T::from_i64(bounds.w as i64),
            cx0: T::from_i64(r.x as i64 - ax),
            cx1: T::from_i64(r.x1() - ax),
        }
    }
}

impl<T: EdgeInt> Iterator for Spans<'_, T> {
    type Item = Row;

    #[inline(always)]
    fn next(&mut self) -> Option<Row> {
        while self.py < self.y1 {
            let (mut lo, mut hi) = (self.left, self.right);
            each_edge(&mut self.rows, |row| row.clip(&mut lo, &mut hi));
            let (x0, x1) = (lo.max(self.cx0), hi.min(self.cx1));
            let (py, dy) = (self.py, self.dy);
            each_edge(&mut self.rows, |row| row.next());
            self.py += 1;
            self.dy += T::ONE;
            if x0 < x1 {
                let at = |e: &EdgeAt<T>| (e.a * lo + e.b + e.step * dy).to_i64();
                return Some(Row {
                    py,
                    xr: self.ax + lo.to_i64(),
                    x0: self.ax + x0.to_i64(),
                    x1: self.ax + x1.to_i64(),
                    xe: self.ax + hi.to_i64(),
                    e1: at(&self.e[1]),
                    e2: at(&self.e[2]),
                });
            }
        }
        None
    }
}

/// Calls `f` with each of the three edges, in order: by hand on the
/// Cortex-M0, where at `opt-level = "s"` a loop over them stayed a loop (80
/// instructions a row on the large Gouraud + Z workload, measured); a loop
/// elsewhere, which the compiler unrolls (written by hand there, the
/// Cortex-M4's fast-Phong workload took 2.9% more, measured).
#[inline(always)]
fn each_edge<T>(rows: &mut [EdgeRows<T>; 3], mut f: impl FnMut(&mut EdgeRows<T>)) {
    if cfg!(target_abi = "eabi") {
        let [a, b, c] = rows;
        f(a);
        f(b);
        f(c);
    } else {
        for row in rows {
            f(row);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::div_floor;
    #[test]
    fn floor_walk_matches_division() {
        for &(num, den, step) in &[
            (-37i64, 5i64, 13i64),
            (100, 7, -23),
            (0, 1, -1),
            (-1, 16, 16),
        ] {
            let mut w = FloorWalk::new(num, den, step);
            let mut w32 = FloorWalk::new(num as i32, den as i32, step as i32);
            for k in 0..50 {
                assert_eq!(w.q, div_floor(num + k * step, den));
                assert_eq!(w32.q as i64, w.q);
                w32.next();
                w.next();
            }
        }
    }

    /// A linear congruential generator of integers in `lo..hi`.
    fn lcg(mut seed: u64) -> impl FnMut(i64, i64) -> i64 {
        move |lo, hi| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lo + ((seed >> 33) as i64 % (hi - lo))
        }
    }

    /// Every row the floor walks give is exactly the run of pixels whose
    /// centres pass all three edge tests, against a per-pixel evaluation
    /// over the whole box: thin, steep, flat-topped and flat-bottomed
    /// triangles, clips on every side.
    #[test]
    fn rows_are_the_pixels_inside_every_edge() {
        use crate::format::{Rgb, Rgb565Format};
        use crate::geom::Vertex;
        use crate::numeric::Coord;
        use crate::setup::{fits_i32, TriangleSetup};
        let mut rnd = lcg(0x0dd_ba11_5eed);
        let (mut rows, mut flat) = (0, 0);
        for k in 0..10000 {
            let r = [24, 96, 600][rnd(0, 3) as usize];
            let mut v: [Vertex; 3] = core::array::from_fn(|_| {
                Vertex::new(
                    Coord::from_bits((rnd(0, r) - 40) as i32),
                    Coord::from_bits((rnd(0, r) - 40) as i32),
                    7,
                    Rgb::new(1, 2, 3),
                )
            });
            if k % 3 == 0 {
                // A horizontal edge, on a pixel centre's row or not.
                v[1].y = v[0].y;
                flat += 1;
            }
            if !fits_i32(&v) {
                continue;
            }
            let Some(t) = TriangleSetup::<_, i32>::new::<Rgb565Format>(&v, false) else {
                continue;
            };
            let b = t.bounds;
            let clip = Rect::new(rnd(-8, 30) as i32, rnd(-8, 30) as i32, 16, 8);
            let inside = |px: i64, py: i64| {
                t.e.iter().all(|e| {
                    let (i, j) = ((px - b.x as i64) as i32, (py - b.y as i64) as i32);
                    e.a * i + e.b + e.step * j - e.bias >= 0
                })
            };
            let mut got = Spans::new(&t.e, &b, &clip);
            for py in b.y as i64..b.y as i64 + b.h as i64 {
                let cols = || b.x as i64..b.x as i64 + b.w as i64;
                // The restart floor: the row's first pixel at or right of
                // `min(clip.x, 0)`, whatever the tiling.
                let floor = (clip.x as i64).min(0);
                let run = cols().filter(|&px| px >= floor && inside(px, py));
                let cut = || {
                    run.clone()
                        .filter(|&px| px >= clip.x as i64 && px < clip.x1())
                };
                let (Some(x0), Some(x1)) = (cut().min(), cut().max()) else {
                    continue;
                };
                if py < clip.y as i64 || py >= clip.y1() {
                    continue;
                }
                let row = got.next().expect("a covered row");
                assert_eq!(row.py, py);
                assert_eq!((row.x0, row.x1), (x0, x1 + 1));
                let (xr, xe) = (run.clone().min(), run.max());
                assert_eq!((Some(row.xr), Some(row.xe - 1)), (xr, xe));
                rows += 1;
            }
            assert!(got.next().is_none(), "no further row");
        }
        assert!(rows > 5000 && flat > 1000, "{rows} rows, {flat} flat");
    }

    #[test]
    fn i32_and_i64_edges_give_the_same_spans() {
        use crate::format::{Rgb, Rgb565Format};
        use crate::geom::Vertex;
        use crate::numeric::Coord;
        use crate::setup::{fits_i32, TriangleSetup};
        let mut rnd = lcg(0x1234_5678_9abc_def0);
        let mut checked = 0;
        for _ in 0..3000 {
            let (cx, cy) = (rnd(-2000, 6000), rnd(-2000, 6000));
            let r = [8, 200, 4000, 16383][rnd(0, 4) as usize];
            let v: [Vertex; 3] = core::array::from_fn(|_| {
                Vertex::new(
                    Coord::from_bits((cx + rnd(-r / 2, r / 2)) as i32),
                    Coord::from_bits((cy + rnd(-r / 2, r / 2)) as i32),
                    7,
                    Rgb::new(1, 2, 3),
                )
            });
            if !fits_i32(&v) {
                continue;
            }
            let a = TriangleSetup::<_, i32>::new::<Rgb565Format>(&v, true);
            let b = TriangleSetup::<_, i64>::new::<Rgb565Format>(&v, true);
            let (Some(a), Some(b)) = (a, b) else {
                assert!(a.is_none() && b.is_none());
                continue;
            };
            assert_eq!((a.p.gc, a.p.gz), (b.p.gc, b.p.gz));
            let clip = Rect::new(rnd(-100, 300) as i32, rnd(-100, 300) as i32, 64, 32);
            let mut sa = [0i64; 6 * 64];
            let mut sb = [0i64; 6 * 64];
            let (mut na, mut nb) = (0, 0);
            for r in Spans::new(&a.e, &a.bounds, &clip) {
                sa[na..na + 6].copy_from_slice(&[r.py, r.xr, r.x0, r.x1, r.e1, r.e2]);
                na += 6;
            }
            for r in Spans::new(&b.e, &b.bounds, &clip) {
                sb[nb..nb + 6].copy_from_slice(&[r.py, r.xr, r.x0, r.x1, r.e1, r.e2]);
                nb += 6;
            }
            assert_eq!(sa[..na], sb[..nb]);
            checked += na;
        }
        assert!(checked > 1000);
    }
}
