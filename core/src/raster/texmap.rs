//! Texture coordinates along a span (seed 001 §IV.3): what a textured
//! triangle's rows step through ([`crate::texture`] explains the modes).
//!
//! Every attribute is read at a point of the triangle from the same exact
//! barycentric weights the Gouraud restart uses (`E_i inv`, 30 fraction
//! bits, [`crate::setup`]), so a value depends on the point alone, never on
//! the tile. Per span, at the row's first covered pixel `xr` and its last
//! `xr + n` — the whole covered row, whatever the tile:
//!
//! - `u = s / q`, `v = t / q` (perspective) or `u`, `v` themselves
//!   (affine), 32.32 texels;
//! - the quadratic mode cuts the span into *segments* at the screen
//!   columns that are multiples of [`SEGMENT`] (so a tile whose side and
//!   origin are multiples of it meets one segment a row; the first and last
//!   of a span shorter), samples `u` and `v` exactly at each segment end,
//!   and per segment of `m` pixels steps the quadratic
//!   `f(k) = f0 + B k + A k^2` through `f(0)`, `f(m/2)`, `f(m)` as
//!   `f += d; d += dd` ([`steps`]). The middle is not sampled: `s` and `q`
//!   are linear along the row, so `u(k) = u0 + (u1 - u0) k q1 / (k q1 +
//!   (m - k) q0)` exactly, from the ends and `q` by one 32-bit division
//!   ([`between`], within 2^-14 of the segment's texel range; the exact
//!   sample it replaces cost two 64-bit divisions and three 64-bit plane
//!   evaluations). A tile entering at `k` starts from
//!   `f0 + k d0 + k (k - 1)/2 dd`, the same integers the steps reach.
//!   Segments bound the error whatever the span: one quadratic over a
//!   216-pixel span of a wall at depth ratio 3 is off by a texel
//!   (measured, `tests/tests/texture.rs`), and the interpolation error
//!   falls with the cube of the length;
//! - a segment whose quadratic would miss by more than half a texel (a
//!   bound within 1–10% of the true miss, from its second difference and
//!   how fast `q` changes across it, [`too_curved`]) is halved, down to 2
//!   pixels: only where depth changes fast (a 32-pixel segment with `q`
//!   4:1 across 16 texels is off by 1.78 texels whole, 0.16 in quarters);
//!   the halves' ends and middles come from [`between`] too. The decision
//!   depends on the segment's end samples alone and a tile entering a row
//!   replays the segments from the grid column before it, so tiling still
//!   cannot change a pixel;
//! - the shade is linear in screen space: read at the span's start, it
//!   steps by the triangle's own x-gradient ([`TexSetup`]'s `dl`);
//! - a span steps its coordinates in 32 bits, `I14.18` texels
//!   ([`STEP_FRAC`]): the samples are exact (rounded once to it), the
//!   middles and steps rounded;
//! - the pixel loop runs from one segment end to the next over a copy of
//!   the stepped state ([`TexStep`]), so the quadratic's per-pixel work is
//!   four 32-bit additions in registers, and a segment is loaded between
//!   runs, never past the span's last pixel (the span's last segment runs
//!   on to that pixel: its steps reach the exact end sample there within
//!   2^-9 texel, so no row ends in a one-pixel run);
//! - the weights are those of covered pixels, in `0..=2^30`: held as
//!   `u32`, a 64-bit attribute delta times a weight is one long multiply
//!   and one multiply-accumulate on a 32-bit core.
//!
//! The exact samples divide `s` and `t` by `q` (below 2^24) exactly: on a
//! chip with a 32-bit hardware divider by schoolbook digits
//! ([`crate::numeric`]'s `div_round_pair`); on the Cortex-M0, which has
//! none, by byte digits each estimated with one 32-bit product from a
//! table-seeded bound of `1 / q` and corrected up (no library division:
//! the quadratic workload 25,185 -> 21,464 ticks there, and the segment
//! middles' 16-bit weights the same way); the quotients are the same
//! integers on every chip.

use crate::format::Lanes;
use crate::numeric::{
    div_round_pair, div_shl16, mul_small, pairs, wide_mul, Divisor, HW_CLZ, LONG_MUL, W_FRAC,
};
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
    /// The quadratic mode's split tolerance ([`too_curved`]), eighths of
    /// a texel.
    tol: u32,
    /// The shade's step per pixel along x (8.16 on the 0..255 scale), once
    /// per triangle: the shade is linear in screen space, so a span needs
    /// its start alone (before: both ends and a rounded division per span,
    /// 45 instructions a span on the M4, profiled).
    dl: i32,
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

