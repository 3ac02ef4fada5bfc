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
//! A triangle outside the contract's domain returns `false` before any
//! pixel is drawn, and the caller draws it under the exact contract.

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
        let mut e = Edge {
            a: -dy << SUBPIXEL_BITS,
            n: dx * (oy - p.1) - dy * (ox - p.0) - (!top_left) as i32,
            s: dx << SUBPIXEL_BITS,
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
        // `|k| < 2 area2` and `r < 2^62 / area2`: `|k r| < 2^63`.
        let r = (((1u64 << 62) - 1) / area2 as u64) as i64;
        let w = |k: i32| ((k as i64 * r + (1 << 31)) >> 32) as i32;
        let rc = Recip {
            wx: (w(a.0), w(a.1)),
            wy: (w(s.0), w(s.1)),
            bits: W_BITS,
            o,
        };
        rc.conditioned(extent).then_some(rc)
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
        // (`dot2_wide`: on the Cortex-M0 32-bit products of 16-bit halves,
        // not the general 64x64-bit library multiply.)
        let g = |w: (i32, i32)| (dot2_wide(d1, w.0, d2, w.1) + (1 << (bits - 1))) >> bits;
        let (gx, gy) = (g(self.wx), g(self.wy));
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
            *p = if bits == W_BITS {
                rc.plane::<true>(bits, c0, d1, d2)
            } else {
                rc.plane::<false>(bits, c0, d1, d2)
            };
        }
        let zl = |k: usize| (v[k].z as i32) << Z_FRAC;
        let zp = rc.plane::<false>(bits, zl(0), zl(1) - zl(0), zl(2) - zl(0));
        (cp, zp)
    }

    /// [`Self::planes`] of a sliver (fewer fraction bits, a shift by a
    /// variable), out of line.
    #[inline(never)]
    #[cold]
    fn sliver_planes(rc: &Recip, v: [&MeshVertex; 3]) -> ([Plane; 4], Plane) {
        Self::planes(rc, rc.bits, v)
    }

    /// Draws the opaque Gouraud triangle `v` under the plane contract
    /// ([module docs](self)); `false`, with nothing drawn, when the
    /// triangle lies outside the contract's domain. Vertex coordinates lie
    /// in the validated domain (`|x|, |y| < 2^17` sub-pixels).
    #[inline(never)]
    pub(crate) fn plane_triangle(&mut self, v: [&MeshVertex; 3], st: &State) -> bool {
        let (x0, x1) = (
            v[0].x.min(v[1].x).min(v[2].x),
            v[0].x.max(v[1].x).max(v[2].x),
        );
        let (y0, y1) = (
            v[0].y.min(v[1].y).min(v[2].y),
            v[0].y.max(v[1].y).max(v[2].y),
        );
        if (x1 - x0) as i64 >= SMALL_EXTENT || (y1 - y0) as i64 >= SMALL_EXTENT {
            return false;
        }
        // The triangle's pixel box (its anchor is the top-left), then
        // clipped to the tile.
        let (bx0, bx1) = pixel_span(x0, x1);
        let (by0, by1) = pixel_span(y0, y1);
        let t = self.area;
        let (cx0, cx1) = (bx0.max(t.x), bx1.min(t.x + t.w as i32 - 1));
        let (cy0, cy1) = (by0.max(t.y), by1.min(t.y + t.h as i32 - 1));
        if cx0 > cx1 || cy0 > cy1 {
            return true;
        }
        // Orientation: the inside is where every edge is `>= bias`.
        let (p0, mut p1, mut p2) = ((v[0].x, v[0].y), (v[1].x, v[1].y), (v[2].x, v[2].y));
        let (mut i1, mut i2) = (1, 2);
        let mut area2 = (p1.0 - p0.0) * (p2.1 - p0.1) - (p1.1 - p0.1) * (p2.0 - p0.0);
        if area2 == 0 {
            return true;
        }
        if area2 < 0 {
            core::mem::swap(&mut p1, &mut p2);
            (i1, i2) = (2, 1);
            area2 = -area2;
        }
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
        let mut py = cy0;
        // Rows above the first covered one: edges only.
        let (mut lo, mut hi);
        loop {
            (lo, hi) = row_run(&e, width);
            if lo < hi {
                break;
            }
            if py == cy1 {
                return true;
            }
            py += 1;
            for e in &mut e {
                e.next(stepped);
            }
        }
        // The first covered row: the attribute planes.
        let o = (
            (bx0 << SUBPIXEL_BITS) + half - p0.0,
            (by0 << SUBPIXEL_BITS) + half - p0.1,
        );
        let extent = ((bx1 - bx0) + (by1 - by0) + 2) as u32;
        let Some(rc) = Recip::new(area2, (e[1].a, e[2].a), (e[1].s, e[2].s), o, extent) else {
            return false;
        };
        let ends = [v[0], v[i1], v[i2]];
        let (cp, zp) = if rc.bits == W_BITS {
            Self::planes(&rc, W_BITS, ends)
        } else {
            Self::sliver_planes(&rc, ends)
        };
        let dc = <C::Format as PixelFormat>::Lanes::from_fn(|i| cp[i].gx);
        loop {
            if lo < hi {
                let (i, j) = (cx0 + lo - bx0, py - by0);
                let at = |p: &Plane| {
                    p.c.wrapping_add(j.wrapping_mul(p.gy))
                        .wrapping_add(i.wrapping_mul(p.gx))
                };
                let s = SpanStart {
                    c: <C::Format as PixelFormat>::Lanes::from_fn(|k| at(&cp[k])),
                    dc,
                    z: at(&zp),
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
                return true;
            }
            py += 1;
            for e in &mut e {
                e.next(stepped);
            }
            (lo, hi) = row_run(&e, width);
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

    /// Under the plane contract: the same pixels as the exact contract's
    /// traversal, every colour within 0.5 + 2^-4 of the exact rational
    /// value (to nearest, no dither) and every depth within 0.5 + 2^-4 —
    /// the bound the contract documents — and the same output in 4
    /// tiles as in one; triangles outside its domain are drawn exactly.
    #[test]
    fn plane_contract_covers_exactly_within_its_bound() {
        let mut next = xorshift(0x9e37_79b9_7f4a_7c15);
        let whole = Rect::new(0, 0, SIDE, SIDE);
        let (mut fast_tris, mut exact_tris, mut fragments, mut differ) = (0, 0, 0u32, 0u32);
        let (mut zdiffer, mut slivers, mut large) = (0u32, 0u32, 0u32);
        let mut worst = 0.0f64;
        for _ in 0..3000 {
            let v = triangle(&mut next);
            let st = State::default();
            let mut exact: Tile<CAP, Exact> = Tile::new();
            exact.begin(whole, &Clear::default()).unwrap();
            exact
                .draw(&Command::Triangle {
                    v: vertices(&v),
                    state: st,
                })
                .ok();
            let mut fast: Tile<CAP, Fast> = Tile::new();
            fast.begin(whole, &Clear::default()).unwrap();
            let in_domain = fast.plane_triangle([&v[0], &v[1], &v[2]], &st);
            slivers += (in_domain && is_sliver(&v)) as u32;
            large += (in_domain && area2(&v) >= PLANE_AREA_LIMIT) as u32;
            if !in_domain {
                exact_tris += 1;
                fast.draw(&Command::Triangle {
                    v: vertices(&v),
                    state: st,
                })
                .ok();
            } else {
                fast_tris += 1;
            }
            // Tiling invariance: four quarter tiles.
            let h = SIDE / 2;
            for (tx, ty) in [(0, 0), (h, 0), (0, h), (h, h)] {
                let mut q: Tile<CAP, Fast> = Tile::new();
                q.begin(Rect::new(tx as i32, ty as i32, h, h), &Clear::default())
                    .unwrap();
                q.draw(&Command::Triangle {
                    v: vertices(&v),
                    state: st,
                })
                .ok();
                for y in ty as i32..(ty + h) as i32 {
                    for x in tx as i32..(tx + h) as i32 {
                        assert_eq!(q.raw(x, y), fast.raw(x, y), "tiling {v:?} at {x},{y}");
                        assert_eq!(q.depth(x, y), fast.depth(x, y), "tiling {v:?}");
                    }
                }
            }
            for y in 0..SIDE as i32 {
                for x in 0..SIDE as i32 {
                    let covered = exact.depth(x, y) != Some(u16::MAX);
                    assert_eq!(
                        covered,
                        fast.depth(x, y) != Some(u16::MAX),
                        "coverage {v:?} at {x},{y}"
                    );
                    if !covered {
                        continue;
                    }
                    fragments += 1;
                    differ += (exact.raw(x, y) != fast.raw(x, y)) as u32;
                    zdiffer += (exact.depth(x, y) != fast.depth(x, y)) as u32;
                    if !in_domain {
                        assert_eq!(exact.raw(x, y), fast.raw(x, y));
                        continue;
                    }
                    let (c, z) = reference(&v, x, y);
                    let raw = fast.raw(x, y).unwrap();
                    for (k, c) in c.iter().enumerate() {
                        let out = (raw >> (16 - 8 * k)) & 0xff;
                        let e = abs(out as f64 - c);
                        worst = worst.max(e);
                        assert!(
                            e <= 0.5 + 1.0 / 16.0,
                            "colour {v:?} at {x},{y}: {out} vs {c}"
                        );
                    }
                    let dz = abs(fast.depth(x, y).unwrap() as f64 - z);
                    assert!(dz <= 0.5 + 1.0 / 16.0, "depth {v:?} at {x},{y}: {dz}");
                }
            }
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
        // Most triangles are in the domain; some fragments differ by
        // rounding, few.
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
