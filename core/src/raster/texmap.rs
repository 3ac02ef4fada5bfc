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
//!   `dd = 2A = 4 c / m^2`, `d(0) = A + B = (2 c + m (f(m) - f(0) - 2 c)) / m^2`,
//!   `c = f(0) - 2 f(m/2) + f(m)`, each rounded once (shifts for a whole
//!   segment, a compile-time reciprocal of `m^2` otherwise); a tile
//!   entering at `k` starts from `f0 + k d0 + k (k - 1)/2 dd`, the same
//!   integers the steps reach. Segments bound the error whatever the span:
//!   one quadratic over a 216-pixel span of a wall at depth ratio 3 is off
//!   by a texel (measured, `tests/tests/texture.rs`), and the interpolation
//!   error falls with the cube of the length;
//! - a segment whose quadratic would miss by more than half a texel (an
//!   estimate from its second difference and how fast `q` changes across
//!   it, [`too_curved`]) is halved, down to 2 pixels: only where depth
//!   changes fast (a 32-pixel segment with `q` 4:1 across 16 texels is off
//!   by 1.78 texels whole, 0.16 in quarters). The decision depends on the
//!   segment's exact samples alone and a tile entering a row replays the
//!   segments from the grid column before it, so tiling still cannot
//!   change a pixel;
//! - the shade is linear along the span;
//! - a span steps its coordinates in 32 bits, `I14.18` texels
//!   ([`STEP_FRAC`]): the samples are exact, the steps rounded;
//! - the pixel loop runs from one segment end to the next over a copy of
//!   the stepped state ([`TexStep`]), so the quadratic's per-pixel work is
//!   four 32-bit additions in registers, and a segment is loaded between
//!   runs, never past the span's last pixel.
//!
//! The exact samples divide `s` and `t` by `q` (below 2^24) exactly: on a
//! chip with a 32-bit hardware divider by schoolbook digits
//! ([`crate::numeric`]'s `div_round_pair`), elsewhere by one reciprocal;
//! the quotients are the same integers on every chip.

use crate::format::Lanes;
use crate::numeric::{div_round_pair, mul_small, pairs, wide_mul, Divisor, LONG_MUL, W_FRAC};
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
/// offset from `xr` and the exact coordinates there (the segment's end,
/// 32.32), the span's last offset.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct TexSpan {
    /// The stepped state at the span's current pixel.
    pub px: TexStep,
    left: i32,
    next: i64,
    end: (i64, i64),
    /// `q` at the segment's end ([`TexSetup::uvq`]).
    end_q: i64,
    /// The end of the last segment split (twice its offset from `xr`),
    /// its exact coordinates and `q`: where a later segment ends.
    far: (i64, (i64, i64), i64),
    n: i64,
    /// `xr` modulo [`SEGMENT`]: where the screen's segment grid falls.
    phase: i64,
}

/// `1 / m^2` for the segment lengths `m` in `1..SEGMENT` (a partial
/// segment at a span's ends), from a table computed at compile time (no
/// division per segment): [`round_by_m2`].
const BY_M2: [Divisor; SEGMENT as usize] = {
    let mut t = [Divisor::new(1); SEGMENT as usize];
    let mut m = 1;
    while m < SEGMENT as usize {
        t[m] = Divisor::new((m * m) as i64);
        m += 1;
    }
    t
};

/// A segment's step: the 32.32 difference `x` over `m^2` straight into
/// [`STEP_FRAC`], `x / (m^2 2^b)` rounded once (`b = 32 - STEP_FRAC`),
/// as `floor(floor((x + m^2 2^(b-1)) / 2^b) / m^2)` — the same integer
/// (nested floors of positive divisors), but the quotient by `m^2 < 2^10`
/// takes a dividend that the shift brought below 2^32: one reciprocal
/// quotient on the Cortex-M0 instead of five 8-bit digits (with
/// [`too_curved`]'s 32-bit products, the quadratic workload on the M0
/// 44,871 -> 42,206 ticks: measured).
#[inline(always)]
fn round_by_m2(x: i64, m: i64) -> i64 {
    const B: u32 = 32 - STEP_FRAC;
    // `m < 32`: a 32-bit product (an `i64` one is a library call on the M0).
    let h = (m as i32 * m as i32) as i64;
    BY_M2[m as usize].round(((x + (h << (B - 1))) >> B) - h / 2)
}

impl TexSetup {
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
        TexSetup {
            f0,
            d: [
                core::array::from_fn(|i| f1[i] - f0[i]),
                core::array::from_fn(|i| f2[i] - f0[i]),
            ],
            a: [t.e[1].a.to_i64(), t.e[2].a.to_i64()],
            inv: (1i64 << 62) / t.area2,
            tol,
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
        let q = f(Q).max(1);
        let (u, v) = div_round_pair(f(S) << 20, f(T) << 20, q);
        ((u << 8, v << 8), q)
    }