/// Fraction bits of the coordinates a span steps (`I14.18` texels): the
/// coordinates lie in `0..4096` texels inside a triangle (convex
/// combinations of `U12.4` vertex coordinates; a segment's quadratic
/// overshoots its samples by at most an eighth of their range), so they,
/// their steps and second differences fit 32 bits, one register each on
/// a 32-bit chip. Rounding the samples and steps to 2^-18 adds at most
/// `2^-19 (1 + k + k^2 / 2)` texel after `k` steps: 2^-9 over a whole
/// 32-pixel segment, 2^-8 over a 180-pixel affine span.
pub(crate) const STEP_FRAC: u32 = 18;

/// A 32.32-texel value rounded to [`STEP_FRAC`] fraction bits.
#[inline(always)]
fn to_step(x: i64) -> i32 {
    ((x + (1 << (31 - STEP_FRAC))) >> (32 - STEP_FRAC)) as i32
}

/// What a span loop steps per pixel: coordinates and their first and
/// second differences ([`STEP_FRAC`]), the shade and its step (8.16); for
/// the exact mode the edge values at the current pixel and their steps
/// (the quadratic mode keeps its edge values at `xr` there).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct TexStep {
    u: [i32; 3],
    v: [i32; 3],
    /// The shade (8.16 on the 0..255 scale).
    pub l: i32,
    dl: i32,
    e: [i64; 2],
    ea: [i64; 2],
}

/// A span's state: what its pixels step ([`TexStep`]) and, for the
/// quadratic mode, the pixels left in the segment, the next segment's
/// offset from `xr` and the coordinates there (the segment's end,
/// [`STEP_FRAC`] units), the span's last offset.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct TexSpan {
    /// The stepped state at the span's current pixel.
    pub px: TexStep,
    left: i32,
    next: i32,
    end: [i32; 2],
    /// `q` at the segment's end ([`TexSetup::uvq`]).
    end_q: u32,
    /// The end of the last segment split (twice its offset from `xr`),
    /// its coordinates and `q`: where a later segment ends.
    far: (i32, [i32; 2], u32),
    /// The weights at the span's last pixel (the shade's), for the
    /// segment that ends there.
    w_end: (i64, i64),
    n: i32,
    /// `xr` modulo [`SEGMENT`]: where the screen's segment grid falls.
    phase: i32,
}

/// `1 / m` and `1 / m^2` for the segment lengths `m` in `1..=SEGMENT`,
/// computed at compile time: no division is set up per segment
/// ([`steps`]).
const BY_M: [[Divisor; 2]; SEGMENT as usize + 1] = {
    let mut t = [[Divisor::new(1); 2]; SEGMENT as usize + 1];
    let mut m = 1;
    while m <= SEGMENT as usize {
        t[m] = [Divisor::new(m as i64), Divisor::new((m * m) as i64)];
        m += 1;
    }
    t
};

impl TexSetup {
    /// Inlined: the quadratic mode's tolerance is each texturing
    /// configuration's constant, so its split test folds into the
    /// configuration's own row loop (on the M4, out of line and shared by
    /// three tolerances, the quadratic workload took 4% more instructions:
    /// 15,605 against 14,985 ticks, measured).
    #[inline(always)]
    pub(crate) fn new<Ln: Lanes, Tn: EdgeInt>(
        tv: &[TexVertex; 3],
        shade: &[u8; 3],
        t: &TriangleSetup<Ln, Tn>,
        tol: u32,
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
        let mut ts = TexSetup {
            f0,
            d: [
                core::array::from_fn(|i| f1[i] - f0[i]),
                core::array::from_fn(|i| f2[i] - f0[i]),
            ],
            a: [t.e[1].a.to_i64(), t.e[2].a.to_i64()],
            inv: (1i64 << 62) / t.area2,
            tol,
            dl: 0,
        };
        // The weights' change over one pixel, floored (off by under 2^-16
        // of a level per pixel: 0.003 of a level across a 200-pixel span).
        // `a inv` overflows 64 bits for edges long beside the area, so
        // the floor is taken in two halves of `inv` (exact: the high half's
        // product is a multiple of 2^32). A sliver's gradient may not fit
        // 32 bits; it is then never used (no row holds two pixels of it).
        const { assert!(62 - W_FRAC == 32) };
        let (hi, lo) = (ts.inv >> 32, ts.inv & 0xffff_ffff);
        let step = |a: i64| a * hi + ((a * lo) >> 32);
        ts.dl = ts.lerp(L, (step(ts.a[0]), step(ts.a[1])), 14) as i32;
        ts
    }

