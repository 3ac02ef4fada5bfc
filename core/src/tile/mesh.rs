//! Mesh triangles under the **plane contract**
//! ([`PlaneContract`](crate::numeric::PlaneContract)): setup,
//! traversal and the row starts of an opaque Gouraud triangle in one routine
//! whose state stays in 32-bit integers, from three compact vertices
//! ([`MeshVertex`]) — what the geometry stage's vertex cache holds, so a
//! mesh triangle reaches the tile without a command being built, decoded or
//! validated ([`crate::geometry`]).
//!
//! Per (tile, triangle) pair:
//!
//! 1. the triangle's pixel box (pixel centres `16 p + 8` inside its
//!    sub-pixel box), clipped to the tile: an empty one costs nothing more;
//! 2. the three edge functions of [`crate::setup`] (same orientation, same
//!    top-left rule), relative to the clipped box's first pixel centre;
//! 3. each row's covered run `[xl, xr)` straight from the edges: one floor
//!    division per edge with a slope (a divide instruction on every chip
//!    but the Cortex-M0, which scans the rows of a box at most
//!    [`SCAN_WIDTH`] columns wide, a few additions a column, and steps the
//!    quotients of a wider one); exactly the pixels the traversal
//!    (`crate::raster::traverse`) finds;
//! 4. at the first covered row, and only then, the attribute planes: one
//!    reciprocal of the doubled area and two 32x32-bit products a step
//!    ([`PlaneContract`](crate::numeric::PlaneContract)), anchored at the top-left pixel of the
//!    triangle's own box, so a row's start `c + i gx + j gy` (wrapping
//!    `i32`) is the same whichever tile asks;
//! 5. each row through the tile's span loop (window ID, Z, dither, pack,
//!    plane mask, store: the one store path).
//!
//! A triangle too large for that 32-bit setup (a side of 1024 pixels or
//! more, or a box of 512 pixels of width plus height: what near clipping
//! leaves of a ground or a wall beside the camera) is a *far* triangle
//! ([`Tile::far_triangle`]): its edges are set up exactly in 64 bits per
//! 64-pixel block of the tile, and its planes anchored per 256-pixel cell
//! of the screen at a pixel whose weights are exactly rounded — both grids
//! fixed to the screen, so the output is the same in any tiling. (Before,
//! these took the exact contract: on the host city walk 11% more
//! instructions for the same pixels, most of them in the span loop.)
//!
//! A triangle outside the contract's domain (a sliver beyond the ones it
//! serves) returns `false` before any pixel is drawn, and the caller draws
//! it under the exact contract.

use super::Tile;
use crate::command::{Command, State};
use crate::config::TileConfig;
use crate::format::{Lanes, PixelFormat};
use crate::fragment::BlendMode;
use crate::geom::{pixel_span, MeshVertex};
use crate::numeric::{
    div_floor_i32, dot2_i16, dot2_wide, wide_mul, wrapping_mul_i32, Precision, LONG_MUL,
    SUBPIXEL_BITS, Z_FRAC,
};
use crate::raster::coverage::AaMode;
use crate::raster::span::SpanStart;
use crate::setup::SMALL_EXTENT;

/// One edge as the fused path walks it: `E - bias = a k + n` along a row
/// (`k` pixels right of the clipped box's first column), `n` growing by `s`
/// each row; inside when `a k + n >= 0` (the top-left rule's bias folded
/// into `n`).
///
/// A row's run needs `floor(n / |a|)`. Where the core divides
/// ([`LONG_MUL`]) that is one division a row. The Cortex-M0 has no divide
/// instruction, and a large triangle's quotients are too big for its
/// few-subtractions route: there the quotient `q` and remainder `r` are
/// stepped a row at a time by the row step's own quotient and remainder
/// (`qs`, `rs`: two divisions an edge, then none; only in boxes wider
/// than [`SCAN_WIDTH`], whose rows are not scanned) — the same quotients,
/// so the same pixels (the micro:bit's rotating cube, whose faces are
/// large: 1.82 -> 1.43 M instructions a frame of raster, measured).
#[derive(Clone, Copy)]
struct Edge {
    a: i32,
    n: i32,
    s: i32,
    q: i32,
    r: i32,
    qs: i32,
    rs: i32,
}

impl Edge {
    /// The edge from `p` to `q` relative to the sub-pixel point `(ox, oy)`.
    #[inline(always)]
    fn new(p: (i32, i32), q: (i32, i32), (ox, oy): (i32, i32), stepped: bool) -> Edge {
        let (dx, dy) = (q.0 - p.0, q.1 - p.1);
        let top_left = dy < 0 || (dy == 0 && dx > 0);
        Edge::of(
            -dy << SUBPIXEL_BITS,
            dx * (oy - p.1) - dy * (ox - p.0) - (!top_left) as i32,
            dx << SUBPIXEL_BITS,
            stepped,
        )
    }

    /// The edge `a k + n` along a row, `n` growing by `s` a row.
    #[inline(always)]
    fn of(a: i32, n: i32, s: i32, stepped: bool) -> Edge {
        let mut e = Edge {
            a,
            n,
            s,
            q: 0,
            r: 0,
            qs: 0,
            rs: 0,
        };
        if stepped && e.a != 0 {
            e.start_steps();
        }
        e
    }

    /// Divides once for the stepped quotients (`a != 0`).
    #[inline(always)]
    fn start_steps(&mut self) {
        let d = self.a.abs();
        (self.q, self.qs) = (div_floor_i32(self.n, d), div_floor_i32(self.s, d));
        (self.r, self.rs) = (self.n - self.q * d, self.s - self.qs * d);
    }

    /// Steps the quotient and remainder a row (`a != 0`).
    #[inline(always)]
    fn step(&mut self) {
        let d = self.a.abs();
        (self.q, self.r) = (self.q + self.qs, self.r + self.rs);
        if self.r >= d {
            (self.q, self.r) = (self.q + 1, self.r - d);
        }
    }

    /// Steps to the next row (`stepped`: its quotient too, as
    /// [`Self::new`] was told).
    #[inline(always)]
    fn next(&mut self, stepped: bool) {
        self.n += self.s;
        if stepped && self.a != 0 {
            self.step();
        }
    }

    /// `floor(n / |a|)` for `a != 0`.
    #[inline(always)]
    fn quotient(&self) -> i32 {
        if LONG_MUL {
            div_floor_i32(self.n, self.a.abs())
        } else {
            self.q
        }
    }

    /// Narrows the row's run `[lo, hi)` to this edge's side of it.
    #[inline(always)]
    fn clip(&self, lo: &mut i32, hi: &mut i32) {
        if self.a > 0 {
            // a k + n >= 0  <=>  k >= ceil(-n / a) = -floor(n / a).
            *lo = (*lo).max(-self.quotient());
        } else if self.a < 0 {
            // k <= floor(n / -a).
            *hi = (*hi).min(self.quotient() + 1);
        } else if self.n < 0 {
            *hi = *lo;
        }
    }
}

/// One attribute's plane: value at the anchor pixel, steps per pixel and
/// per row (wrapping `i32`).
#[derive(Clone, Copy)]
struct Plane {
    c: i32,
    gx: i32,
    gy: i32,
}

/// What every attribute's plane shares: the barycentric weights' steps
/// and the anchor's offset from vertex 0.
struct Recip {
    /// Steps of the weights of vertices 1 and 2 per pixel (`x`) and per
    /// row (`y`), `bits` fraction bits.
    wx: (i32, i32),
    wy: (i32, i32),
    /// Fraction bits of the weights' steps: [`W_BITS`], fewer for a
    /// sliver (whose weights change by 2 or more a pixel or a row).
    bits: u32,
    /// Anchor centre minus vertex 0, sub-pixels.
    o: (i32, i32),
}

