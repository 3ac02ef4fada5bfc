//! Texture coordinates along a span (seed 001 §IV.3): what a textured
//! triangle's rows step through ([`crate::texture`] explains the modes).
//!
//! Every attribute is read at a point of the triangle from the same exact
//! barycentric weights the Gouraud restart uses (`E_i inv`, 30 fraction
//! bits, [`crate::setup`]), so a value depends on the point alone, never on
//! the tile. Per span, at the row's first covered pixel `xr`, its last
//! `xr + n` and (for the quadratic) its middle `xr + n/2` — the whole
//! covered row, whatever the tile:
//!
//! - `u = s / q`, `v = t / q` (perspective) or `u`, `v` themselves
//!   (affine), 32.32 texels;
//! - the quadratic mode cuts the span into *segments* at the screen
//!   columns that are multiples of [`SEGMENT`] (so a tile whose side and
//!   origin are multiples of it meets one segment a row; the first and last
//!   of a span shorter) and per segment of `m` pixels
//!   steps the quadratic `f(k) = f0 + B k + A k^2` through the exact
//!   `f(0)`, `f(m/2)`, `f(m)` as `f += d; d += dd` with
//!   `dd = 2A = 4 c / m^2`, `d(0) = A + B = 2 c / m^2 + (f(m) - f(0) - 2 c) / m`,
//!   `c = f(0) - 2 f(m/2) + f(m)` (shifts for a whole segment); a tile
//!   entering at `k` starts from `f0 + k d0 + k (k - 1)/2 dd`, the same
//!   integers the steps reach. Segments bound the error whatever the span:
//!   one quadratic over a 216-pixel span of a wall at depth ratio 3 is off
//!   by a texel (measured, `tests/tests/texture.rs`), and the interpolation
//!   error falls with the cube of the length;
//! - the shade is linear along the span.

use crate::format::Lanes;
use crate::numeric::{Divisor, W_FRAC};
use crate::raster::traverse::Row;
use crate::setup::{EdgeInt, TriangleSetup};
use crate::texture::{TexVertex, PERSPECTIVE_EXACT, PERSPECTIVE_QUADRATIC};

/// A textured triangle's attributes relative to its first vertex, in the
/// set-up triangle's vertex order.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TexSetup {
    /// `s = u q`, `t = v q`, `q` (vertex 0's value and the deltas to
    /// vertices 1 and 2); `u`, `v` affine; the shade.
    f0: [i64; 6],
    d: [[i64; 6]; 2],
    /// Edge steps per pixel along x, edges 1 and 2.
    a: [i64; 2],
    /// `2^62 / area2`: the weights' scale (the Gouraud setup computes it
    /// only for the configurations that restart rows exactly).
    inv: i64,
}

/// Indices into [`TexSetup`]'s attributes.
const S: usize = 0;
const T: usize = 1;
const Q: usize = 2;
const UA: usize = 3;
const VA: usize = 4;
const L: usize = 5;

/// Pixels per segment of the quadratic mode: a power of two, so that a
/// whole segment's differences are shifts.
pub(crate) const SEGMENT_BITS: u32 = 5;
/// Pixels per segment of the quadratic mode (the last of a span shorter).
pub(crate) const SEGMENT: i64 = 1 << SEGMENT_BITS;

/// The state a span loop steps: coordinates and their first and second
/// differences (32.32 texels), the shade and its step (8.16); for the
/// exact mode the edge values at the current pixel; for the quadratic
/// mode the pixels left in the segment, the next segment's offset from
/// `xr` and the exact coordinates there (the segment's end), the span's
/// last offset and its edge values at `xr`.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct TexSpan {
    pub u: [i64; 3],
    pub v: [i64; 3],
    pub l: i32,
    pub dl: i32,
    pub e: [i64; 2],
    left: i64,
    next: i64,
    end: (i64, i64),
    n: i64,
    /// `xr` modulo [`SEGMENT`]: where the screen's segment grid falls.
    phase: i64,
}

/// `1/m` for the segment lengths `m` in `1..SEGMENT` (a partial segment at a
/// span's ends), computed at compile time: no division per segment.
const BY_M: [Divisor; SEGMENT as usize] = {
    let mut t = [Divisor::new(1); SEGMENT as usize];
    let mut m = 1;
    while m < SEGMENT as usize {
        t[m] = Divisor::new(m as i64);
        m += 1;
    }
    t
};