    /// Barycentric weights `w1, w2` (30 fraction bits) at the unbiased
    /// edge values `e1`, `e2`, as [`TriangleSetup`]'s restart computes them.
    ///
    /// Every point asked about is a covered pixel, so the weights lie in
    /// `0..=2^30`: held as `u32`, each product of a lerp is one long
    /// multiply and one multiply-accumulate on a 32-bit core instead of a
    /// full 64x64-bit product.
    #[inline(always)]
    fn weights(&self, e1: i64, e2: i64) -> (i64, i64) {
        let w = |e: i64| {
            let w = (e * self.inv) >> (62 - W_FRAC);
            debug_assert!((0..=1 << W_FRAC).contains(&w), "{w}");
            w as u32 as i64
        };
        (w(e1), w(e2))
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
            self.uvq(w).0
        } else {
            let f = |i: usize| (self.f0[i] << 28) + self.lerp(i, w, 2);
            (f(UA), f(VA))
        }
    }

    /// `(u, v)` as [`Self::uv`]'s perspective mode and the `q` they were
    /// divided by (8 more fraction bits than the vertices', below 2^24).
    #[inline(always)]
    fn uvq(&self, w: (i64, i64)) -> ((i64, i64), i64) {
        // s, t, q with 8 more fraction bits: s < 2^40, so s 2^20 fits,
        // and q < 2^24 (exact quotients, rounded).
        let f = |i: usize| (self.f0[i] << 8) + self.lerp(i, w, 22);
        // `q` is a convex combination of the vertices' `u16`s: 32 bits
        // hold it (a 64-bit `max` took 12 instructions on the M4).
        let q = (f(Q) as i32).max(1) as i64;
        let (u, v) = div_round_pair(f(S) << 20, f(T) << 20, q);
        ((u << 8, v << 8), q)
    }

    /// `(u, v)` in [`STEP_FRAC`] units at a point of weights `w`, as
    /// [`Self::uvq`] (rounded once), and `q` there.
    #[inline(always)]
    fn sample(&self, w: (i64, i64)) -> ([i32; 2], u32) {
        let ((u, v), q) = self.uvq(w);
        ([to_step(u), to_step(v)], q as u32)
    }

    /// The weights `k >= 0` pixels on from the span start, whose edge
    /// values are `e`.
    #[inline(always)]
    fn at(&self, e: [i64; 2], k: i32) -> (i64, i64) {
        // The pixel offset is below 2^16 on every span a display holds.
        let step = |a: i64| {
            if !LONG_MUL && k < 1 << 16 {
                mul_small(a, k as u32)
            } else {
                a * (k as u32 as i64)
            }
        };
        self.weights(e[0] + step(self.a[0]), e[1] + step(self.a[1]))
    }

    /// The span state at the tile's first pixel `x0` of `row`, written
    /// over `s`: built in place, not returned (on the Cortex-M0, with
    /// [`Self::segment`] out of line, a returned span was copied once more
    /// per span through `memcpy`: 119 instructions a span of the quadratic
    /// workload, profiled).
    #[inline(always)]
    pub(crate) fn span<const MODE: u8>(&self, row: &Row, x0: i64, s: &mut TexSpan) {
        let n = row.xe - 1 - row.xr;
        let k = x0 - row.xr;
        let e = [row.e1, row.e2];
        let w0 = self.at(e, 0);
        // The weights at the span's last pixel (the exact mode steps its
        // edges instead).
        let w1 = if MODE == PERSPECTIVE_EXACT {
            (0, 0)
        } else {
            self.at(e, n as i32)
        };
        let l0 = ((self.f0[L] << 16) + self.lerp(L, w0, 14)) as i32;
        let dl = self.dl;
        *s = TexSpan {
            px: TexStep {
                l: l0.wrapping_add(dl.wrapping_mul(k as i32)),
                dl,
                e,
                ..TexStep::default()
            },
            n: n as i32,
            ..TexSpan::default()
        };
        match MODE {
            PERSPECTIVE_EXACT => {
                s.px.e = [row.e1 + self.a[0] * k, row.e2 + self.a[1] * k];
                s.px.ea = self.a;
            }
            PERSPECTIVE_QUADRATIC => {
                s.w_end = w1;
                // Pixel offsets within a span: 32 bits.
                let (k, seg) = (k as i32, SEGMENT as i32);
                s.phase = row.xr as i32 & (seg - 1);
                let mut first = (((k + s.phase) & !(seg - 1)) - s.phase).max(0);
                (s.end, s.end_q) = self.sample(if first == 0 { w0 } else { self.at(e, first) });
                // The segments from the grid column before `k` on, as a
                // tile entering there would have loaded them (a segment
                // may have been split): the same integers in every tile.
                self.segment(s, first);
                while s.left != i32::MAX && s.next <= k {
                    first = s.next;
                    self.segment(s, first);
                }
                advance(&mut s.px.u, k - first);
                advance(&mut s.px.v, k - first);
                s.left -= k - first;
            }
            _ => {
                let (p0, p1) = (self.uv::<false>(w0), self.uv::<false>(w1));
                // One reciprocal of the span's length serves its steps.
                let per_px = Divisor::new(n.max(1));
                let d = |a: i64, b: i64| to_step(per_px.round(b - a));
                s.px.u = [to_step(p0.0), d(p0.0, p1.0), 0];
                s.px.v = [to_step(p0.1), d(p0.1, p1.1), 0];
                advance(&mut s.px.u, k as i32);
                advance(&mut s.px.v, k as i32);
            }
        }
    }

    /// Loads the quadratic segment starting `first` pixels into the span,
    /// whose exact start coordinates are `s.end`; past the span's last
    /// pixel, nothing (the loop is done).
    // Inlined (the Cortex-M4's quadratic workload 20,544 -> 19,024 ticks,
    // the span state no longer escapes; the Cortex-M0's 26,476 -> 26,024,
    // 12 KB more flash in the micro:bit build that has the texturing
    // workloads, none in its scenes' build, which does not texture).
    #[inline(always)]
    fn segment(&self, s: &mut TexSpan, first: i32) {
        let seg = SEGMENT as i32;
        let mut m = (seg - ((first + s.phase) & (seg - 1))).min(s.n - first);
        if m <= 0 {
            s.px.u = [s.end[0], 0, 0];
            s.px.v = [s.end[1], 0, 0];
            s.left = i32::MAX;
            return;
        }
        let (p0, q0) = (s.end, s.end_q);
        let end = 2 * (first + m);
        let (mut p1, mut q1) = if s.far.0 == end {
            (s.far.1, s.far.2)
        } else {
            self.sample(if end == 2 * s.n {
                s.w_end
            } else {
                self.at(s.px.e, first + m)
            })
        };
        // The middle from the ends and `q` ([`between`]): no sample.
        let mut k = Knots::new(p0, between(p0, q0, p1, q1, m as u32, 2 * m as u32), p1);
        // Halve the segment while its quadratic would miss the curve by
        // more than half a texel ([`too_curved`]): only where the depth
        // changes fast across it. An even segment's middle is its first
        // half's end; the whole segment's end is kept for the segment that
        // ends there next.
        while m >= 2 * MIN_SPLIT
            && self.tol != crate::texture::NEVER_SPLIT
            && too_curved(k.c, q0, q1, self.tol)
        {
            if 2 * (first + m) == end {
                s.far = (end, p1, q1);
            }
            // The first half's end, `h` of the `m` pixels on, and `q` there.
            let h = m / 2;
            p1 = if m % 2 == 0 {
                k.pm
            } else {
                between(p0, q0, p1, q1, 2 * h as u32, 2 * m as u32)
            };
            q1 = (h as u32 * q1 + (m - h) as u32 * q0) / m as u32;
            m = h;
            k = Knots::new(p0, between(p0, q0, p1, q1, m as u32, 2 * m as u32), p1);
        }
        s.px.u = steps(k.a[0], k.c[0], k.e[0], m);
        s.px.v = steps(k.a[1], k.c[1], k.e[1], m);
        (s.end, s.end_q) = (p1, q1);
        // The span's last segment runs on to the span's last pixel, which
        // its steps reach within 2^-9 texel of the exact sample: no
        // segment of one pixel, and no second run, at the end of each row.
        let last = (first + m == s.n) as i32;
        s.left = m + last;
        s.next = first + m + last;
    }
}