/// Doubled areas (sub-pixels squared) the plane contract's reciprocal
/// serves: below 2^16 (triangles under 128 square pixels).
pub(crate) const PLANE_AREA_LIMIT: i32 = 1 << 16;

/// Width plus height (pixels) of a large triangle's box the plane contract
/// serves: below 512, so a value's error from the steps' rounding stays
/// below 2^-4 of a depth unit.
pub(crate) const LARGE_EXTENT: u32 = 512;

/// Fraction bits of the weights' steps.
const W_BITS: u32 = 30;

/// How far a weight's step may change across the triangle's box, at most:
/// `2^8` with [`W_BITS`] fraction bits, the bound every value's error
/// follows from ([`Recip::conditioned`]).
const W_SPREAD_BITS: u32 = W_BITS + 8;

/// `floor((2^46 - 1) / a)` for `0 < a < 2^16`, by three 32-bit divisions
/// (16-bit digits of long division): at least 2^30, so within 2^-30 of
/// `2^46 / a`.
///
/// On a core without a divide instruction (the Cortex-M0, where each
/// 32-bit division is a library call of about 130 instructions) one
/// division instead of three ([`reciprocal46_m0`]).
#[inline(always)]
pub(crate) fn reciprocal46(a: u32) -> u64 {
    reciprocal46_by::<{ LONG_MUL }>(a)
}

/// [`reciprocal46`] by three divisions (`DIV`) or by the Cortex-M0's route
/// (the tests run both).
#[inline(always)]
fn reciprocal46_by<const DIV: bool>(a: u32) -> u64 {
    if !DIV {
        return reciprocal46_m0(a);
    }
    debug_assert!(a > 0 && a < PLANE_AREA_LIMIT as u32);
    const HI: u32 = (1 << 14) - 1;
    let q1 = HI / a;
    let n2 = ((HI - q1 * a) << 16) | 0xffff;
    let q2 = n2 / a;
    let q3 = (((n2 - q2 * a) << 16) | 0xffff) / a;
    (q1 as u64) << 32 | (q2 as u64) << 16 | q3 as u64
}

/// [`reciprocal46`] from one division: `R = floor((2^32 - 1) / a)`, so
/// `q0 = R 2^14` falls short of the quotient by less than `2^14 + 1`
/// (`R a <= 2^32 - 1`, a 32-bit product), and the remainder
/// `m = 2^46 - 1 - q0 a = (2^32 - 1 - R a) 2^14 + 2^14 - 1` is below
/// `2^30 + 2^14`. Its quotient by `a` is `t = floor(m R / 2^32)` (one
/// 32x32-bit high product of 16-bit pieces) or at most two more, since
/// `m / a - m R / 2^32 < m (1 + 1/a) / 2^32 < 1`.
#[cfg_attr(all(target_arch = "arm", not(target_has_atomic = "32")), inline(never))]
fn reciprocal46_m0(a: u32) -> u64 {
    debug_assert!(a > 0 && a < PLANE_AREA_LIMIT as u32);
    let r = u32::MAX / a;
    let m = ((u32::MAX - r * a) << 14) | ((1 << 14) - 1);
    let mut t = (wide_mul(m, r) >> 32) as u32;
    let mut left = m - t * a;
    while left >= a {
        (t, left) = (t + 1, left - a);
    }
    ((r as u64) << 14) + t as u64
}

impl Recip {
    /// From the doubled area and the steps of the edges opposite vertices
    /// 1 and 2 per pixel (`a`) and per row (`s`): each weight's step
    /// `round(k r / 2^16)`, `k / area2` with 30 fraction bits, and the
    /// weights' spread over a box of `extent` (width plus height) pixels
    /// checked ([`Self::conditioned`]). A sliver's steps (a weight
    /// changing by 2 or more a pixel or a row: `|k| >= 2 area2`) do not
    /// fit `i32` with 30 fraction bits; they keep `30 - s`, the fewest
    /// dropped bits `s` that fit, rounded (so `|k| < 2^15 area2`, where
    /// `k r < 2^62`). `None` outside the contract's domain.
    #[inline(always)]
    fn new(area2: i32, a: (i32, i32), s: (i32, i32), o: (i32, i32), extent: u32) -> Option<Recip> {
        let m = a.0.unsigned_abs() | a.1.unsigned_abs() | s.0.unsigned_abs() | s.1.unsigned_abs();
        // (An OR of the magnitudes is at least their largest, below twice it.)
        if area2 >= PLANE_AREA_LIMIT {
            return Self::large(area2, m, (a, s), o, extent);
        }
        let r = reciprocal46(area2 as u32) as i64;
        if m < 2 * area2 as u32 {
            // Every step below 2^31: the common case, 32-bit steps. `k` is
            // a multiple of 16 below 2^17: on the Cortex-M0 `k r` is
            // `(k / 16) (16 r)`, two 32-bit products of a 15-bit factor
            // ([`wrapping_mul_i32`]) instead of `__aeabi_lmul`.
            let kr = |k: i32| {
                if LONG_MUL {
                    k as i64 * r
                } else {
                    debug_assert!(k % (1 << SUBPIXEL_BITS) == 0);
                    wrapping_mul_i32(r << SUBPIXEL_BITS, k >> SUBPIXEL_BITS)
                }
            };
            let w = |k: i32| ((kr(k) + (1 << 15)) >> (46 - W_BITS)) as i32;
            let rc = Recip {
                wx: (w(a.0), w(a.1)),
                wy: (w(s.0), w(s.1)),
                bits: W_BITS,
                o,
            };
            // Each step is below 2^31 (`|k| < 2 area2`, `r <= 2^46 /
            // area2`): 31 bits, so a box under 2^7 pixels is conditioned
            // without looking (a mesh's triangles; the test costs ~20
            // instructions a pair).
            return (extent < 1 << (W_SPREAD_BITS - 31) || rc.conditioned(extent)).then_some(rc);
        }
        Self::sliver(area2, r, m, (a, s), o, extent)
    }

    /// [`Self::new`] for a large triangle (`area2 >= 2^16`): the
    /// reciprocal `floor((2^62 - 1) / area2)` by one 64-bit division, each
    /// weight's step `round(k r / 2^32)` with [`W_BITS`] fraction bits, out
    /// of line (a large triangle's rows cost far more than the division).
    /// Its box must be under [`LARGE_EXTENT`] pixels of width plus height,
    /// and it must not be a sliver; else `None`.
    #[inline(never)]
    #[cold]
    fn large(
        area2: i32,
        m: u32,
        (a, s): ((i32, i32), (i32, i32)),
        o: (i32, i32),
        extent: u32,
    ) -> Option<Recip> {
        if m >= 2 * area2 as u32 || extent >= LARGE_EXTENT {
            return None;
        }
        let rc = Self::divided(area2 as u64, (a, s), o);
        rc.conditioned(extent).then_some(rc)
    }

    /// The weights' steps of a triangle that is not a sliver (`|k| < 2
    /// area2` for every step `k`), whatever its doubled area (below
    /// 2^38): the reciprocal `floor((2^62 - 1) / area2)` by one 64-bit
    /// division, each step `round(k r / 2^32)` with [`W_BITS`] fraction
    /// bits (`|k r| < 2^63`), within 2^-31 of `k / area2` plus
    /// `|k| 2^-32`.
    #[inline(always)]
    fn divided(area2: u64, (a, s): ((i32, i32), (i32, i32)), o: (i32, i32)) -> Recip {
        let r = (((1u64 << 62) - 1) / area2) as i64;
        let w = |k: i32| ((k as i64 * r + (1 << 31)) >> 32) as i32;
        Recip {
            wx: (w(a.0), w(a.1)),
            wy: (w(s.0), w(s.1)),
            bits: W_BITS,
            o,
        }
    }