impl TexSetup {
    pub(crate) fn new<Ln: Lanes, Tn: EdgeInt>(
        tv: &[TexVertex; 3],
        shade: &[u8; 3],
        t: &TriangleSetup<Ln, Tn>,
    ) -> Self {
        let attr = |k: usize| {
            let (v, q) = (&tv[k], tv[k].q as i64);
            [
                v.u as i64 * q,
                v.v as i64 * q,
                q,
                v.u as i64,
                v.v as i64,
                shade[k] as i64,
            ]
        };
        let (k1, k2) = if t.swapped { (2, 1) } else { (1, 2) };
        let (f0, f1, f2) = (attr(0), attr(k1), attr(k2));
        TexSetup {
            f0,
            d: [
                core::array::from_fn(|i| f1[i] - f0[i]),
                core::array::from_fn(|i| f2[i] - f0[i]),
            ],
            a: [t.e[1].a.to_i64(), t.e[2].a.to_i64()],
            inv: (1i64 << 62) / t.area2,
        }
    }

    /// Barycentric weights `w1, w2` (30 fraction bits) at the unbiased
    /// edge values `e1`, `e2`, as [`TriangleSetup`]'s restart computes them.
    #[inline(always)]
    fn weights(&self, e1: i64, e2: i64) -> (i64, i64) {
        (
            (e1 * self.inv) >> (62 - W_FRAC),
            (e2 * self.inv) >> (62 - W_FRAC),
        )
    }

    /// Attribute `i` at the point with unbiased edge values `e`, weights
    /// scaled back by `2^shift` (30 fraction bits less `shift`).
    #[inline(always)]
    fn lerp(&self, i: usize, w: (i64, i64), shift: u32) -> i64 {
        (self.d[0][i] * w.0 + self.d[1][i] * w.1) >> shift
    }

    /// `(u, v)` in 32.32 texels at a point of weights `w`: `s / q`, `t / q`
    /// (perspective) or the affine coordinates.
    #[inline(always)]
    pub(crate) fn uv<const PERSPECTIVE: bool>(&self, w: (i64, i64)) -> (i64, i64) {
        if PERSPECTIVE {
            // s, t, q with 8 more fraction bits: s < 2^40, so s 2^20 fits;
            // one reciprocal of q serves both quotients (exact, rounded).
            let f = |i: usize| (self.f0[i] << 8) + self.lerp(i, w, 22);
            let q = Divisor::new(f(Q).max(1));
            (q.round(f(S) << 20) << 8, q.round(f(T) << 20) << 8)
        } else {
            let f = |i: usize| (self.f0[i] << 28) + self.lerp(i, w, 2);
            (f(UA), f(VA))
        }
    }

    /// The weights at offset `m2 / 2` pixels from the span start, whose
    /// edge values are `e` (the edge steps are even).
    #[inline(always)]
    fn at(&self, e: [i64; 2], m2: i64) -> (i64, i64) {
        self.weights(e[0] + self.a[0] / 2 * m2, e[1] + self.a[1] / 2 * m2)
    }

    /// The span state at the tile's first pixel `x0` of `row`.
    #[inline(always)]
    pub(crate) fn span<const MODE: u8>(&self, row: &Row, x0: i64) -> TexSpan {
        let n = row.xe - 1 - row.xr;
        let k = x0 - row.xr;
        let e = [row.e1, row.e2];
        let (w0, w1) = (self.at(e, 0), self.at(e, 2 * n));
        let shade = |w| ((self.f0[L] << 16) + self.lerp(L, w, 14)) as i32;
        let (l0, l1) = (shade(w0), shade(w1));
        // One reciprocal of the span's length serves its steps.
        let per_px = Divisor::new(n.max(1));
        let dl = per_px.round((l1 - l0) as i64) as i32;
        let mut s = TexSpan {
            l: l0 + dl * k as i32,
            dl,
            n,
            e,
            ..TexSpan::default()
        };
        match MODE {
            PERSPECTIVE_EXACT => {
                s.e = [row.e1 + self.a[0] * k, row.e2 + self.a[1] * k];
                s.u[0] = self.a[0];
                s.v[0] = self.a[1];
            }
            PERSPECTIVE_QUADRATIC => {
                s.phase = row.xr & (SEGMENT - 1);
                let first = (((k + s.phase) & !(SEGMENT - 1)) - s.phase).max(0);
                s.end = self.uv::<true>(self.at(e, 2 * first));
                self.segment(&mut s, first);
                advance(&mut s.u, k - first);
                advance(&mut s.v, k - first);
                s.left -= k - first;
            }
            _ => {
                let (p0, p1) = (self.uv::<false>(w0), self.uv::<false>(w1));
                let (du, dv) = (per_px.round(p1.0 - p0.0), per_px.round(p1.1 - p0.1));
                s.u = [p0.0, du, 0];
                s.v = [p0.1, dv, 0];
                advance(&mut s.u, k);
                advance(&mut s.v, k);
            }
        }
        s
    }