/// A segment's coordinates in [`STEP_FRAC`] units: `u` and `v` at its
/// start (`a`) and end (`e`) and their second differences
/// `c = a - 2 b + e` through the middle `b`, below 2^31 in magnitude (the
/// coordinates lie in `0..2^30` units: one 32-bit register, where 64-bit
/// differences took 18 instructions a segment in absolute values alone on
/// the M4); and the middle itself, the first half's end if the segment is
/// split.
#[derive(Debug, Clone, Copy)]
struct Knots {
    a: [i32; 2],
    e: [i32; 2],
    c: [i32; 2],
    pm: [i32; 2],
}

impl Knots {
    #[inline(always)]
    fn new(a: [i32; 2], pm: [i32; 2], e: [i32; 2]) -> Self {
        // Modulo 2^32, exact: the true value lies within `(-2^31, 2^31)`.
        let c =
            core::array::from_fn(|i| a[i].wrapping_add(e[i]).wrapping_sub(pm[i].wrapping_mul(2)));
        Knots { a, e, c, pm }
    }
}

/// A coordinate's `[f, d, dd]` over a segment of `m` pixels from its
/// values at the start `a` and end `e` and its second difference `c`
/// ([`Knots`]): with `D = e - a`, the quadratic `a + B k + A k^2` through
/// them steps `d(0) = A + B = (D - 2 c) / m + 2 c / m^2` and
/// `dd = 2 A = 4 c / m^2`, each quotient rounded once (a shift for a
/// power-of-two length, else one 32-bit division or reciprocal from
/// [`BY_M`]): the roundings add under `2^-19 (1 + 2 k + k (k - 1) / 2)`
/// texel after `k` steps, 2^-9 over a whole segment. Before: one 64-bit
/// rounding of `(2 c + m (D - 2 c)) / m^2` from the 32.32 values, 177
/// instructions a segment for the two coordinates on the M4 (profiled).
/// Inlined on the Cortex-M0 too (its quadratic workload 26,024 -> 25,350
/// ticks; out of line, each call paid 147 instructions).
#[inline(always)]
fn steps(a: i32, c: i32, e: i32, m: i32) -> [i32; 3] {
    // `|e - a| < 2^30`: the coordinates lie in `0..2^30`.
    let big_d = e - a;
    let [by_m, by_m2] = &BY_M[m as usize];
    let (d1, d2) = if big_d.unsigned_abs() < 1 << 29 && c.unsigned_abs() < 1 << 28 {
        // Nearly always (differences below 2^11 texels): 32 bits, with
        // `|D - 2 c| < 2^30` and `|4 c| < 2^30`.
        let (d, c2, c4) = (big_d - 2 * c, 2 * c, 4 * c);
        let m = m as u32;
        if m & (m - 1) == 0 {
            let b = m.trailing_zeros();
            let r = |x: i32, b: u32| (x + ((1 << b) >> 1)) >> b;
            (r(d, b) + r(c2, 2 * b), r(c4, 2 * b))
        } else {
            (
                by_m.round_small(d) + by_m2.round_small(c2),
                by_m2.round_small(c4),
            )
        }
    } else {
        let (d, c) = (big_d as i64 - 2 * c as i64, c as i64);
        let (d1, d2) = (by_m.round(d) + by_m2.round(2 * c), by_m2.round(4 * c));
        (d1 as i32, d2 as i32)
    };
    [a, d1, d2]
}