    /// [`Self::new`] for a sliver: fewer fraction bits, out of line.
    #[inline(never)]
    #[cold]
    fn sliver(
        area2: i32,
        r: i64,
        m: u32,
        (a, s): ((i32, i32), (i32, i32)),
        o: (i32, i32),
        extent: u32,
    ) -> Option<Recip> {
        if m as u64 >= (area2 as u64) << 15 {
            return None;
        }
        let w = |k: i32| (k as i64 * r + (1 << 15)) >> (46 - W_BITS);
        let (wx, wy) = ((w(a.0), w(a.1)), (w(s.0), w(s.1)));
        let big =
            wx.0.unsigned_abs() | wx.1.unsigned_abs() | wy.0.unsigned_abs() | wy.1.unsigned_abs();
        // The spread across the box, in the weights' full precision.
        if (64 - big.leading_zeros()) + (32 - extent.leading_zeros()) > W_SPREAD_BITS {
            return None;
        }
        let drop = (64 - big.leading_zeros()).saturating_sub(31);
        let n = |w: i64| ((w + ((1 << drop) >> 1)) >> drop) as i32;
        Some(Recip {
            wx: (n(wx.0), n(wx.1)),
            wy: (n(wy.0), n(wy.1)),
            bits: W_BITS - drop,
            o,
        })
    }

    /// Whether the weights change by less than 2^8 across a box of
    /// `extent` (width plus height) pixels: the domain, where a value's
    /// error stays below `2^8 |d| 2^-30` (`|d|` the attribute's largest
    /// difference between vertices, in its DDA units) plus the steps'
    /// rounding — under 1/64 of a depth unit. (A sliver's steps, with
    /// `s` fraction bits dropped, err by up to `2^(s-1)` units of 2^-30
    /// more; its spread bound keeps `2^s extent <= 2^8`, so the same
    /// order: `tile::mesh`'s tests measure it.)
    #[inline(always)]
    fn conditioned(&self, extent: u32) -> bool {
        let m = self.wx.0.unsigned_abs()
            | self.wx.1.unsigned_abs()
            | self.wy.0.unsigned_abs()
            | self.wy.1.unsigned_abs();
        (32 - m.leading_zeros()) + (32 - extent.leading_zeros()) <= W_SPREAD_BITS
    }

    /// The plane of an attribute worth `a0` at vertex 0 and `a0 + d1`,
    /// `a0 + d2` at the (oriented) others: steps `round(d1 w1 + d2 w2)`
    /// (two 32x32-bit products; `bits` is [`Self::bits`], passed so the
    /// common path's shifts are constants), and the anchor's value through
    /// them.
    ///
    /// With `NARROW` the caller knows both steps fit `i32` (a colour lane,
    /// `|d| < 2^25`, on the common path, whose weights' steps are below
    /// 2^31: each step below 2^27), and the anchor's products are 32x32-bit
    /// ones — the same numbers.
    #[inline(always)]
    fn plane<const NARROW: bool>(&self, bits: u32, a0: i32, d1: i32, d2: i32) -> Plane {
        let (gx, gy) = self.steps(bits, d1, d2);
        // The anchor's value through the steps (as the exact contract's
        // small triangles: `crate::setup`): wrapping 64-bit products of the
        // whole steps, whose shifted low 32 bits are exact modulo 2^32 (a
        // sliver's step may not fit `i32`; the values inside it do).
        let round = 1 << (SUBPIXEL_BITS - 1);
        // The anchor's offsets lie in the box (`|o| < 2^15` sub-pixels): on
        // the Cortex-M0 `dot2_i16` is four 32-bit products and
        // `wrapping_mul_i32` two.
        let off = if NARROW {
            debug_assert!(gx as i32 as i64 == gx && gy as i32 as i64 == gy);
            (dot2_i16(gx as i32, self.o.0, gy as i32, self.o.1) + round) >> SUBPIXEL_BITS
        } else {
            wrapping_mul_i32(gx, self.o.0)
                .wrapping_add(wrapping_mul_i32(gy, self.o.1))
                .wrapping_add(round)
                >> SUBPIXEL_BITS
        };
        Plane {
            c: a0.wrapping_add(off as i32),
            gx: gx as i32,
            gy: gy as i32,
        }
    }

    /// An attribute's steps per pixel and per row, `round(d1 w1 + d2 w2)`
    /// with `bits` fraction bits dropped (two 32x32-bit products each).
    #[inline(always)]
    fn steps(&self, bits: u32, d1: i32, d2: i32) -> (i64, i64) {
        // (`dot2_wide`: on the Cortex-M0 32-bit products of 16-bit halves,
        // not the general 64x64-bit library multiply.)
        let g = |w: (i32, i32)| (dot2_wide(d1, w.0, d2, w.1) + (1 << (bits - 1))) >> bits;
        (g(self.wx), g(self.wy))
    }

    /// A far triangle's plane ([`Tile::far_triangle`]) of an attribute
    /// worth `a0` at vertex 0 and `a0 + d1`, `a0 + d2` at the others:
    /// the steps of [`Self::steps`], and the value at the cell's anchor
    /// from its weights `w` (2^-30 units, [`anchor_weights`]) exactly
    /// rounded, modulo 2^32: within 1.5 units of the exact value there.
    #[inline(always)]
    fn far_plane(&self, w: (i128, i128), a0: i32, d1: i32, d2: i32) -> Plane {
        let (gx, gy) = self.steps(W_BITS, d1, d2);
        let off = (d1 as i128 * w.0 + d2 as i128 * w.1 + (1 << (W_BITS - 1))) >> W_BITS;
        Plane {
            c: a0.wrapping_add(off as i32),
            gx: gx as i32,
            gy: gy as i32,
        }
    }
}

/// An attribute's plane from its value `a0` at vertex 0 and its
/// differences `d1`, `d2` at the others (`lane`: a colour lane's, below
/// 2^25): [`Tile::planes_by`].
trait PlaneOf {
    fn plane(&self, a0: i32, d1: i32, d2: i32, lane: bool) -> Plane;
}

/// The 32-bit setup's planes: steps with `bits` fraction bits, the anchor
/// reached through them ([`Recip::plane`]).
struct Anchored<'a> {
    rc: &'a Recip,
    bits: u32,
}

impl PlaneOf for Anchored<'_> {
    #[inline(always)]
    fn plane(&self, a0: i32, d1: i32, d2: i32, lane: bool) -> Plane {
        if lane && self.bits == W_BITS {
            self.rc.plane::<true>(self.bits, a0, d1, d2)
        } else {
            self.rc.plane::<false>(self.bits, a0, d1, d2)
        }
    }
}

/// A far triangle's planes in one cell: the anchor's weights `w`
/// ([`Recip::far_plane`]).
struct Weighted<'a> {
    rc: &'a Recip,
    w: (i128, i128),
}

impl PlaneOf for Weighted<'_> {
    #[inline(always)]
    fn plane(&self, a0: i32, d1: i32, d2: i32, _: bool) -> Plane {
        self.rc.far_plane(self.w, a0, d1, d2)
    }
}