    /// The weights at offset `m2 / 2` pixels from the span start, whose
    /// edge values are `e` (the edge steps are even).
    #[inline(always)]
    fn at(&self, e: [i64; 2], m2: i64) -> (i64, i64) {
        // The pixel offset is below 2^16 on every span a display holds.
        let step = |a: i64| {
            if !LONG_MUL && m2 < 1 << 16 {
                mul_small(a / 2, m2 as u32)
            } else {
                a / 2 * m2
            }
        };
        self.weights(e[0] + step(self.a[0]), e[1] + step(self.a[1]))
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
            px: TexStep {
                l: l0 + dl * k as i32,
                dl,
                e,
                ..TexStep::default()
            },
            n,
            ..TexSpan::default()
        };
        match MODE {
            PERSPECTIVE_EXACT => {
                s.px.e = [row.e1 + self.a[0] * k, row.e2 + self.a[1] * k];
                s.px.ea = self.a;
            }
            PERSPECTIVE_QUADRATIC => {
                s.phase = row.xr & (SEGMENT - 1);
                let mut first = (((k + s.phase) & !(SEGMENT - 1)) - s.phase).max(0);
                (s.end, s.end_q) = self.uvq(if first == 0 {
                    w0
                } else {
                    self.at(e, 2 * first)
                });
                // The segments from the grid column before `k` on, as a
                // tile entering there would have loaded them (a segment
                // may have been split): the same integers in every tile.
                self.segment(&mut s, first);
                while s.left != i32::MAX && s.next <= k {
                    first = s.next;
                    self.segment(&mut s, first);
                }
                advance(&mut s.px.u, k - first);
                advance(&mut s.px.v, k - first);
                s.left -= (k - first) as i32;
            }
            _ => {
                let (p0, p1) = (self.uv::<false>(w0), self.uv::<false>(w1));
                let d = |a: i64, b: i64| to_step(per_px.round(b - a));
                s.px.u = [to_step(p0.0), d(p0.0, p1.0), 0];
                s.px.v = [to_step(p0.1), d(p0.1, p1.1), 0];
                advance(&mut s.px.u, k);
                advance(&mut s.px.v, k);
            }
        }
        s
    }

    /// Loads the quadratic segment starting `first` pixels into the span,
    /// whose exact start coordinates are `s.end`; past the span's last
    /// pixel, nothing (the loop is done).
    // Inlined where flash is plenty (the Cortex-M4: the quadratic
    // workload 20,544 -> 19,024 ticks, the span state no longer escapes),
    // one copy on the soft-float Cortex-M0, whose flash is full.
    #[cfg_attr(target_abi = "eabi", inline(never))]
    #[cfg_attr(not(target_abi = "eabi"), inline(always))]
    fn segment(&self, s: &mut TexSpan, first: i64) {
        let mut m = (SEGMENT - ((first + s.phase) & (SEGMENT - 1))).min(s.n - first);
        if m <= 0 {
            let p = s.end;
            s.px.u = [to_step(p.0), 0, 0];
            s.px.v = [to_step(p.1), 0, 0];
            s.left = i32::MAX;
            return;
        }
        let (p0, q0) = (s.end, s.end_q);
        let e = s.px.e;
        let (mut pm, mut qm) = self.uvq(self.at(e, 2 * first + m));
        let end = 2 * (first + m);
        let (mut p1, mut q1) = if s.far.0 == end {
            (s.far.1, s.far.2)
        } else {
            self.uvq(self.at(e, end))
        };
        // Halve the segment while its quadratic would miss the curve by
        // more than half a texel ([`too_curved`]): only where the depth
        // changes fast across it. An even segment's middle is its first
        // half's end; the whole segment's end is kept for the segment that
        // ends there next.
        while m >= 2 * MIN_SPLIT && too_curved(p0, pm, p1, q0, q1, self.tol) {
            if 2 * (first + m) == end {
                s.far = (end, p1, q1);
            }
            (p1, q1) = if m % 2 == 0 {
                (pm, qm)
            } else {
                self.uvq(self.at(e, 2 * (first + m / 2)))
            };
            m /= 2;
            (pm, qm) = self.uvq(self.at(e, 2 * first + m));
        }
        // `d(0) = A + B = (2 c + m (f(m) - f(0) - 2 c)) / m^2`, `dd = 4 c / m^2`
        // with `c = f(0) - 2 f(m/2) + f(m)`: one rounding each, into
        // STEP_FRAC (a shift for a power-of-two length).
        s.px.u = steps(p0.0, pm.0, p1.0, m);
        s.px.v = steps(p0.1, pm.1, p1.1, m);
        (s.end, s.end_q) = (p1, q1);
        s.left = m as i32;
        s.next = first + m;
    }
}