/// The coordinates `k2 / m2` of the way from `p0` to `p1` ([`STEP_FRAC`]
/// units, below 2^30)
/// in perspective, where `q` runs linearly from `q0` to `q1` (below 2^24,
/// positive; `k2 < m2 <= 2^7`): with `s = u q` linear too,
/// `u(k) = u0 + (u1 - u0) k q1 / (k q1 + (m - k) q0)` exactly, so the
/// point needs one 32-bit division for both coordinates instead of an
/// exact sample's two 64-bit ones. The weight is taken to 16 fraction bits
/// from its numerator and denominator cut to 16 significant bits: the
/// point is within `|u1 - u0| 2^-14` of the exact one (2^-10 texel for a
/// segment 16 texels long).
#[inline(always)]
fn between(p0: [i32; 2], q0: u32, p1: [i32; 2], q1: u32, k2: u32, m2: u32) -> [i32; 2] {
    debug_assert!(k2 < m2 && m2 <= 1 << 7 && q0 > 0 && q1 > 0 && q0.max(q1) < 1 << 24);
    // Both below 2^31.
    let num = k2 * q1;
    let den = num + (m2 - k2) * q0;
    let cut = over_16(den);
    // `num <= den`: the weight is at most 2^16, kept below it so that the
    // products below take the 16-bit multiplier.
    let (num, den) = (num >> cut, den >> cut);
    let w = if num < den {
        div_shl16(num, den)
    } else {
        0xffff
    };
    let lerp = |a: i32, b: i32| a + (mul_small(b as i64 - a as i64, w) >> 16) as i32;
    [lerp(p0[0], p1[0]), lerp(p0[1], p1[1])]
}