/// The weights of the (oriented) vertices 1 and 2 at the sub-pixel point
/// `p`, `round(E 2^30 / area2)` of the edge functions opposite them
/// (`E(p) = (q - a) x (p - a)` for the edge `a -> q`), exactly: a far
/// triangle's anchors may lie far from every vertex, where the weights'
/// steps, summed, would err by more than the contract allows.
#[inline(always)]
fn anchor_weights([p0, p1, p2]: [(i32, i32); 3], area2: i64, p: (i64, i64)) -> (i128, i128) {
    let cross = |a: (i32, i32), q: (i32, i32)| {
        (q.0 - a.0) as i64 * (p.1 - a.1 as i64) - (q.1 - a.1) as i64 * (p.0 - a.0 as i64)
    };
    let w = |e: i64| {
        let n = (e as i128) << W_BITS;
        let d = area2 as i128;
        // Rounded to nearest, ties up: `floor((2 n + d) / 2 d)`.
        (2 * n + d).div_euclid(2 * d)
    };
    (w(cross(p2, p0)), w(cross(p0, p1)))
}

impl<const N: usize, C: TileConfig> Tile<N, C> {
    /// Whether an opaque Gouraud triangle with state `st` takes the plane
    /// contract's path in this configuration.
    #[inline(always)]
    pub(crate) fn plane_path(st: &State) -> bool {
        <C::Precision as Precision>::PLANE
            && <C::Aa as AaMode>::SAMPLES == 0
            && !(<C::Blending as BlendMode>::ALPHA && st.blend.translucent())
    }

    /// Draws a mesh triangle from its compact vertices with state `st`,
    /// as [`Tile::draw`] draws the [`Command::Triangle`] of the same
    /// vertices: under the plane contract when the configuration chooses it
    /// and the triangle is in its domain, else through the command path.
    #[inline(always)]
    pub(crate) fn draw_mesh_triangle(&mut self, v: [&MeshVertex; 3], st: &State) {
        if Self::plane_path(st) && self.plane_triangle(v, st) {
            return;
        }
        let v = v.map(MeshVertex::vertex);
        self.draw_valid(&Command::Triangle { v, state: *st }, &[]);
    }

    /// The colour lanes' and depth's planes of the triangle `v` (vertex 0
    /// then the other two in the orientation's order) through `rc`, whose
    /// steps have `bits` fraction bits (a constant on the common path, so
    /// its shifts are).
    #[inline(always)]
    fn planes(rc: &Recip, bits: u32, v: [&MeshVertex; 3]) -> ([Plane; 4], Plane) {
        Self::planes_by(v, &Anchored { rc, bits })
    }

    /// The colour lanes' and depth's planes of the triangle `v`, each
    /// [`PlaneOf::plane`] of its value at vertex 0 and differences at the
    /// others. (A trait, not a closure: at the micro:bit's `opt-level =
    /// "s"` a closure stayed out of line, its shifts by `bits` no longer
    /// constants: 64-bit shifts by library call, +1.5% on its demo frame,
    /// measured.)
    #[inline(always)]
    fn planes_by(v: [&MeshVertex; 3], plane: &impl PlaneOf) -> ([Plane; 4], Plane) {
        let lanes = |k: usize| C::Format::lanes_from_rgb8(v[k].rgb);
        let (l0, l1, l2) = (lanes(0), lanes(1), lanes(2));
        let mut cp = [Plane { c: 0, gx: 0, gy: 0 }; 4];
        for (i, p) in cp
            .iter_mut()
            .enumerate()
            .take(<C::Format as PixelFormat>::Lanes::LEN)
        {
            let c0 = l0.lane(i);
            let (d1, d2) = (l1.lane(i) - c0, l2.lane(i) - c0);
            *p = plane.plane(c0, d1, d2, true);
        }
        let zl = |k: usize| (v[k].z as i32) << Z_FRAC;
        let zp = plane.plane(zl(0), zl(1) - zl(0), zl(2) - zl(0), false);
        (cp, zp)
    }

    /// [`Self::planes`] of a sliver (fewer fraction bits, a shift by a
    /// variable), out of line.
    #[inline(never)]
    #[cold]
    fn sliver_planes(rc: &Recip, v: [&MeshVertex; 3]) -> ([Plane; 4], Plane) {
        Self::planes(rc, rc.bits, v)
    }

    /// The triangle `v`'s sub-pixel box's width and height, its pixel
    /// box `[x0, x1, y0, y1]` (pixel centres inside; its top-left is the
    /// planes' anchor) and that box clipped to the tile, `None` if empty.
    #[inline(always)]
    fn boxes(&self, v: [&MeshVertex; 3]) -> ((i32, i32), [i32; 4], Option<[i32; 4]>) {
        let (x0, x1) = (
            v[0].x.min(v[1].x).min(v[2].x),
            v[0].x.max(v[1].x).max(v[2].x),
        );
        let (y0, y1) = (
            v[0].y.min(v[1].y).min(v[2].y),
            v[0].y.max(v[1].y).max(v[2].y),
        );
        let (bx0, bx1) = pixel_span(x0, x1);
        let (by0, by1) = pixel_span(y0, y1);
        let t = self.area;
        let (cx0, cx1) = (bx0.max(t.x), bx1.min(t.x + t.w as i32 - 1));
        let (cy0, cy1) = (by0.max(t.y), by1.min(t.y + t.h as i32 - 1));
        let clipped = (cx0 <= cx1 && cy0 <= cy1).then_some([cx0, cx1, cy0, cy1]);
        ((x1 - x0, y1 - y0), [bx0, bx1, by0, by1], clipped)
    }

    /// Draws the opaque Gouraud triangle `v` under the plane contract
    /// ([module docs](self)); `false`, with nothing drawn, when the
    /// triangle lies outside the contract's domain. Vertex coordinates lie
    /// in the validated domain (`|x|, |y| < 2^17` sub-pixels).
    ///
    /// A far triangle is drawn from here, not from the 32-bit setup
    /// ([`Self::near_triangle`]): the two frames never stack (the
    /// micro:bit's 16 KB of RAM).
    #[inline(always)]
    pub(crate) fn plane_triangle(&mut self, v: [&MeshVertex; 3], st: &State) -> bool {
        match self.near_triangle(v, st) {
            Some(drawn) => drawn,
            None => self.far_triangle(v, st),
        }
    }

    /// [`Self::plane_triangle`] by the 32-bit setup ([module docs](self)):
    /// `Some(true)` when drawn (or nothing to draw in this tile), `None`,
    /// with nothing drawn, when the triangle is too large for it.
    #[inline(never)]
    fn near_triangle(&mut self, v: [&MeshVertex; 3], st: &State) -> Option<bool> {
        let (sides, [bx0, bx1, by0, by1], clipped) = self.boxes(v);
        if sides.0 as i64 >= SMALL_EXTENT || sides.1 as i64 >= SMALL_EXTENT {
            return None;
        }
        let Some([cx0, cx1, cy0, cy1]) = clipped else {
            return Some(true);
        };
        let Some(([p0, p1, p2], (i1, i2), area2)) = oriented(v, |a, b| a * b) else {
            return Some(true);
        };
        let half = 1 << (SUBPIXEL_BITS - 1);
        let o = ((cx0 << SUBPIXEL_BITS) + half, (cy0 << SUBPIXEL_BITS) + half);
        let width = cx1 - cx0 + 1;
        // A narrow box's rows are scanned ([`row_run`]); only a wider one
        // divides, and on a core without a divider steps its quotients.
        let stepped = !LONG_MUL && width > SCAN_WIDTH;
        let mut e = [
            Edge::new(p1, p2, o, stepped),
            Edge::new(p2, p0, o, stepped),
            Edge::new(p0, p1, o, stepped),
        ];
        let Some(first) = first_run(&mut e, (cy0, cy1, width), stepped) else {
            return Some(true);
        };
        // The first covered row: the attribute planes (outside the
        // domain, nothing drawn: a large triangle may still be a far one).
        let o = (
            (bx0 << SUBPIXEL_BITS) + half - p0.0,
            (by0 << SUBPIXEL_BITS) + half - p0.1,
        );
        let extent = ((bx1 - bx0) + (by1 - by0) + 2) as u32;
        let rc = Recip::new(area2, (e[1].a, e[2].a), (e[1].s, e[2].s), o, extent)?;
        let ends = [v[0], v[i1], v[i2]];
        let (cp, zp) = if rc.bits == W_BITS {
            Self::planes(&rc, W_BITS, ends)
        } else {
            Self::sliver_planes(&rc, ends)
        };
        let rows = (cx0, cy1, width);
        self.plane_rows(&mut e, rows, first, stepped, st, (&cp, &zp, (bx0, by0)));
        Some(true)
    }