/// A coordinate's `[f, d, dd]` over a segment of `m` pixels from its
/// exact values `f0`, `fm`, `f1` at the start, middle and end (32.32).
// Inlined where flash is plenty (the Cortex-M4: the quadratic workload
// 21,760 -> 21,248 ticks); the compiler's choice on the Cortex-M0.
#[cfg_attr(not(target_abi = "eabi"), inline(always))]
fn steps(f0: i64, fm: i64, f1: i64, m: i64) -> [i32; 3] {
    let c = f0 - 2 * fm + f1;
    let (n1, n2) = (2 * c + mul_small(f1 - f0 - 2 * c, m as u32), 4 * c);
    let (d1, d2) = if m.count_ones() == 1 {
        let b = 2 * m.trailing_zeros() + 32 - STEP_FRAC;
        let r = |x: i64| (x + (1 << (b - 1))) >> b;
        (r(n1), r(n2))
    } else {
        (round_by_m2(n1, m), round_by_m2(n2, m))
    };
    [to_step(f0), d1 as i32, d2 as i32]
}

/// The shortest segment a split leaves, pixels.
const MIN_SPLIT: i64 = 2;

/// Whether the quadratic through a segment's exact coordinates `p0`,
/// `pm`, `p1` (32.32 texels) at its start, middle and end, where `q` runs
/// from `q0` to `q1`, may miss the exact curve by more than `tol` eighths
/// of a texel (half a texel by default).
/// With `q` linear along the span, `u = a + b / q`, whose third
/// derivative is `-3 u'' q' / q`; a quadratic through three points `h`
/// apart misses by at most `|u'''| h^3 / (9 sqrt 3)`, so with the second
/// difference `c = p0 - 2 pm + p1`, about `u'' h^2`, the error is about
/// `0.19 |c| rho` with `rho = |q1 - q0| / (2 min q)`. The estimate runs
/// about 1.5x above the true error (a 32-pixel segment with `q` 4:1
/// across 16 texels: estimated 2.7, true 1.78 texels), so a segment it
/// keeps whole stays within about a third of a texel. `c` is taken in
/// 2^-16 texels.
#[inline(always)]
fn too_curved(p0: (i64, i64), pm: (i64, i64), p1: (i64, i64), q0: i64, q1: i64, tol: u32) -> bool {
    let c = |a: i64, m: i64, b: i64| ((a - 2 * m + b).unsigned_abs() >> 16).min(u32::MAX as u64);
    let c = c(p0.0, pm.0, p1.0).max(c(p0.1, pm.1, p1.1));
    // 0.095 |c| |q1 - q0| / min q > tol / 8 in integers: c < 2^32,
    // q < 2^24 and tol < 2^16, so each side is one 32x32-bit product
    // (`wide_mul`: no 64-bit multiply on the Cortex-M0) below 2^61.
    let spread = (q0.abs_diff(q1) * 19) as u32;
    let bound = (q0.min(q1) * 25) as u32;
    wide_mul(c as u32, spread) > wide_mul(bound, tol) << 16
}

/// A coordinate's state `[f, d, dd]` advanced `k` steps in closed form:
/// the same integers `k` steps reach (modulo 2^32).
#[inline(always)]
fn advance(f: &mut [i32; 3], k: i64) {
    let (k, tri) = (k as i32, pairs(k as i32));
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
    s.l += s.dl;
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
    use super::too_curved;

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
    /// a segment the estimate keeps whole misses by at most half a texel,
    /// and one it splits misses by more than a fifth (the estimate is
    /// conservative, but not by more than 2.5x). At the far end of the
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
                        let p = |x: f64| (fx(x), fx(x) / 2);
                        let (q0, q1) = (q(a).round() as i64, q(a + l).round() as i64);
                        let split = too_curved(p(a), p(a + l / 2.0), p(a + l), q0, q1, 4);
                        let miss = quadratic_miss(&u, a, l);
                        if split {
                            assert!(miss > 0.2, "{texels} {ratio} [{a}, +{l}]: {miss}");
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
        let fx = |x: f64| ((u(x) * 4294967296.0).round() as i64, 0);
        // The segment of `l` pixels at the wall's far end (`q` smallest).
        let seg = |l: f64| {
            let a = 32.0 - l;
            too_curved(
                fx(a),
                fx(a + l / 2.0),
                fx(32.0),
                q(a) as i64,
                q(32.0) as i64,
                4,
            )
        };
        assert!((quadratic_miss(&u, 0.0, 32.0) - 1.78).abs() < 0.01);
        assert!((quadratic_miss(&u, 16.0, 16.0) - 0.61).abs() < 0.01);
        assert!((quadratic_miss(&u, 24.0, 8.0) - 0.16).abs() < 0.01);
        assert_eq!([seg(32.0), seg(16.0), seg(8.0)], [true, true, false]);
    }
}