/// How far `x` shifts right to fit 16 bits,
/// `(32 - x.leading_zeros()).saturating_sub(16)`: one `clz` where the core
/// has it ([`HW_CLZ`]); the Cortex-M0 has none (a library call of about 55
/// instructions, once per segment), so there four compares.
#[inline(always)]
fn over_16(x: u32) -> u32 {
    over_16_by::<HW_CLZ>(x)
}

#[inline(always)]
fn over_16_by<const CLZ: bool>(x: u32) -> u32 {
    if CLZ {
        return (32 - x.leading_zeros()).saturating_sub(16);
    }
    // Unrolled by hand: the micro:bit builds for size.
    let (mut y, mut c) = (x >> 16, 0);
    if y >= 1 << 8 {
        y >>= 8;
        c += 8;
    }
    if y >= 1 << 4 {
        y >>= 4;
        c += 4;
    }
    if y >= 1 << 2 {
        y >>= 2;
        c += 2;
    }
    if y >= 1 << 1 {
        y >>= 1;
        c += 1;
    }
    c + y
}

/// The shortest segment a split leaves, pixels.
const MIN_SPLIT: i32 = 2;

/// Whether the quadratic through a segment's coordinates at its start,
/// middle and end, whose second differences are `c` ([`Knots`]), where `q`
/// runs from `q0` to `q1`, may miss the exact curve by more than `tol`
/// eighths of a texel (half a texel by default).
///
/// With `q` linear along the segment, `u(t) = A + B / q(t)` (`t` from 0
/// to 1), and the error of the quadratic through `t = 0, 1/2, 1` is
/// exactly `2 c g(t)` with `g(t) = (q1 - q0) t (t - 1/2) (t - 1) / q(t)`
/// (the divided differences of `1 / q` are closed-form). So the miss is at
/// most `2 |c| 0.0481 |q1 - q0| / (q_min + a |q1 - q0|)`: `0.0481 =
/// 1 / (12 sqrt 3)` is the cubic's largest value on `[0, 1]`, and `a`
/// accounts for the cubic's peak (a fifth of the way from the near end)
/// lying where `q` is larger than its minimum — `a = 11/64` while the
/// depth ratio across the segment is at most 4 (the true `a` falls from
/// 0.211 at ratio 1 to 0.186 at 4), and each `q` unit beyond that counts
/// `1/16` (the true slope tends to 0.096). The bound is within 1–10% of
/// the true miss for ratios up to 8 (the estimate it replaces took `q` at
/// its minimum everywhere: 1.54x the true miss at ratio 4, so a third more
/// splits there). `c` is taken in 2^-16 texels.
#[inline(always)]
fn too_curved(c: [i32; 2], q0: u32, q1: u32, tol: u32) -> bool {
    let c = c[0].unsigned_abs().max(c[1].unsigned_abs()) >> (STEP_FRAC - 16);
    // q < 2^24, so spread and the denominator fit 32 bits, and each side
    // is one 32x32-bit product (`wide_mul`: no 64-bit multiply on the
    // Cortex-M0) below 2^63 (tol < 2^16).
    let (lo, dq) = (q0.min(q1), q0.abs_diff(q1));
    let near = dq.min(3 * lo);
    let den = lo + ((11 * near) >> 6) + ((dq - near) >> 4);
    // 0.0962 |c| dq / den > tol / 8, in hundredths.
    wide_mul(c, 77 * dq) > wide_mul(100 * den, tol) << 16
}

