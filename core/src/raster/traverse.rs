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
use crate::numeric::div_floor;
use crate::setup::Edge;

/// `floor(num / den)` as `num` grows by `step` each row (`den > 0`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct FloorWalk {
    pub(crate) q: i64,
    r: i64,
    den: i64,
    sq: i64,
    sr: i64,
}

impl FloorWalk {
    pub(crate) fn new(num: i64, den: i64, step: i64) -> Self {
        let q = div_floor(num, den);
        let sq = div_floor(step, den);
        FloorWalk {
            q,
            r: num - q * den,
            den,
            sq,
            sr: step - sq * den,
        }
    }

    #[inline]
    pub(crate) fn next(&mut self) {
        self.q += self.sq;
        self.r += self.sr;
        if self.r >= self.den {
            self.r -= self.den;
            self.q += 1;
        }
    }
}

#[derive(Debug, Clone, Copy)]
enum EdgeRows {
    /// Left bound: `px >= -q`.
    Lower(FloorWalk),
    /// Right bound: `px <= q`.
    Upper(FloorWalk),
    /// Horizontal edge: the row is inside iff `num >= 0`.
    Flat { num: i64, step: i64 },
}

impl EdgeRows {
    fn new(e: &Edge, py: i64) -> Self {
        let num = e.row(py) - e.bias;
        match e.a {
            a if a > 0 => EdgeRows::Lower(FloorWalk::new(num, a, e.step)),
            a if a < 0 => EdgeRows::Upper(FloorWalk::new(num, -a, e.step)),
            _ => EdgeRows::Flat { num, step: e.step },
        }
    }

    #[inline]
    fn clip(&self, lo: &mut i64, hi: &mut i64) {
        match self {
            EdgeRows::Lower(w) => *lo = (*lo).max(-w.q),
            EdgeRows::Upper(w) => *hi = (*hi).min(w.q + 1),
            EdgeRows::Flat { num, .. } => {
                if *num < 0 {
                    *hi = *lo;
                }
            }
        }
    }

    #[inline]
    fn next(&mut self) {
        match self {
            EdgeRows::Lower(w) | EdgeRows::Upper(w) => w.next(),
            EdgeRows::Flat { num, step } => *num += *step,
        }
    }
}

/// Calls `f(py, xr, x0, x1, e1, e2)` for every row of `clip` the triangle
/// covers: the covered pixels are `x0..x1`; `xr <= x0` is the row's restart
/// point — its first covered pixel at or right of `min(clip.x, 0)`, which does
/// not depend on how the screen is cut into tiles — and `e1`, `e2` are the
/// unbiased values of edges 1 and 2 at `(xr, py)`.
pub(crate) fn for_each_span(
    e: &[Edge; 3],
    bounds: &Rect,
    clip: &Rect,
    mut f: impl FnMut(i64, i64, i64, i64, i64, i64),
) {
    let Some(r) = bounds.intersect(clip) else {
        return;
    };
    let (y0, y1) = (r.y as i64, r.y1());
    let left = (bounds.x as i64).max((clip.x as i64).min(0));
    let mut rows = [
        EdgeRows::new(&e[0], y0),
        EdgeRows::new(&e[1], y0),
        EdgeRows::new(&e[2], y0),
    ];
    for py in y0..y1 {
        let (mut lo, mut hi) = (left, bounds.x1());
        for row in &rows {
            row.clip(&mut lo, &mut hi);
        }
        let (x0, x1) = (lo.max(clip.x as i64), hi.min(clip.x1()));
        if x0 < x1 {
            f(
                py,
                lo,
                x0,
                x1,
                e[1].a * lo + e[1].row(py),
                e[2].a * lo + e[2].row(py),
            );
        }
        for row in &mut rows {
            row.next();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn floor_walk_matches_division() {
        for &(num, den, step) in &[
            (-37i64, 5i64, 13i64),
            (100, 7, -23),
            (0, 1, -1),
            (-1, 16, 16),
        ] {
            let mut w = FloorWalk::new(num, den, step);
            for k in 0..50 {
                assert_eq!(w.q, div_floor(num + k * step, den));
                w.next();
            }
        }
    }
}