    /// Loads the quadratic segment starting `first` pixels into the span,
    /// whose exact start coordinates are `s.end`.
    #[inline(never)]
    fn segment(&self, s: &mut TexSpan, first: i64) {
        let m = (SEGMENT - ((first + s.phase) & (SEGMENT - 1))).min(s.n - first);
        let p0 = s.end;
        let (pm, p1) = if m > 0 {
            (
                self.uv::<true>(self.at(s.e, 2 * first + m)),
                self.uv::<true>(self.at(s.e, 2 * (first + m))),
            )
        } else {
            (p0, p0)
        };
        let steps = |f0: i64, fm: i64, f1: i64| -> [i64; 3] {
            if m == 0 {
                return [f0, 0, 0];
            }
            let c = f0 - 2 * fm + f1;
            let (d1, d2) = if m == SEGMENT {
                // div_round by a power of two: the same integers, shifted.
                let r = |x: i64, b: u32| (x + (1 << (b - 1))) >> b;
                (
                    r(2 * c, 2 * SEGMENT_BITS) + r(f1 - f0 - 2 * c, SEGMENT_BITS),
                    r(4 * c, 2 * SEGMENT_BITS),
                )
            } else {
                // `/ m^2` as `/ m` twice (rounded twice: within 2^-31
                // texel of one rounding).
                let by_m = BY_M[m as usize];
                let sq = |x: i64| by_m.round(by_m.round(x));
                (sq(2 * c) + by_m.round(f1 - f0 - 2 * c), sq(4 * c))
            };
            [f0, d1, d2]
        };
        s.u = steps(p0.0, pm.0, p1.0);
        s.v = steps(p0.1, pm.1, p1.1);
        s.end = p1;
        s.left = if m == 0 { i64::MAX } else { m };
        s.next = first + m;
    }
}

/// A coordinate's state `[f, d, dd]` advanced `k` steps in closed form:
/// the same integers `k` steps reach (modulo 2^64).
#[inline(always)]
fn advance(f: &mut [i64; 3], k: i64) {
    let tri = (k * (k - 1) / 2).wrapping_mul(f[2]);
    f[0] = f[0].wrapping_add(k.wrapping_mul(f[1])).wrapping_add(tri);
    f[1] = f[1].wrapping_add(k.wrapping_mul(f[2]));
}

/// One pixel on: the exact mode's edges step (`u[0]`, `v[0]` hold their
/// steps), the others' coordinates; the quadratic mode loads the next
/// segment at a segment's end.
#[inline(always)]
pub(crate) fn step<const MODE: u8>(ts: &TexSetup, s: &mut TexSpan) {
    if MODE == PERSPECTIVE_EXACT {
        s.e[0] += s.u[0];
        s.e[1] += s.v[0];
    } else if MODE == PERSPECTIVE_QUADRATIC {
        s.left -= 1;
        if s.left == 0 {
            ts.segment(s, s.next);
        } else {
            s.u[0] = s.u[0].wrapping_add(s.u[1]);
            s.v[0] = s.v[0].wrapping_add(s.v[1]);
            s.u[1] = s.u[1].wrapping_add(s.u[2]);
            s.v[1] = s.v[1].wrapping_add(s.v[2]);
        }
    } else {
        s.u[0] = s.u[0].wrapping_add(s.u[1]);
        s.v[0] = s.v[0].wrapping_add(s.v[1]);
    }
    s.l += s.dl;
}

/// The coordinates at the span state's pixel.
#[inline(always)]
pub(crate) fn coords<const MODE: u8>(ts: &TexSetup, s: &TexSpan) -> (i64, i64) {
    if MODE == PERSPECTIVE_EXACT {
        ts.uv::<true>(ts.weights(s.e[0], s.e[1]))
    } else {
        (s.u[0], s.v[0])
    }
}