/// A coordinate's state `[f, d, dd]` advanced `k` steps in closed form:
/// the same integers `k` steps reach (modulo 2^32).
#[inline(always)]
fn advance(f: &mut [i32; 3], k: i32) {
    let tri = pairs(k);
    f[0] = f[0]
        .wrapping_add(k.wrapping_mul(f[1]))
        .wrapping_add(tri.wrapping_mul(f[2]));
    f[1] = f[1].wrapping_add(k.wrapping_mul(f[2]));
}

impl TexSpan {
    /// The pixels a loop may step from here, at most `n`, before
    /// [`TexSetup::next_segment`]: the rest of the quadratic mode's
    /// segment; the whole span otherwise.
    #[inline(always)]
    pub(crate) fn run<const MODE: u8>(&self, n: usize) -> usize {
        if MODE == PERSPECTIVE_QUADRATIC {
            n.min(self.left as usize)
        } else {
            n
        }
    }
}

impl TexSetup {
    /// Loads the quadratic mode's next segment once a run has stepped the
    /// last one's pixels (`s.px` holds the stepped state).
    #[inline(always)]
    pub(crate) fn next_segment(&self, s: &mut TexSpan) {
        self.segment(s, s.next);
    }
}

/// One pixel on: the exact mode's edges step, the others' coordinates
/// (first and second differences for the quadratic), and the shade.
#[inline(always)]
pub(crate) fn step<const MODE: u8>(s: &mut TexStep) {
    if MODE == PERSPECTIVE_EXACT {
        s.e[0] += s.ea[0];
        s.e[1] += s.ea[1];
    } else {
        s.u[0] = s.u[0].wrapping_add(s.u[1]);
        s.v[0] = s.v[0].wrapping_add(s.v[1]);
        if MODE == PERSPECTIVE_QUADRATIC {
            s.u[1] = s.u[1].wrapping_add(s.u[2]);
            s.v[1] = s.v[1].wrapping_add(s.v[2]);
        }
    }
    s.l = s.l.wrapping_add(s.dl);
}