    /// From the first covered row `first` (its `y` and run) down to row
    /// `cy1` of a clipped box `width` pixels wide from column `cx0`, its
    /// edges `e` at that row (`stepped` as they were made): every covered
    /// row's run through the span loop, its values from the colour lanes'
    /// and depth's planes anchored at pixel `(ax, ay)`.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn plane_rows(
        &mut self,
        e: &mut [Edge; 3],
        (cx0, cy1, width): (i32, i32, i32),
        (mut py, mut lo, mut hi): (i32, i32, i32),
        stepped: bool,
        st: &State,
        (cp, zp, (ax, ay)): (&[Plane; 4], &Plane, (i32, i32)),
    ) {
        let dc = <C::Format as PixelFormat>::Lanes::from_fn(|i| cp[i].gx);
        loop {
            if lo < hi {
                let (i, j) = (cx0 + lo - ax, py - ay);
                let at = |p: &Plane| {
                    p.c.wrapping_add(j.wrapping_mul(p.gy))
                        .wrapping_add(i.wrapping_mul(p.gx))
                };
                let s = SpanStart {
                    c: <C::Format as PixelFormat>::Lanes::from_fn(|k| at(&cp[k])),
                    dc,
                    z: at(zp),
                    dz: zp.gx,
                };
                self.span_with::<false, true>(
                    (cx0 + lo) as i64,
                    py as i64,
                    (hi - lo) as i64,
                    s,
                    dc,
                    st,
                );
            }
            if py == cy1 {
                return;
            }
            py += 1;
            for e in e.iter_mut() {
                e.next(stepped);
            }
            (lo, hi) = row_run(e, width);
        }
    }

    /// A far triangle's block's rows ([`Self::plane_rows`]), out of line:
    /// the span loop's registers apart from the far setup's 64-bit and
    /// 128-bit values. (The far setup's frame is 864 bytes on the
    /// Cortex-M0; it is entered beside the 32-bit setup's, never on top
    /// of it: [`Self::plane_triangle`].)
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn far_rows(
        &mut self,
        e: &mut [Edge; 3],
        rows: (i32, i32, i32),
        first: (i32, i32, i32),
        stepped: bool,
        st: &State,
        planes: (&[Plane; 4], &Plane, (i32, i32)),
    ) {
        self.plane_rows(e, rows, first, stepped, st, planes)
    }

    /// [`Self::plane_triangle`] for a triangle too large for its 32-bit
    /// setup (a side of [`SMALL_EXTENT`] sub-pixels or more, or a box of
    /// [`LARGE_EXTENT`] pixels of width plus height: the near-clipped
    /// pieces of a ground or a wall beside the camera), out of line.
    /// `false`, with nothing drawn, for a sliver.
    ///
    /// The screen is cut into cells [`FAR_CELL`] pixels square and those
    /// into blocks [`FAR_BLOCK`] pixels square, both aligned at the
    /// origin, so neither depends on the tiling. Per block of the clipped
    /// box: the edges, exactly in 64 bits at its first pixel — an edge the
    /// whole block is inside of is dropped, one it is outside of empties
    /// the block, and one that crosses it fits 32 bits there; then the
    /// rows as [`Self::plane_rows`] walks them. Per cell, at its first
    /// covered row: planes anchored at the top-left pixel of the
    /// triangle's box within the cell, whose values come from that
    /// pixel's exactly rounded weights ([`anchor_weights`]), so a value's
    /// error is the anchor's (1.5 units) plus at most 510 steps' (1.5
    /// units each, the steps of [`Recip::divided`]): below 2^-4 of a
    /// depth unit and 2^-7 of a colour unit.
    #[inline(never)]
    #[cold]
    fn far_triangle(&mut self, v: [&MeshVertex; 3], st: &State) -> bool {
        let (_, [bx0, _, by0, _], clipped) = self.boxes(v);
        let Some([cx0, cx1, cy0, cy1]) = clipped else {
            return true;
        };
        let wide = |a: i32, b: i32| a as i64 * b as i64;
        let Some(([p0, p1, p2], (i1, i2), area2)) = oriented(v, wide) else {
            return true;
        };
        let ends = [(p1, p2), (p2, p0), (p0, p1)];
        let steps = ends.map(|(p, q)| ((p.1 - q.1) << SUBPIXEL_BITS, (q.0 - p.0) << SUBPIXEL_BITS));
        let (a, s) = ((steps[1].0, steps[2].0), (steps[1].1, steps[2].1));
        let m = a.0.unsigned_abs() | a.1.unsigned_abs() | s.0.unsigned_abs() | s.1.unsigned_abs();
        if m as u64 >= 2 * area2 as u64 {
            return false;
        }
        let rc = Recip::divided(area2 as u64, (a, s), (0, 0));
        let verts = [v[0], v[i1], v[i2]];
        let half = 1 << (SUBPIXEL_BITS - 1);
        let centre = |p: i32| ((p as i64) << SUBPIXEL_BITS) + half;
        // The planes of the cell last drawn in.
        let mut cell: Option<((i32, i32), [Plane; 4], Plane)> = None;
        let block = |lo: i32| lo & !(FAR_BLOCK - 1);
        let mut by = block(cy0);
        while by <= cy1 {
            let (ry0, ry1) = (cy0.max(by), cy1.min(by + FAR_BLOCK - 1));
            let mut bx = block(cx0);
            while bx <= cx1 {
                let (rx0, rx1) = (cx0.max(bx), cx1.min(bx + FAR_BLOCK - 1));
                let width = rx1 - rx0 + 1;
                let stepped = !LONG_MUL && width > SCAN_WIDTH;
                let (ox, oy) = (centre(rx0), centre(ry0));
                let mut e = [Edge::of(0, 0, 0, false); 3];
                let mut empty = false;
                for (k, &(p, q)) in ends.iter().enumerate() {
                    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
                    let top_left = dy < 0 || (dy == 0 && dx > 0);
                    let (ea, es) = steps[k];
                    let n = dx as i64 * (oy - p.1 as i64)
                        - dy as i64 * (ox - p.0 as i64)
                        - (!top_left) as i64;
                    // The edge's least and greatest values in the block,
                    // at two of its corners.
                    let (da, ds) = (wide(ea, rx1 - rx0), wide(es, ry1 - ry0));
                    if n + da.min(0) + ds.min(0) >= 0 {
                        continue; // the whole block inside: no test
                    }
                    if n + da.max(0) + ds.max(0) < 0 {
                        empty = true;
                        break;
                    }
                    // Crossing: every value in the block within
                    // `(|a| + |s|) 63 < 2^29` of the others, so in `i32`.
                    e[k] = Edge::of(ea, n as i32, es, stepped);
                }
                let first = (!empty)
                    .then(|| first_run(&mut e, (ry0, ry1, width), stepped))
                    .flatten();
                if let Some(first) = first {
                    // The planes of the block's cell, at its first covered
                    // row.
                    let here = (bx >> FAR_CELL_BITS, by >> FAR_CELL_BITS);
                    let (ax, ay) = anchor_of(here, (bx0, by0));
                    let (_, cp, zp) = match cell {
                        Some(c) if c.0 == here => c,
                        _ => {
                            let w = anchor_weights([p0, p1, p2], area2, (centre(ax), centre(ay)));
                            let (cp, zp) = Self::planes_by(verts, &Weighted { rc: &rc, w });
                            *cell.insert((here, cp, zp))
                        }
                    };
                    let rows = (rx0, ry1, width);
                    self.far_rows(&mut e, rows, first, stepped, st, (&cp, &zp, (ax, ay)));
                }
                bx += FAR_BLOCK;
            }
            by += FAR_BLOCK;
        }
        true
    }
}

/// The triangle `v`'s corners oriented so that its inside is where every
/// edge is `>= bias`: vertex 0 and the other two in that order, their
/// indices, and the doubled area (positive; `mul` the product, in `i32`
/// or `i64`); `None` for a degenerate triangle.
#[inline(always)]
#[allow(clippy::type_complexity)]
fn oriented<T>(
    v: [&MeshVertex; 3],
    mul: impl Fn(i32, i32) -> T,
) -> Option<([(i32, i32); 3], (usize, usize), T)>
where
    T: Copy + Default + PartialOrd + core::ops::Sub<Output = T> + core::ops::Neg<Output = T>,
{
    let (p0, p1, p2) = ((v[0].x, v[0].y), (v[1].x, v[1].y), (v[2].x, v[2].y));
    let area2 = mul(p1.0 - p0.0, p2.1 - p0.1) - mul(p1.1 - p0.1, p2.0 - p0.0);
    let zero = T::default();
    if area2 > zero {
        Some(([p0, p1, p2], (1, 2), area2))
    } else if area2 < zero {
        Some(([p0, p2, p1], (2, 1), -area2))
    } else {
        None
    }
}

/// The anchor of a far triangle's planes in the cell `(cx, cy)`: the
/// top-left pixel of the triangle's box (top-left pixel `b`) within it.
#[inline(always)]
fn anchor_of((cx, cy): (i32, i32), b: (i32, i32)) -> (i32, i32) {
    (b.0.max(cx << FAR_CELL_BITS), b.1.max(cy << FAR_CELL_BITS))
}

/// Side of a far triangle's cells ([`Tile::far_triangle`]), pixels: each
/// cell's planes are anchored in it, so no value is more than 510 steps
/// from its anchor.
const FAR_CELL_BITS: u32 = 8;
/// [`FAR_CELL_BITS`] as a side.
const FAR_CELL: i32 = 1 << FAR_CELL_BITS;
/// Side of a far triangle's blocks, pixels (a divisor of [`FAR_CELL`]):
/// an edge that crosses a block has values within `2^23 * 126 < 2^30` of
/// each other there.
const FAR_BLOCK: i32 = 64;
const _: () = assert!(FAR_CELL % FAR_BLOCK == 0);

/// Steps the edges `e` (at row `cy0` of a clipped box `width` pixels
/// wide, `stepped` as they were made) down to the first covered row of
/// `cy0..=cy1`: its `y` and run, `None` if no row is covered.
#[inline(always)]
fn first_run(
    e: &mut [Edge; 3],
    (cy0, cy1, width): (i32, i32, i32),
    stepped: bool,
) -> Option<(i32, i32, i32)> {
    let mut py = cy0;
    loop {
        let (lo, hi) = row_run(e, width);
        if lo < hi {
            return Some((py, lo, hi));
        }
        if py == cy1 {
            return None;
        }
        py += 1;
        for e in e.iter_mut() {
            e.next(stepped);
        }
    }
}

/// Clipped boxes at most this many pixels wide find each row's run by
/// stepping the three edge functions across the row ([`scan_run`]), on a
/// core without a divide instruction (the Cortex-M0, whose library
/// division or few-subtractions quotient costs more than a row of
/// additions); cores that divide never scan. Measured on the micro:bit's
/// demo frame (QEMU, raster without the flush): 24.32 M instructions
/// dividing, 23.48 M scanning boxes up to 4 pixels wide, 22.96 M up to 8,
/// 22.94 M up to 16; the same pixels.
const SCAN_WIDTH: i32 = if LONG_MUL { 0 } else { 8 };

/// The row's covered run `[lo, hi)` of the clipped box's columns
/// `0..width`: the columns `k` where every edge's `a k + n >= 0`, an
/// interval (the triangle is convex); an empty run has `lo >= hi`. A box
/// of at most [`SCAN_WIDTH`] columns is scanned ([`scan_run`]), a wider
/// one divides ([`divide_run`]): the same columns either way.
#[inline(always)]
fn row_run(e: &[Edge; 3], width: i32) -> (i32, i32) {
    if width <= SCAN_WIDTH {
        scan_run(e, width)
    } else {
        divide_run(e, width)
    }
}

/// [`row_run`] by stepping the edge functions across the row, first to
/// the run's start, then to its end: three additions and a sign test a
/// column, no division.
#[inline(always)]
fn scan_run(e: &[Edge; 3], width: i32) -> (i32, i32) {
    let (mut v0, mut v1, mut v2) = (e[0].n, e[1].n, e[2].n);
    let mut k = 0;
    // Outside while any edge function is negative.
    while k < width && (v0 | v1 | v2) < 0 {
        (v0, v1, v2) = (v0 + e[0].a, v1 + e[1].a, v2 + e[2].a);
        k += 1;
    }
    let lo = k;
    while k < width && (v0 | v1 | v2) >= 0 {
        (v0, v1, v2) = (v0 + e[0].a, v1 + e[1].a, v2 + e[2].a);
        k += 1;
    }
    (lo, k)
}