/// The coordinates (32.32 texels) at the stepped state's pixel.
#[inline(always)]
pub(crate) fn coords<const MODE: u8>(ts: &TexSetup, s: &TexStep) -> (i64, i64) {
    if MODE == PERSPECTIVE_EXACT {
        ts.uv::<true>(ts.weights(s.e[0], s.e[1]))
    } else {
        (
            (s.u[0] as i64) << (32 - STEP_FRAC),
            (s.v[0] as i64) << (32 - STEP_FRAC),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::{between, over_16_by, to_step, too_curved, Knots};

    /// [`between`] is the exact perspective point, `k / m` of the way in
    /// screen space from `a` (where `q` is `q0`) to `e` (`q1`), within its
    /// stated bound `|e - a| 2^-14` (plus the final rounding), over
    /// pseudo-random ends, depths from 1 to 2^24 - 1 and every split point.
    #[test]
    fn the_middle_is_the_perspective_point() {
        let mut random = crate::numeric::xorshift(0x9e37_79b9_7f4a_7c15);
        let mut next = |bits: u32| random() >> (64 - bits);
        for i in 0..20_000 {
            let (a, e) = (next(30) as i32, next(30) as i32);
            let mut q = |bits: u32| (next(bits) as u32).clamp(1, (1 << 24) - 1);
            let (q0, q1) = match i % 3 {
                0 => (q(24), q(24)),
                1 => (q(12), q(24)),
                _ => (q(4) + 1, q(8) + 1),
            };
            let m2 = 2 + next(6) as u32 % 63;
            let k2 = 1 + next(6) as u32 % (m2 - 1);
            let got = between([a, a], q0, [e, e], q1, k2, m2)[0];
            let (k, m) = (k2 as f64, m2 as f64);
            let t = k * q1 as f64 / (k * q1 as f64 + (m - k) * q0 as f64);
            let want = a as f64 + (e as f64 - a as f64) * t;
            let bound = (e as f64 - a as f64).abs() / 16384.0 + 1.0;
            assert!(
                (got as f64 - want).abs() <= bound,
                "{a} {e} q {q0} {q1} {k2}/{m2}: {got} vs {want}"
            );
        }
    }

    #[test]
    fn over_16_is_the_same_on_both_routes() {
        let check = |x: u32| {
            let want = (32 - x.leading_zeros()).saturating_sub(16);
            assert_eq!(over_16_by::<false>(x), want, "{x:#x}");
            assert_eq!(over_16_by::<true>(x), want, "{x:#x}");
        };
        for x in [0, 1, u32::MAX] {
            check(x);
        }
        for b in 0..32 {
            let p = 1u32 << b;
            for x in [p - 1, p, p + 1, p | (p >> 1)] {
                check(x);
            }
        }
        let mut r = crate::numeric::xorshift(0x0c1e_a5ed);
        for _ in 0..10_000 {
            let x = r();
            check((x >> (x % 33)) as u32);
        }
    }

    /// The largest error of the quadratic through `u` at `a`, `a + l/2`,
    /// `a + l`, sampled finely (f64).
    fn quadratic_miss(u: &dyn Fn(f64) -> f64, a: f64, l: f64) -> f64 {
        let (x0, x1, x2) = (a, a + l / 2.0, a + l);
        let (y0, y1, y2) = (u(x0), u(x1), u(x2));
        let p = |x: f64| {
            y0 * (x - x1) * (x - x2) / ((x0 - x1) * (x0 - x2))
                + y1 * (x - x0) * (x - x2) / ((x1 - x0) * (x1 - x2))
                + y2 * (x - x0) * (x - x1) / ((x2 - x0) * (x2 - x1))
        };
        (0..=256)
            .map(|i| a + l * i as f64 / 256.0)
            .map(|x| (p(x) - u(x)).abs())
            .fold(0.0, f64::max)
    }

    /// Walls of `texels` texels over 32 pixels with `q` falling `ratio`:1:
    /// a segment the bound keeps whole misses by at most half a texel, and
    /// one it splits misses by more than 0.45 texel (the bound is above
    /// the miss, but by less than 11%). At the far end of the
    /// workload's wall (16 texels, 4:1) the quadratic misses by 1.78 texels
    /// over 32 pixels, 0.61 over 16, 0.16 over 8: split, split, kept.
    #[test]
    fn the_split_estimate_bounds_the_quadratic_error() {
        let mut checked = 0;
        for texels in [4.0, 16.0, 64.0] {
            for ratio in [1.5, 2.0, 4.0, 8.0, 16.0, 64.0] {
                // `q` from `ratio` to 1 (scaled by 2^14), `u = s / q` from
                // 0 to `texels` with `s` linear.
                let q = |x: f64| 16384.0 * (ratio - (ratio - 1.0) * x / 32.0);
                let u = |x: f64| texels * (x / 32.0) * 16384.0 / q(x);
                for l in [2.0, 4.0, 8.0, 16.0, 32.0] {
                    let mut a = 0.0;
                    while a + l <= 32.0 {
                        let fx = |x: f64| (u(x) * 4294967296.0).round() as i64;
                        let p = |x: f64| [to_step(fx(x)), to_step(fx(x) / 2)];
                        let (q0, q1) = (q(a).round() as u32, q(a + l).round() as u32);
                        let k = Knots::new(p(a), p(a + l / 2.0), p(a + l));
                        let split = too_curved(k.c, q0, q1, 4);
                        let miss = quadratic_miss(&u, a, l);
                        if split {
                            assert!(miss > 0.45, "{texels} {ratio} [{a}, +{l}]: {miss}");
                        } else {
                            assert!(miss <= 0.5, "{texels} {ratio} [{a}, +{l}]: {miss}");
                        }
                        checked += 1;
                        a += l;
                    }
                }
            }
        }
        assert_eq!(checked, 3 * 6 * (16 + 8 + 4 + 2 + 1));
        // The workload's wall: 16 texels, q 4:1, from the near end.
        let q = |x: f64| 16384.0 * (4.0 - 3.0 * x / 32.0);
        let u = |x: f64| (x / 2.0) / (q(x) / 16384.0);
        let fx = |x: f64| [to_step((u(x) * 4294967296.0).round() as i64), 0];
        // The segment of `l` pixels at the wall's far end (`q` smallest).
        let seg = |l: f64| {
            let a = 32.0 - l;
            let k = Knots::new(fx(a), fx(a + l / 2.0), fx(32.0));
            too_curved(k.c, q(a) as u32, q(32.0) as u32, 4)
        };
        assert!((quadratic_miss(&u, 0.0, 32.0) - 1.78).abs() < 0.01);
        assert!((quadratic_miss(&u, 16.0, 16.0) - 0.61).abs() < 0.01);
        assert!((quadratic_miss(&u, 24.0, 8.0) - 0.16).abs() < 0.01);
        assert_eq!([seg(32.0), seg(16.0), seg(8.0)], [true, true, false]);
    }
}