/// [`row_run`] by narrowing `0..width` edge by edge, one floor quotient
/// each ([`Edge::clip`]).
#[inline(always)]
fn divide_run(e: &[Edge; 3], width: i32) -> (i32, i32) {
    let (mut lo, mut hi) = (0, width);
    for e in e {
        e.clip(&mut lo, &mut hi);
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Planes;
    use crate::format::Rgb888Format;
    use crate::fragment::dither::NoDither;
    use crate::fragment::{Depth16, NoWid};
    use crate::geom::Rect;
    use crate::numeric::{xorshift, FullPrecision, PlaneContract};
    use crate::raster::coverage::NoAa;
    use crate::tile::Clear;

    type Exact = Planes<Rgb888Format, Depth16, NoWid, NoDither, NoAa, FullPrecision>;
    type Fast = Planes<Rgb888Format, Depth16, NoWid, NoDither, NoAa, PlaneContract>;
    const SIDE: u32 = 48;
    const CAP: usize = (SIDE * SIDE / 8) as usize;

    fn abs(v: f64) -> f64 {
        if v < 0.0 {
            -v
        } else {
            v
        }
    }

    /// A random triangle over a `SIDE` square and a little beyond: most
    /// small (a mesh's), some tiny or slivers, some large.
    fn triangle(next: &mut impl FnMut() -> u64) -> [MeshVertex; 3] {
        if next() % 8 == 0 {
            return sliver(next);
        }
        let span = match next() % 8 {
            0 => 16 * 4,
            1 => 16 * 255,
            2 | 3 => 16 * 64,
            _ => 16 * 20,
        };
        core::array::from_fn(|_| MeshVertex {
            x: (next() % span) as i32 - 64,
            y: (next() % span) as i32 - 64,
            z: (next() % 60000) as u16,
            rgb: [next() as u8, next() as u8, next() as u8],
            code: 0,
            spare: 0,
        })
    }

    /// A sliver: a long edge and a third vertex a fraction of a pixel to
    /// its side, so a weight changes by 2 or more a pixel or a row.
    fn sliver(next: &mut impl FnMut() -> u64) -> [MeshVertex; 3] {
        let mut p = |lim: u64| (next() % lim) as i32;
        let (x0, y0) = (p(16 * 40), p(16 * 40));
        let (x1, y1) = (x0 + p(16 * 24) - 16 * 12, y0 + p(16 * 24) - 16 * 12);
        let t = p(17);
        let (x2, y2) = (
            x0 + (x1 - x0) * t / 16 + p(9) - 4,
            y0 + (y1 - y0) * t / 16 + p(9) - 4,
        );
        let mut v = [(x0, y0), (x1, y1), (x2, y2)].map(|(x, y)| MeshVertex {
            x,
            y,
            z: 0,
            rgb: [0; 3],
            code: 0,
            spare: 0,
        });
        for v in &mut v {
            v.z = (next() % 60000) as u16;
            v.rgb = [next() as u8, next() as u8, next() as u8];
        }
        v
    }

    /// The doubled area of `v`, sub-pixels squared.
    fn area2(v: &[MeshVertex; 3]) -> i32 {
        let (dx1, dy1) = (v[1].x - v[0].x, v[1].y - v[0].y);
        let (dx2, dy2) = (v[2].x - v[0].x, v[2].y - v[0].y);
        (dx1 * dy2 - dy1 * dx2).abs()
    }

    /// Whether `v` is a sliver the plane contract draws with fewer
    /// fraction bits ([`Recip::sliver`]): an edge step of at least twice
    /// the doubled area.
    fn is_sliver(v: &[MeshVertex; 3]) -> bool {
        let (dx1, dy1) = (v[1].x - v[0].x, v[1].y - v[0].y);
        let (dx2, dy2) = (v[2].x - v[0].x, v[2].y - v[0].y);
        let area2 = area2(v);
        let k = [dx1, dy1, dx2, dy2].map(|d| d.abs() << SUBPIXEL_BITS);
        area2 > 0 && k.iter().any(|&k| k >= 2 * area2)
    }

    fn vertices(v: &[MeshVertex; 3]) -> [crate::command::Vertex; 3] {
        v.map(|v| v.vertex())
    }

    /// The exact rational colour and depth at pixel centre `(px, py)`.
    fn reference(v: &[MeshVertex; 3], px: i32, py: i32) -> ([f64; 3], f64) {
        let (x, y) = (16.0 * px as f64 + 8.0, 16.0 * py as f64 + 8.0);
        let p = v.map(|v| (v.x as f64, v.y as f64));
        let cross = |a: (f64, f64), b: (f64, f64), c: (f64, f64)| {
            (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
        };
        let area = cross(p[0], p[1], p[2]);
        let w1 = cross(p[0], (x, y), p[2]) / area;
        let w2 = cross(p[0], p[1], (x, y)) / area;
        let w0 = 1.0 - w1 - w2;
        let lerp = |f: &dyn Fn(&MeshVertex) -> f64| w0 * f(&v[0]) + w1 * f(&v[1]) + w2 * f(&v[2]);
        (
            core::array::from_fn(|k| lerp(&|v| v.rgb[k] as f64)),
            lerp(&|v| v.z as f64),
        )
    }

    /// What [`compare`] found of one triangle.
    #[derive(Default)]
    struct Compared {
        /// Drawn under the plane contract (else exactly).
        plane: bool,
        fragments: u32,
        /// Colours and depths that differ from the exact contract's.
        differ: u32,
        zdiffer: u32,
        /// Worst colour error against the exact rational value, LSB.
        worst: f64,
    }

    /// Draws `v` into `whole` under the exact and the plane contract, and
    /// under the plane contract in each tile of `tiling`: asserts the same
    /// pixels covered as the exact contract's traversal, every colour and
    /// depth within 0.5 + 2^-4 of the exact rational value (to nearest,
    /// no dither) — the bound the contract documents — or, for a triangle
    /// outside its domain, equal to the exact contract's; and the same
    /// output in the tiles as in one.
    fn compare<const N: usize>(v: &[MeshVertex; 3], whole: Rect, tiling: &[Rect]) -> Compared {
        let st = State::default();
        let tri = Command::Triangle {
            v: vertices(v),
            state: st,
        };
        let mut exact: Tile<N, Exact> = Tile::new();
        exact.begin(whole, &Clear::default()).unwrap();
        exact.draw(&tri).ok();
        let mut fast: Tile<N, Fast> = Tile::new();
        fast.begin(whole, &Clear::default()).unwrap();
        let mut out = Compared {
            plane: fast.plane_triangle([&v[0], &v[1], &v[2]], &st),
            ..Compared::default()
        };
        if !out.plane {
            fast.draw(&tri).ok();
        }
        for &t in tiling {
            let mut q: Tile<N, Fast> = Tile::new();
            q.begin(t, &Clear::default()).unwrap();
            q.draw(&tri).ok();
            for y in t.y..t.y + t.h as i32 {
                for x in t.x..t.x + t.w as i32 {
                    assert_eq!(q.raw(x, y), fast.raw(x, y), "tiling {v:?} at {x},{y}");
                    assert_eq!(q.depth(x, y), fast.depth(x, y), "tiling {v:?}");
                }
            }
        }
        for y in whole.y..whole.y + whole.h as i32 {
            for x in whole.x..whole.x + whole.w as i32 {
                let covered = exact.depth(x, y) != Some(u16::MAX);
                assert_eq!(
                    covered,
                    fast.depth(x, y) != Some(u16::MAX),
                    "coverage {v:?} at {x},{y}"
                );
                if !covered {
                    continue;
                }
                out.fragments += 1;
                out.differ += (exact.raw(x, y) != fast.raw(x, y)) as u32;
                out.zdiffer += (exact.depth(x, y) != fast.depth(x, y)) as u32;
                if !out.plane {
                    assert_eq!(exact.raw(x, y), fast.raw(x, y));
                    continue;
                }
                let (c, z) = reference(v, x, y);
                let raw = fast.raw(x, y).unwrap();
                for (k, c) in c.iter().enumerate() {
                    let px = (raw >> (16 - 8 * k)) & 0xff;
                    let e = abs(px as f64 - c);
                    out.worst = out.worst.max(e);
                    assert!(
                        e <= 0.5 + 1.0 / 16.0,
                        "colour {v:?} at {x},{y}: {px} vs {c}"
                    );
                }
                let dz = abs(fast.depth(x, y).unwrap() as f64 - z);
                assert!(dz <= 0.5 + 1.0 / 16.0, "depth {v:?} at {x},{y}: {dz}");
            }
        }
        out
    }

    /// [`compare`] over random triangles: most in the plane contract's
    /// domain, four quarter tiles against one; some fragments differ from
    /// the exact contract's by rounding, few.
    #[test]
    fn plane_contract_covers_exactly_within_its_bound() {
        let mut next = xorshift(0x9e37_79b9_7f4a_7c15);
        let whole = Rect::new(0, 0, SIDE, SIDE);
        let h = SIDE / 2;
        let quarters =
            [(0, 0), (h, 0), (0, h), (h, h)].map(|(x, y)| Rect::new(x as i32, y as i32, h, h));
        let (mut fast_tris, mut exact_tris, mut fragments, mut differ) = (0, 0, 0u32, 0u32);
        let (mut zdiffer, mut slivers, mut large) = (0u32, 0u32, 0u32);
        let mut worst = 0.0f64;
        for _ in 0..3000 {
            let v = triangle(&mut next);
            let c = compare::<CAP>(&v, whole, &quarters);
            slivers += (c.plane && is_sliver(&v)) as u32;
            large += (c.plane && area2(&v) >= PLANE_AREA_LIMIT) as u32;
            fast_tris += c.plane as u32;
            exact_tris += !c.plane as u32;
            fragments += c.fragments;
            differ += c.differ;
            zdiffer += c.zdiffer;
            worst = worst.max(c.worst);
        }
        {
            extern crate std;
            std::println!(
                "plane contract: {fast_tris} triangles in its domain ({slivers} slivers, \
                 {large} large), \
                 {exact_tris} outside; \
                 {differ} colours and {zdiffer} depths of {fragments} fragments differ from \
                 the exact contract's; \
                 worst error {worst:.4} LSB"
            );
        }
        assert!(
            fast_tris > 2500 && exact_tris > 10 && slivers > 100 && large > 300,
            "{fast_tris} / {exact_tris}, {slivers} slivers, {large} large"
        );
        assert!(differ * 100 < fragments, "{differ} of {fragments} differ");
        assert!(
            zdiffer * 100 < fragments,
            "{zdiffer} of {fragments} depths differ"
        );
        assert!(worst > 0.4, "{worst}"); // the check measured something
    }

    /// [`compare`] over far triangles ([`Tile::far_triangle`]): vertices
    /// up to the validated domain's edge (8,191 pixels out) around a
    /// 96-pixel window across a cell's corner (256, 256), drawn whole
    /// and in tilings whose tiles straddle the cells' and blocks' edges.
    #[test]
    fn far_triangles_cover_exactly_within_the_bound() {
        extern crate std;
        const W: u32 = 96;
        let mut next = xorshift(0x3c6e_f372_fe94_f82b);
        let whole = Rect::new(208, 208, W, W);
        let tiles = |side: u32| {
            let k = W.div_ceil(side);
            (0..k * k).map(move |i| {
                let (x, y) = (208 + (i % k) * side, 208 + (i / k) * side);
                Rect::new(
                    x as i32,
                    y as i32,
                    side.min(208 + W - x),
                    side.min(208 + W - y),
                )
            })
        };
        let tiling: std::vec::Vec<Rect> = tiles(40).chain(tiles(48)).collect();
        let (mut far, mut fragments, mut differ, mut worst) = (0, 0u32, 0u32, 0.0f64);
        for _ in 0..600 {
            // A point of the window, and each vertex up to `reach` pixels
            // from it (within `|x|, |y| < 2^17` sub-pixels).
            let (cx, cy) = (
                16 * (208 + (next() % W as u64) as i32),
                16 * (208 + (next() % W as u64) as i32),
            );
            let v: [MeshVertex; 3] = core::array::from_fn(|_| {
                let reach = [64, 700, 4000, 7900][next() as usize % 4] * 16;
                let mut d = || (next() % (2 * reach as u64)) as i32 - reach;
                MeshVertex {
                    x: (cx + d()).clamp(-(1 << 17) + 1, (1 << 17) - 1),
                    y: (cy + d()).clamp(-(1 << 17) + 1, (1 << 17) - 1),
                    z: (next() % 60000) as u16,
                    rgb: [next() as u8, next() as u8, next() as u8],
                    code: 0,
                    spare: 0,
                }
            });
            let c = compare::<{ (W * W / 8) as usize }>(&v, whole, &tiling);
            let wide = [v[0].x, v[1].x, v[2].x].iter().max().unwrap()
                - [v[0].x, v[1].x, v[2].x].iter().min().unwrap()
                >= 1 << 14;
            far += (c.plane && wide && c.fragments > 0) as u32;
            fragments += c.fragments;
            differ += c.differ;
            worst = worst.max(c.worst);
        }
        {
            std::println!(
                "far triangles: {far} drawn under the plane contract with a side of 1024 px or \
                 more; {differ} colours of {fragments} fragments differ from the exact \
                 contract's; worst error {worst:.4} LSB"
            );
        }
        assert!(far > 150, "{far}");
        assert!(differ * 100 < fragments, "{differ} of {fragments} differ");
        assert!(worst > 0.4, "{worst}");
    }

    /// The Cortex-M0's stepped quotients equal a division every row, for
    /// random edges of triangles up to the validated extent and rows
    /// beyond them.
    #[test]
    fn stepped_edge_quotients_equal_division() {
        let mut next = xorshift(0x51ed_270b_3c9f_4a11);
        let mut c = |lim: i32| (next() % (2 * lim as u64)) as i32 - lim;
        for _ in 0..20_000 {
            let lim = [40, 400, 4000, 16000][(c(2) + 2) as usize % 4];
            let (p, q) = ((c(lim), c(lim)), (c(lim), c(lim)));
            let o = (c(lim) | 8, c(lim) | 8);
            let mut e = Edge::new(p, q, o, false);
            if e.a == 0 {
                continue;
            }
            e.start_steps();
            for row in 0..300 {
                assert_eq!(
                    e.q,
                    div_floor_i32(e.n, e.a.abs()),
                    "{p:?} {q:?} {o:?} row {row}"
                );
                e.n += e.s;
                e.step();
            }
        }
    }

    /// A row's run scanned equals the run found by division, for the
    /// edges of random triangles over random rows and box widths (the
    /// Cortex-M0 scans narrow boxes, every other core divides).
    #[test]
    fn scanned_runs_equal_divided_runs() {
        let mut next = xorshift(0x2545_f491_4f6c_dd1d);
        let mut c = |lim: i32| (next() % (2 * lim as u64)) as i32 - lim;
        let (mut covered, mut empty) = (0, 0);
        for _ in 0..20_000 {
            let lim = [24, 64, 160, 400][(c(2) + 2) as usize % 4];
            let p = [(c(lim), c(lim)), (c(lim), c(lim)), (c(lim), c(lim))];
            let o = (c(lim) | 8, c(lim) | 8);
            let width = 1 + (c(16) + 16).rem_euclid(32);
            let mut e = [
                Edge::new(p[1], p[2], o, false),
                Edge::new(p[2], p[0], o, false),
                Edge::new(p[0], p[1], o, false),
            ];
            for _ in 0..8 {
                let (lo, hi) = scan_run(&e, width);
                let (dlo, dhi) = divide_run(&e, width);
                if dlo < dhi {
                    covered += 1;
                    assert_eq!((lo, hi), (dlo, dhi), "{p:?} {o:?} {width}");
                } else {
                    empty += 1;
                    assert!(lo >= hi, "{p:?} {o:?} {width}: {lo}..{hi}");
                }
                for e in &mut e {
                    e.next(false);
                }
            }
        }
        assert!(covered > 5_000 && empty > 5_000, "{covered} {empty}");
    }

    /// The reciprocal's three 32-bit divisions equal one 64-bit division.
    #[test]
    fn reciprocal46_is_the_64_bit_quotient() {
        for a in (1..PLANE_AREA_LIMIT as u32)
            .step_by(7)
            .chain([1, 2, 3, 65535])
        {
            let want = ((1u64 << 46) - 1) / a as u64;
            assert_eq!(reciprocal46_by::<true>(a), want, "{a}");
            assert_eq!(reciprocal46_by::<false>(a), want, "{a}");
        }
    }
}
