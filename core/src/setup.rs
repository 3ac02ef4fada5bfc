//! Triangle setup (pipeline stage 2): vertices to exact integer edge
//! functions and attribute planes (the RE's triangle input, seed 001 §IV.1).
//!
//! **Edge functions.** For the edge from `a` to `b` (sub-pixel units),
//! `E(p) = (b.x - a.x)(p.y - a.y) - (b.y - a.y)(p.x - a.x)`, evaluated at
//! pixel centres `p = (16 px + 8, 16 py + 8)`. Per pixel this is
//! `E = A px + B(py)` with `A = -16 dy`, `B(py + 1) = B(py) + 16 dx`: exact
//! `i64` integers (inputs below 2^18, products below 2^37).
//! After orienting the triangle so that its doubled area `area2 > 0`, a pixel
//! is inside when every `E >= 0`; on an edge (`E == 0`) it belongs to the
//! triangle only if the edge is a *top* edge (`dy == 0, dx > 0`) or a *left*
//! edge (`dy < 0`) — the top-left rule, applied as a bias of 1.
//!
//! **Attribute planes.** With `E_i` the edge opposite vertex `i`,
//! `E_0 + E_1 + E_2 = area2` everywhere, and the barycentric weights are
//! `w_i = E_i / area2`. An attribute is `A = a0 + (a1 - a0) w1 + (a2 - a0) w2`,
//! so its steps are `dA/dx = ((a1 - a0) A_1 + (a2 - a0) A_2) / area2` per
//! pixel and the same with the rows' steps per row, each rounded to nearest.
//! The divisions share one reciprocal of `area2` ([`Divisor`]): a high
//! product and one correction each, the exact rounded quotient.
//!
//! Small triangles (`i32`, every triangle of a small display) then step
//! from an anchor pixel: no division and no 64-bit product per row
//! (incremental stepping, the DDA in two directions). Large ones keep
//! `floor(2^62 / area2)` and restart each span from the weights: two
//! multiplies per lane (inside the triangle `0 <= E_i <= area2`, so
//! `E_i * inv <= 2^62` cannot overflow). The error bounds of both are in
//! [`crate::numeric`].

use crate::format::{Lanes, PixelFormat};
use crate::geom::Rect;
use crate::geom::{QuadVertex, SubBox, Vertex};
use crate::numeric::{
    dot2_i16, pairs, wide_mul, wide_mul_i, wrapping_mul_i32, Divisor, LONG_MUL, SUBPIXEL,
    SUBPIXEL_BITS, W_FRAC, Z_FRAC,
};

/// One edge as a function of pixel indices: `E(px, py) = a px + b0 + step py`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Edge {
    /// Change per pixel in x: `-16 dy`.
    pub a: i64,
    /// Value at pixel (0, 0).
    pub b0: i64,
    /// Change per row: `16 dx`.
    pub step: i64,
    /// 0 for top-left edges, 1 otherwise: inside means `E - bias >= 0`.
    pub bias: i64,
}

impl Edge {
    fn new(p: (i64, i64), q: (i64, i64)) -> Edge {
        let (dx, dy) = (q.0 - p.0, q.1 - p.1);
        let half = SUBPIXEL / 2;
        let top_left = dy < 0 || (dy == 0 && dx > 0);
        Edge {
            a: -SUBPIXEL * dy,
            b0: dx * (half - p.1) + dy * (p.0 - half),
            step: SUBPIXEL * dx,
            bias: (!top_left) as i64,
        }
    }

    /// The unbiased value at the start of row `py`.
    #[inline]
    pub fn row(&self, py: i64) -> i64 {
        self.b0 + self.step * py
    }
}

/// The integer a triangle's edge functions are evaluated in: `i32` when
/// the triangle's box is under [`SMALL_EXTENT`] sub-pixels on both axes
/// (every triangle of a small display), `i64` otherwise. Both give exactly
/// the same values; `i32` divides with one instruction on the Cortex-M4 and
/// without a 64-bit library call on the Cortex-M0.
pub(crate) trait EdgeInt:
    Copy
    + Ord
    + core::fmt::Debug
    + core::ops::Add<Output = Self>
    + core::ops::Sub<Output = Self>
    + core::ops::Mul<Output = Self>
    + core::ops::Neg<Output = Self>
    + core::ops::AddAssign
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// `v`, which the caller knows to fit.
    fn from_i64(v: i64) -> Self;
    /// Widened.
    fn to_i64(self) -> i64;
    /// Floor division for `d > 0`.
    fn div_floor(self, d: Self) -> Self;
    /// Whether triangles set up in this type restart each row exactly from
    /// the plane equation (large triangles, `i64`) rather than stepping
    /// from the anchor (`i32`): see [`TriangleSetup`].
    const EXACT_ROWS: bool;
}

macro_rules! edge_int {
    ($($t:ty: $exact:expr, $div_floor:expr),*) => {$(
        impl EdgeInt for $t {
            const ZERO: Self = 0;
            const ONE: Self = 1;
            const EXACT_ROWS: bool = $exact;
            #[inline(always)]
            fn from_i64(v: i64) -> Self {
                v as $t
            }
            #[inline(always)]
            fn to_i64(self) -> i64 {
                self as i64
            }
            #[inline(always)]
            fn div_floor(self, d: Self) -> Self {
                $div_floor(self, d)
            }
        }
    )*};
}
edge_int!(
    i32: false, crate::numeric::div_floor_i32,
    i64: true, |n: i64, d: i64| {
        let q = n / d;
        if n % d < 0 { q - 1 } else { q }
    }
);

/// Largest box side, in sub-pixels, of a triangle set up in `i32`: sides
/// and offsets below 2^14 + 2^5 keep each product below 2^29 and every edge
/// value below 2^30.
pub(crate) const SMALL_EXTENT: i64 = 1 << 14;

/// One edge relative to the anchor pixel `(ax, ay)` (the top-left pixel of
/// the triangle's box): `E(px, py) = a (px - ax) + b + step (py - ay)`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct EdgeAt<T> {
    /// Change per pixel in x: `-16 dy`.
    pub a: T,
    /// Value at the anchor pixel's centre.
    pub b: T,
    /// Change per row: `16 dx`.
    pub step: T,
    /// 0 for top-left edges, 1 otherwise.
    pub bias: T,
}

/// A triangle ready for traversal: edges, pixel bounds and attribute planes.
///
/// **Small triangles** (`T = i32`, box under 1024 px a side: every triangle
/// of a small display) carry each attribute as a plane anchored at the
/// top-left pixel of their box ([`Attrs`], in `p`): its value there (`c`,
/// `z`) and its steps per pixel in x (`gc`, `gz`) and per row in y (`gcy`,
/// `gzy`). The value at
/// pixel `(ax + i, ay + j)` is `c + i gc + j gcy`, in `i32` arithmetic
/// modulo 2^32: no division and no 64-bit product per row, and the same
/// value whichever tile asks, so tiling cannot change the output. The
/// anchor lies outside most triangles and the steps of a sliver can exceed
/// `i32`: only the values at pixels inside the triangle fit, and modular
/// arithmetic gets those exactly.
///
/// **Large triangles** (`T = i64`) restart each row from the exact plane
/// equation ([`Self::start`]), so the drift stays within one span.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TriangleSetup<L: Lanes, T> {
    /// `e[i]` is the edge opposite vertex `i`, relative to the anchor.
    pub e: [EdgeAt<T>; 3],
    /// Pixels whose centres can be inside; the anchor is its top-left.
    pub bounds: Rect,
    /// Twice the triangle's area, sub-pixels squared (`> 0`).
    pub area2: i64,
    /// Whether vertices 1 and 2 were swapped to orient the triangle: edge
    /// `e[1]` is then opposite vertex 2, `e[2]` opposite vertex 1.
    pub swapped: bool,
    /// The attribute planes ([`Attrs`]).
    pub p: Attrs<L>,
}

/// A triangle's attribute planes: what [`TriangleSetup::planes`] adds
/// to its edges.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Attrs<L: Lanes> {
    /// Colour at the anchor pixel (output scale, 16 fraction bits, modulo
    /// 2^32; small triangles only).
    pub c: L,
    /// Z at the anchor pixel (16.14, modulo 2^32; small triangles only).
    pub z: i32,
    /// Colour step per pixel in x (output scale, 16 fraction bits).
    pub gc: L,
    /// Z step per pixel in x (16.14).
    pub gz: i32,
    /// Colour step per row (small triangles only).
    pub gcy: L,
    /// Z step per row (small triangles only).
    pub gzy: i32,
    /// Blend-weight plane of a translucent triangle (zero for an opaque
    /// one): value at the anchor, steps in x and y, as for `c`. The weight is
    /// `256 α / 255` in 1/256 with 16 fraction bits ([`alpha_weight`]).
    pub alpha: [i32; 3],
    inv: i64,
    c0: L,
    dc: [L; 2],
    z0: i32,
    dz: [i32; 2],
    a0: i32,
    da: [i32; 2],
}

/// A vertex's opacity as a blend weight in 1/256 with 16 fraction bits:
/// `round(256 α / 255 · 2^16) = 65793 α + round(α / 255)`, so `α = 255`
/// weighs exactly `2^24` (replace) and `α = 0` nothing. No division
/// (checked against the division for every `α` in this module's tests).
#[inline(always)]
pub(crate) const fn alpha_weight(alpha: u8) -> i32 {
    alpha as i32 * 65793 + (alpha >> 7) as i32
}

fn sub(v: &Vertex) -> (i64, i64) {
    (v.x.to_bits() as i64, v.y.to_bits() as i64)
}

/// The edges of a triangle oriented so that the inside is `E >= bias`
/// (`e[i]` opposite vertex `i`), its doubled area and whether the second and
/// third vertices were swapped to get there; `None` for zero area.
pub(crate) fn oriented_edges(v: &[Vertex; 3]) -> Option<([Edge; 3], i64, bool)> {
    let (p0, mut p1, mut p2) = (sub(&v[0]), sub(&v[1]), sub(&v[2]));
    let mut area2 = (p1.0 - p0.0) * (p2.1 - p0.1) - (p1.1 - p0.1) * (p2.0 - p0.0);
    if area2 == 0 {
        return None;
    }
    let swapped = area2 < 0;
    if swapped {
        core::mem::swap(&mut p1, &mut p2);
        area2 = -area2;
    }
    Some((
        [Edge::new(p1, p2), Edge::new(p2, p0), Edge::new(p0, p1)],
        area2,
        swapped,
    ))
}

/// Whether a triangle's edge functions fit `i32` ([`SMALL_EXTENT`]).
#[inline]
pub(crate) fn fits_i32(v: &[Vertex; 3]) -> bool {
    fits_box(&SubBox::of(v))
}

/// [`fits_i32`] of the triangle whose box is `b`.
#[inline(always)]
pub(crate) fn fits_box(b: &SubBox) -> bool {
    let ext = |lo: i32, hi: i32| (hi as i64 - lo as i64) < SMALL_EXTENT;
    ext(b.lo.0, b.hi.0) && ext(b.lo.1, b.hi.1)
}

impl<L: Lanes, T: EdgeInt> TriangleSetup<L, T> {
    /// Sets up a validated triangle; `None` when it has zero area or covers
    /// no pixel centre. With `T = i32` the caller has checked [`fits_i32`].
    ///
    /// With `alpha` (a translucent command) it also sets up the blend-weight
    /// plane from the vertices' opacities, like one more colour channel.
    #[inline(always)]
    pub fn new<F: PixelFormat<Lanes = L>>(v: &[Vertex; 3], alpha: bool) -> Option<Self> {
        Self::new_in::<F>(v, &SubBox::of(v), alpha)
    }

    /// [`Self::new`] of a triangle whose box `b` the caller has made (and
    /// checked with [`fits_box`] for `T = i32`): [`Self::edges_in`], then
    /// [`Self::planes`].
    ///
    /// On soft-float ARM targets (the Cortex-M0, whose flash is the
    /// scarcest) it stays out of line: one copy per pixel format and
    /// integer, shared by every tile configuration. Elsewhere it is inlined
    /// into the draw loop, which saves 3% of a teapot frame on the
    /// Cortex-M4 (measured). Inlining cannot change a result.
    #[cfg_attr(target_abi = "eabi", inline(never))]
    #[cfg_attr(not(target_abi = "eabi"), inline(always))]
    pub(crate) fn new_in<F: PixelFormat<Lanes = L>>(
        v: &[Vertex; 3],
        b: &SubBox,
        alpha: bool,
    ) -> Option<Self> {
        let mut t = Self::edges_in(v, b)?;
        t.p = t.planes::<F>(v, alpha);
        Some(t)
    }

    /// The first half of the setup: the oriented edges, the pixel bounds
    /// and the doubled area; the attribute planes are zero until
    /// [`Self::planes`]. `None` when the triangle has zero area or
    /// its box holds no pixel centre. A caller that traverses first sets
    /// the planes up only for a triangle that covers a pixel of its tile
    /// (a Gouraud draw): a sixth of a teapot frame's (triangle, tile) pairs
    /// cover none, a quarter of the demo's (counted on the host), and a
    /// triangle's planes cost about 390 instructions on the Cortex-M4.
    #[inline(always)]
    pub(crate) fn edges_in(v: &[Vertex; 3], b: &SubBox) -> Option<Self> {
        let bounds = b.pixels()?;
        let (p0, mut p1, mut p2) = (sub(&v[0]), sub(&v[1]), sub(&v[2]));
        let area = |p0: (i64, i64), p1: (i64, i64), p2: (i64, i64)| {
            let d = |a: i64, b: i64| T::from_i64(a - b);
            d(p1.0, p0.0) * d(p2.1, p0.1) - d(p1.1, p0.1) * d(p2.0, p0.0)
        };
        let mut area2 = area(p0, p1, p2);
        if area2 == T::ZERO {
            return None;
        }
        let swapped = area2 < T::ZERO;
        if swapped {
            core::mem::swap(&mut p1, &mut p2);
            area2 = -area2;
        }
        let anchor = anchor(&bounds);
        let edge = |p: (i64, i64), q: (i64, i64)| {
            let d = |a: i64, b: i64| T::from_i64(a - b);
            let (dx, dy) = (d(q.0, p.0), d(q.1, p.1));
            let top_left = dy < T::ZERO || (dy == T::ZERO && dx > T::ZERO);
            let s = T::from_i64(SUBPIXEL);
            EdgeAt {
                a: -(s * dy),
                b: dx * d(anchor.1, p.1) - dy * d(anchor.0, p.0),
                step: s * dx,
                bias: if top_left { T::ZERO } else { T::ONE },
            }
        };
        let e = [edge(p1, p2), edge(p2, p0), edge(p0, p1)];
        Some(TriangleSetup {
            e,
            bounds,
            area2: area2.to_i64(),
            swapped,
            p: Attrs::zero(),
        })
    }

    /// The second half of the setup: the attribute planes of the triangle
    /// [`Self::edges_in`] made from the same vertices `v` (with `alpha`,
    /// a translucent command, the blend-weight plane too, like one more
    /// colour channel), for the caller to store in [`Self::p`] (the edges
    /// may be borrowed meanwhile: traversal has started).
    #[inline(always)]
    pub(crate) fn planes<F: PixelFormat<Lanes = L>>(
        &self,
        v: &[Vertex; 3],
        alpha: bool,
    ) -> Attrs<L> {
        let (e, area2) = (&self.e, self.area2);
        let p0 = sub(&v[0]);
        let anchor = anchor(&self.bounds);
        let (v1, v2) = if self.swapped {
            (&v[2], &v[1])
        } else {
            (&v[1], &v[2])
        };
        let lanes = |v: &Vertex| {
            let c = v.color;
            F::lanes_from_rgb8([c.r, c.g, c.b])
        };
        let (c0, c1, c2) = (lanes(&v[0]), lanes(v1), lanes(v2));
        let dc = [c1.zip(c0, |a, b| a - b), c2.zip(c0, |a, b| a - b)];
        let zf = |v: &Vertex| (v.z as i32) << Z_FRAC;
        let z0 = zf(&v[0]);
        let dz = [zf(v1) - z0, zf(v2) - z0];
        // Steps per pixel (x) and per row (y): dA/dx = (d1 a1 + d2 a2) /
        // area2, dA/dy likewise with the rows' steps, rounded to nearest.
        // |d| <= 2^30 and |a|, |step| < 2^22 keep the sums below 2^53. A
        // step that does not fit `i32` wraps: it belongs to a sliver, and
        // only the values inside the triangle, which fit, are ever used.
        let (a1, a2) = (e[1].a.to_i64(), e[2].a.to_i64());
        let (s1, s2) = (e[1].step.to_i64(), e[2].step.to_i64());
        let planes = Planes {
            area: Divisor::new(area2),
            a: (a1, a2),
            s: (s1, s2),
            // The anchor's offset from vertex 0, in sub-pixels.
            o: (anchor.0 - p0.0, anchor.1 - p0.1),
        };
        let plane = |a0: i32, d0: i32, d1: i32| planes.plane::<T>(a0, d0, d1);
        let mut lanes = [(0, 0, 0); 4];
        for (i, p) in lanes.iter_mut().enumerate().take(L::LEN) {
            *p = plane(c0.lane(i), dc[0].lane(i), dc[1].lane(i));
        }
        let (z, gz, gzy) = plane(z0, dz[0], dz[1]);
        let (a0, da, alpha) = if alpha {
            let a0 = alpha_weight(v[0].alpha);
            let da = [alpha_weight(v1.alpha) - a0, alpha_weight(v2.alpha) - a0];
            let (a, ga, gay) = plane(a0, da[0], da[1]);
            (a0, da, [a, ga, gay])
        } else {
            (0, [0; 2], [0; 3])
        };
        Attrs {
            c: L::from_fn(|i| lanes[i].0),
            z,
            gc: L::from_fn(|i| lanes[i].1),
            gz,
            gcy: L::from_fn(|i| lanes[i].2),
            gzy,
            alpha,
            inv: if T::EXACT_ROWS {
                (1i64 << 62) / area2
            } else {
                0
            },
            c0,
            dc,
            z0,
            dz,
            a0,
            da,
        }
    }

    /// Colour and Z at a pixel inside the triangle, from the unbiased edge
    /// values `e1`, `e2` there (`0 <= e_i <= area2`). Error below 2^-11 LSB.
    #[inline]
    pub fn start(&self, e1: i64, e2: i64) -> (L, i32) {
        let (w1, w2) = self.weights(e1, e2);
        let c = L::from_fn(|i| {
            lerp(
                self.p.c0.lane(i),
                self.p.dc[0].lane(i),
                self.p.dc[1].lane(i),
                w1,
                w2,
            )
        });
        (c, lerp(self.p.z0, self.p.dz[0], self.p.dz[1], w1, w2))
    }

    /// The blend weight at the same pixel as [`Self::start`], same error.
    #[inline]
    pub fn alpha_start(&self, e1: i64, e2: i64) -> i32 {
        let (w1, w2) = self.weights(e1, e2);
        lerp(self.p.a0, self.p.da[0], self.p.da[1], w1, w2)
    }

    /// Barycentric weights `w1, w2` with [`W_FRAC`] fraction bits.
    #[inline(always)]
    fn weights(&self, e1: i64, e2: i64) -> (i64, i64) {
        (
            (e1 * self.p.inv) >> (62 - W_FRAC),
            (e2 * self.p.inv) >> (62 - W_FRAC),
        )
    }
}

/// The centre of the anchor pixel (the top-left of `bounds`), in
/// sub-pixels.
#[inline(always)]
fn anchor(bounds: &Rect) -> (i64, i64) {
    let half = SUBPIXEL / 2;
    (
        SUBPIXEL * bounds.x as i64 + half,
        SUBPIXEL * bounds.y as i64 + half,
    )
}

impl<L: Lanes> Attrs<L> {
    /// No planes yet ([`TriangleSetup::edges_in`]).
    #[inline(always)]
    fn zero() -> Self {
        let zero = L::from_fn(|_| 0);
        Attrs {
            c: zero,
            z: 0,
            gc: zero,
            gz: 0,
            gcy: zero,
            gzy: 0,
            alpha: [0; 3],
            inv: 0,
            c0: zero,
            dc: [zero; 2],
            z0: 0,
            dz: [0; 2],
            a0: 0,
            da: [0; 2],
        }
    }
}

/// What a triangle's attribute planes share: the divisor `area2` and the
/// edges' steps `A_1, A_2` per pixel (`a`) and per row (`s`), and the
/// anchor's offset `o` from vertex 0 in sub-pixels.
struct Planes {
    area: Divisor,
    a: (i64, i64),
    s: (i64, i64),
    o: (i64, i64),
}

impl Planes {
    /// `round((d0 k1 + d1 k2) / area2)`: an attribute's step along the
    /// edges' steps `k`. `|k| < 2^23` (validated coordinates): 32x32-bit
    /// products.
    ///
    /// A small triangle's steps (`T = i32`) are multiples of 16 below 2^18
    /// ([`SMALL_EXTENT`] times [`SUBPIXEL`]): their sixteenths fit 15 bits,
    /// the Cortex-M0's cheap products ([`dot2_i16`]).
    #[inline(always)]
    fn grad<T: EdgeInt>(&self, d0: i32, d1: i32, (k1, k2): (i64, i64)) -> i64 {
        debug_assert!(k1 == k1 as i32 as i64 && k2 == k2 as i32 as i64);
        let n = if T::EXACT_ROWS || LONG_MUL {
            wide_mul_i(d0, k1 as i32) + wide_mul_i(d1, k2 as i32)
        } else {
            debug_assert!(k1 % SUBPIXEL == 0 && k2 % SUBPIXEL == 0);
            let (k1, k2) = ((k1 >> SUBPIXEL_BITS) as i32, (k2 >> SUBPIXEL_BITS) as i32);
            dot2_i16(d0, k1, d1, k2) << SUBPIXEL_BITS
        };
        self.area.round(n)
    }

    /// (value at the anchor, step in x, step in y) of the attribute worth
    /// `a0` at vertex 0 and `a0 + d0`, `a0 + d1` at the others. Inlined
    /// where flash is plenty (the Cortex-M4: four or five calls per
    /// triangle and tile, each paying a frame and the captured values'
    /// loads); one copy on the Cortex-M0.
    #[cfg_attr(target_abi = "eabi", inline(never))]
    #[cfg_attr(not(target_abi = "eabi"), inline(always))]
    fn plane<T: EdgeInt>(&self, a0: i32, d0: i32, d1: i32) -> (i32, i32, i32) {
        let gx = self.grad::<T>(d0, d1, self.a);
        if T::EXACT_ROWS {
            return (a0, gx as i32, 0);
        }
        let gy = self.grad::<T>(d0, d1, self.s);
        // The anchor's value from vertex 0's through the rounded steps:
        // wrapping `i64` products and an arithmetic shift give it exactly
        // modulo 2^32, which is all the `i32` DDA keeps. `|ox|, |oy| <
        // 2^15`: within the triangle's box.
        let (ox, oy) = self.o;
        let off = wrapping_mul_i32(gx, ox as i32).wrapping_add(wrapping_mul_i32(gy, oy as i32));
        let off = off.wrapping_add(SUBPIXEL / 2) >> SUBPIXEL_BITS;
        (a0.wrapping_add(off as i32), gx as i32, gy as i32)
    }
}

/// `a0 + d1 w1 + d2 w2`, the weights with [`W_FRAC`] fraction bits,
/// rounded to nearest.
#[inline(always)]
fn lerp(a0: i32, d1: i32, d2: i32, w1: i64, w2: i64) -> i32 {
    let half = 1i64 << (W_FRAC - 1);
    a0 + ((d1 as i64 * w1 + d2 as i64 * w2 + half) >> W_FRAC) as i32
}

/// Budgets of a quadratic triangle's setup: `κ² (|M| + 16)` up to
/// `SLIVER.0` is set up in `f32`, up to `SLIVER.1` in `f64` (software
/// double precision on a Cortex-M: thousands of instructions, for the few
/// thin triangles that need it), beyond that the triangle is Gouraud-shaded
/// (a *sliver*: its box dwarfs it by `2^20` or more).
///
/// `κ`, the conditioning, is the largest change of a barycentric weight
/// across the triangle's box along x plus along y, `(|dy| bw + |dx| bh) /
/// area2` over its edges (sub-pixel units, `bw`, `bh` the vertices' extent
/// plus one pixel: the expansion's origin lies within a pixel of that box)
/// — about 2 for a well-shaped triangle, large for a thin slanted one,
/// whose `X_k i` and `Y_k j` terms grow and cancel. `|M|` is the largest
/// curvature term `|2 mid - c_p - c_q|` (8-bit units) over the channels
/// and edges. The coefficients' relative rounding (2^-24 in `f32`, 2^-53
/// in `f64`) reaches a pixel amplified about `6 |M| κ²` times (the linear
/// part `16 κ` at most), so each budget keeps the setup's error near
/// `6 · 2^-8` = 0.023 LSB. In `f32`: `κ` up to 11 for the strongest
/// curvature (510), up to 64 for a flat one — most triangles, silhouettes
/// seen edge-on included; long thin ones (a sphere's polar fans) take `f64`.
pub(crate) const SLIVER: (u128, u128) = (1 << 16, 1 << 45);

/// How the quadratic triangle `v` is set up ([`SLIVER`]): `Some(false)` in
/// `f32`, `Some(true)` in `f64`, `None` drawn Gouraud-shaded. Exact
/// integers (coordinates below 2^18 sub-pixels: `κ`'s numerator below
/// 2^37, its square times `|M| + 16` below 2^84, `area2² 2^45` below 2^118).
pub(crate) fn setup_precision(v: &[QuadVertex; 3]) -> Option<bool> {
    let p = v.map(|v| (v.x.to_bits() as i64, v.y.to_bits() as i64));
    let ext = |f: fn(&(i64, i64)) -> i64| {
        let (lo, hi) = (p.iter().map(f).min(), p.iter().map(f).max());
        // The expansion's origin and the rows' anchor lie within a pixel
        // of the vertices' box.
        hi.unwrap_or(0) - lo.unwrap_or(0) + SUBPIXEL
    };
    let (bw, bh) = (ext(|p| p.0), ext(|p| p.1));
    let area2 = ((p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[1].1 - p[0].1) * (p[2].0 - p[0].0))
        .unsigned_abs() as u128;
    let mut curv = 0u128;
    for k in 0..3 {
        let (a, b) = (v[k].color, v[(k + 1) % 3].color);
        let m = v[k].mid;
        for (c, d, mid) in [(a.r, b.r, m.r), (a.g, b.g, m.g), (a.b, b.b, m.b)] {
            let t = (2 * mid as i32 - c as i32 - d as i32).unsigned_abs() as u128;
            curv = curv.max(t);
        }
    }
    let mut worst = 0u128;
    for k in 0..3 {
        let (a, b) = (p[k], p[(k + 1) % 3]);
        let num = ((b.1 - a.1).unsigned_abs() * bw as u64 + (b.0 - a.0).unsigned_abs() * bh as u64)
            as u128;
        worst = worst.max(num * num * (curv + 16));
    }
    let a2 = area2 * area2;
    if worst <= SLIVER.0 * a2 {
        Some(false)
    } else if worst <= SLIVER.1 * a2 {
        Some(true)
    } else {
        None
    }
}

/// The floating-point type a [`QuadPlane`] is set up in: `f32` (hardware
/// on a Cortex-M4F) or `f64` for ill-conditioned triangles. IEEE
/// arithmetic in a fixed order: every target computes the same bits.
trait SetupFloat:
    Copy + core::ops::Add<Output = Self> + core::ops::Mul<Output = Self> + core::ops::AddAssign
{
    const ZERO: Self;
    fn of(v: i64) -> Self;
    /// `1 / v`.
    fn recip(v: i64) -> Self;
    /// `self * 2^16`, truncated towards zero.
    fn fixed16(self) -> i64;
}

/// `f32` setup: conversions from and to `i64` without the library's
/// routines where the result is the same. Measured with `qemu-prof` on the
/// large fast-Phong workload (Cortex-M4F): `__aeabi_l2f` and
/// `__aeabi_f2lz` were 7,700 of its 211,000 instructions, and the
/// workload fell to 200,800 without them (49.0 instr/px in
/// `reports/targets.md`).
impl SetupFloat for f32 {
    const ZERO: Self = 0.0;
    #[inline(always)]
    fn of(v: i64) -> Self {
        // Both conversions round the same integer to nearest: an `i32`
        // is one `vcvt` on an FPU, an `i64` a library call (kept out of
        // line: inline, the compiler folds the two arms back into it).
        match i32::try_from(v) {
            Ok(v) => v as f32,
            Err(_) => i64_to_f32(v),
        }
    }
    fn recip(v: i64) -> Self {
        1.0 / Self::of(v)
    }
    #[inline(always)]
    fn fixed16(self) -> i64 {
        f32_to_i64(self * 65536.0)
    }
}

#[inline(never)]
fn i64_to_f32(v: i64) -> f32 {
    v as f32
}

/// `x as i64` (truncation towards zero, saturating, NaN to 0) through
/// 32-bit conversions (one `vcvt` each on an FPU) where they are exact:
/// below 2^31 directly; below 2^39 `x / 2^8` is an integer (`x`'s unit in
/// the last place is at least 2^8 past 2^31), converted and shifted back.
/// Larger values take the library's routine.
#[inline(always)]
fn f32_to_i64(x: f32) -> i64 {
    let a = x.abs();
    if a < 2_147_483_648.0 {
        x as i32 as i64
    } else if a < 549_755_813_888.0 {
        ((x * (1.0 / 256.0)) as i32 as i64) << 8
    } else {
        f32_to_i64_wide(x)
    }
}

#[inline(never)]
fn f32_to_i64_wide(x: f32) -> i64 {
    x as i64
}

impl SetupFloat for f64 {
    const ZERO: Self = 0.0;
    fn of(v: i64) -> Self {
        v as f64
    }
    fn recip(v: i64) -> Self {
        1.0 / v as f64
    }
    fn fixed16(self) -> i64 {
        (self * 65536.0) as i64
    }
}

/// Quadratic colour planes of a [`QuadVertex`] triangle (the RE's fast
/// Phong, seed 001 §IV.2): per channel the quadratic `Q(x, y)` through the
/// three vertex colours `c_k` and the three edge-midpoint colours,
///
/// `Q = Σ c_k w_k + 2 Σ_{p<q} M_pq w_p w_q`, `M_pq = 2 mid_pq - c_p - c_q`,
///
/// with the barycentric weights `w_k = E_k / area2` (the P2 Lagrange form:
/// `Q` is `c_k` at vertex `k` and `mid_pq` at the midpoint of edge `pq`).
///
/// **Setup** (once per triangle and tile): the weights are expanded about
/// the pixel holding vertex 0 — `w_k = W_k + X_k i + Y_k j` — and `Q`'s six
/// coefficients per channel are formed in `f32` (about 150 operations,
/// hardware on a Cortex-M4F; IEEE arithmetic in a fixed order, so every
/// target gets the same bits), then fixed to `i64` with 32 fraction bits
/// of the output scale. About that origin every term is bounded by the
/// triangle's own values (`|X_k i| <= 1` inside), so `f32`'s 24 bits lose
/// nothing visible *when the triangle is well conditioned*. In a thin
/// slanted triangle `X_k i` and `Y_k j` grow far beyond 1 and cancel, and
/// the coefficients' relative rounding (2^-24) is amplified by the square
/// of the conditioning `κ` and the curvature `|M|` ([`SLIVER`]): past
/// `f32`'s budget the same setup runs in `f64`, past that one the triangle
/// is a sliver, drawn Gouraud-shaded (`None`).
///
/// **Rows** restart exactly (`i64`, a closed form per row) at the anchor
/// column — the triangle box's left edge clamped to the screen's, not the
/// tile's — and **pixels**
/// step by second-order forward differences: `c += dc; dc += ddc`, two
/// additions per channel (the seed's "2 additions per pixel"). The
/// per-row restart is the seed's choice for a triangle walker (§IV.2: a
/// three-direction walk would need `Δy` registers at every pixel); advancing
/// from the anchor column in closed form makes the output independent of the
/// tiling. `dc` and `ddc` are rounded to 16 fraction bits, so `k` pixels
/// from the anchor column drift by at most `(k/2 + k²/4) 2^-16` of an
/// output unit: 0.06 LSB at `k = 128`, 0.25 at `k = 256`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct QuadPlane<L> {
    /// Column whose rows restart exactly (the anchor's) and the origin
    /// row: the triangle box's top, above every row drawn.
    x: i64,
    oy: i64,
    /// Per channel, the row polynomials in `j = py - oy >= 0` at column
    /// `x` (output scale, 32 fraction bits, modulo 2^64): value
    /// `r[0] + j (r[1] + j r[2])`, first difference `r[3] + j r[4]`, each
    /// with the bias that rounds it to 16 fraction bits added.
    r: [[i64; 5]; 3],
    /// Second difference per pixel (output scale, 16 fraction bits).
    pub ddc: L,
}

/// Row polynomials `r` in `j` (value `r[0] + j (r[1] + j r[2])`, first
/// difference `r[3] + j r[4]`, 32 fraction bits) re-expanded about row
/// `dj` (`j = j' + dj`), so that every row drawn has `j' >= 0` when `dj`
/// is the box's top (one `umull` and one `mla` a product in
/// [`QuadPlane::at`], not a 64x64-bit one), with the bias that rounds to
/// 16 fraction bits folded into both values and `bias` (16 fraction bits)
/// into the value: the same numbers modulo 2^64.
fn reanchor([r0, r1, r2, r3, r4]: [i64; 5], dj: i64, bias: i32) -> [i64; 5] {
    let (wr, wm) = (i64::wrapping_add, i64::wrapping_mul);
    let half = 1 << 15;
    [
        wr(
            wr(r0, half + ((bias as i64) << 16)),
            wm(dj, wr(r1, wm(dj, r2))),
        ),
        wr(r1, wm(wm(r2, 2), dj)),
        r2,
        wr(wr(r3, half), wm(dj, r4)),
        r4,
    ]
}

impl<L: Lanes> QuadPlane<L> {
    /// A plane that is never stepped (Gouraud triangles).
    pub fn unused() -> Self {
        QuadPlane {
            x: 0,
            oy: 0,
            r: [[0; 5]; 3],
            ddc: L::from_fn(|_| 0),
        }
    }

    /// The planes of `v`, set up as `t` in the precision it needs
    /// ([`SLIVER`]); `None` for a sliver.
    ///
    /// `bias` (output scale, 16 fraction bits) is added to every colour
    /// [`Self::at`] returns: the opaque span's rounding bias, folded into
    /// the planes once instead of added a span.
    pub fn new<F: PixelFormat<Lanes = L>, T: EdgeInt>(
        v: &[QuadVertex; 3],
        t: &TriangleSetup<L, T>,
        bias: i32,
    ) -> Option<Self> {
        match setup_precision(v)? {
            false => Some(Self::set_up::<F, T, f32>(v, t, bias)),
            true => Some(Self::set_up::<F, T, f64>(v, t, bias)),
        }
    }

    #[cfg_attr(target_abi = "eabi", inline(never))]
    fn set_up<F: PixelFormat<Lanes = L>, T: EdgeInt, R: SetupFloat>(
        v: &[QuadVertex; 3],
        t: &TriangleSetup<L, T>,
        bias: i32,
    ) -> Self {
        // Setup order: vertex k is opposite edge e[k].
        let (i1, i2) = if t.swapped { (2, 1) } else { (1, 2) };
        let order = [0, i1, i2];
        let lanes = |c: crate::format::Rgb| F::lanes_from_rgb8([c.r, c.g, c.b]);
        let c = order.map(|k| lanes(v[k].color));
        // mid[k] lies between command vertices k and k + 1.
        let mid = |p: usize, q: usize| {
            let (p, q) = (order[p], order[q]);
            let k = if (p + 1) % 3 == q { p } else { q };
            lanes(v[k].mid)
        };
        let pairs = [(0, 1), (1, 2), (2, 0)];
        let m = pairs.map(|(p, q)| {
            let mq = mid(p, q);
            L::from_fn(|l| 2 * mq.lane(l) - c[p].lane(l) - c[q].lane(l))
        });
        // The anchor column: the triangle box's left edge, or the screen's
        // when the box starts left of it (every tile lies right of both, so
        // the output stays independent of the tiling, and the drift is
        // bounded by the screen's width, not the triangle's).
        let (bx, ay) = (t.bounds.x as i64, t.bounds.y as i64);
        let ax = bx.max(0);
        let (ox, oy) = (
            (v[0].x.to_bits() >> SUBPIXEL_BITS) as i64,
            (v[0].y.to_bits() >> SUBPIXEL_BITS) as i64,
        );
        // The origin: the pixel holding vertex 0, relative to the edges'
        // anchor (the box's top-left pixel).
        let (dx, dy) = (ox - bx, oy - ay);
        let inv = R::recip(t.area2);
        let mut w = [[R::ZERO; 3]; 3];
        for (k, e) in t.e.iter().enumerate() {
            let (a, b, s) = (e.a.to_i64(), e.b.to_i64(), e.step.to_i64());
            w[k] = [
                R::of(b + a * dx + s * dy) * inv,
                R::of(a) * inv,
                R::of(s) * inv,
            ];
        }
        // Lane-independent products of the weights' expansions, per pair:
        // the coefficients of 1, i, j, i², ij, j² in w_p w_q.
        let basis = pairs.map(|(p, q)| {
            let ([wp, xp, yp], [wq, xq, yq]) = (w[p], w[q]);
            [
                wp * wq,
                wp * xq + xp * wq,
                wp * yq + yp * wq,
                xp * xq,
                xp * yq + yp * xq,
                yp * yq,
            ]
        });
        let mut r = [[0i64; 5]; 3];
        let mut dd = [0i32; 3];
        let i = ax - ox;
        let dj = ay - oy;
        for l in 0..L::LEN {
            let mut q = [R::ZERO; 6];
            for (n, qn) in q.iter_mut().enumerate() {
                let mut acc = R::ZERO;
                if n < 3 {
                    for k in 0..3 {
                        acc += R::of(c[k].lane(l) as i64) * w[k][n];
                    }
                }
                for (b, mk) in basis.iter().zip(&m) {
                    acc += R::of(2 * mk.lane(l) as i64) * b[n];
                }
                *qn = acc;
            }
            // Output scale, 32 fraction bits (the lanes carry 16).
            let q = q.map(R::fixed16);
            let [q00, q10, q01, q20, q11, q02] = q;
            // At column x = ax (i = ax - ox), as polynomials in j.
            let wr = i64::wrapping_add;
            let wm = i64::wrapping_mul;
            let [r0, r1, r2, r3, r4] = [
                wr(q00, wm(i, wr(q10, wm(q20, i)))),
                wr(q01, wm(q11, i)),
                q02,
                wr(q10, wm(q20, 2 * i + 1)),
                q11,
            ];
            r[l] = reanchor([r0, r1, r2, r3, r4], dj, bias);
            dd[l] = (wm(q20, 2).wrapping_add(1 << 15) >> 16) as i32;
        }
        QuadPlane {
            x: ax,
            oy: ay,
            r,
            ddc: L::from_fn(|l| dd[l]),
        }
    }

    /// Colour and first difference at pixel `(x0, py)` (output scale, 16
    /// fraction bits): the row's exact restart at the anchor column,
    /// advanced `k = x0 - anchor` forward-difference steps in closed form
    /// (`i32`, exact modulo 2^32, like `k` additions).
    #[inline(always)]
    pub fn at(&self, x0: i64, py: i64) -> (L, L) {
        // `0 <= j < 2^32`: rows lie in the box, whose top is `oy`.
        let j = (py - self.oy) as u32;
        let k = (x0 - self.x) as i32;
        let steps = pairs(k);
        // The bias is in `r`: rounding is the shift alone.
        let round = |v: u64| (v >> 16) as i32;
        let mut c = [(0, 0); 3];
        for (l, out) in c.iter_mut().enumerate().take(L::LEN) {
            let r = self.r[l].map(|v| v as u64);
            // `j r` modulo 2^64 for a 32-bit `j`: one long product and one
            // 32-bit one (on the Cortex-M0 four 16-bit products, not the
            // library's 64x64-bit multiply).
            let mul = |r: u64| {
                wide_mul(j, r as u32).wrapping_add((j.wrapping_mul((r >> 32) as u32) as u64) << 32)
            };
            let q = r[0].wrapping_add(mul(r[1].wrapping_add(mul(r[2]))));
            let d = r[3].wrapping_add(mul(r[4]));
            let (q, d, dd) = (round(q), round(d), self.ddc.lane(l));
            *out = (
                q.wrapping_add(k.wrapping_mul(d))
                    .wrapping_add(steps.wrapping_mul(dd)),
                d.wrapping_add(k.wrapping_mul(dd)),
            );
        }
        (L::from_fn(|l| c[l].0), L::from_fn(|l| c[l].1))
    }
}

#[cfg(test)]
mod tests {
    use super::{alpha_weight, f32_to_i64, reanchor, QuadPlane, SetupFloat};

    /// [`QuadPlane::at`] on planes re-anchored at the box's top equals the
    /// rounded closed form about the original origin row (plus the bias),
    /// for random coefficients (small ones, as real triangles have, and
    /// any 64-bit ones, whose products wrap), origins and rows.
    #[test]
    fn reanchored_rows_equal_the_closed_form() {
        let mut next = crate::numeric::xorshift(11);
        for plane in 0..2000 {
            let mut coef = || {
                let v = next() as i64;
                if plane % 2 == 0 {
                    v >> 20
                } else {
                    v
                }
            };
            let r: [[i64; 5]; 3] = core::array::from_fn(|_| core::array::from_fn(|_| coef()));
            let ddc: [i32; 3] = core::array::from_fn(|_| coef() as i32 >> 8);
            let bias = (next() % 3) as i32 * (1 << 15);
            let x = (next() % 300) as i64 - 50;
            // The origin row (vertex 0's) at or below the box's top.
            let top = (next() % 400) as i64 - 100;
            let oy = top + (next() % 64) as i64;
            let q = QuadPlane {
                x,
                oy: top,
                r: r.map(|r| reanchor(r, top - oy, bias)),
                ddc,
            };
            let round = |v: i64| (v.wrapping_add(1 << 15) >> 16) as i32;
            for _ in 0..20 {
                let (x0, py) = (x + (next() % 240) as i64, top + (next() % 240) as i64);
                let (j, k) = (py - oy, (x0 - x) as i32);
                let steps = crate::numeric::pairs(k);
                let want: [(i32, i32); 3] = core::array::from_fn(|l| {
                    let r = r[l];
                    let v =
                        r[0].wrapping_add(j.wrapping_mul(r[1].wrapping_add(j.wrapping_mul(r[2]))));
                    let (v, d) = (round(v), round(r[3].wrapping_add(j.wrapping_mul(r[4]))));
                    (
                        v.wrapping_add(k.wrapping_mul(d))
                            .wrapping_add(steps.wrapping_mul(ddc[l]))
                            .wrapping_add(bias),
                        d.wrapping_add(k.wrapping_mul(ddc[l])),
                    )
                });
                let (c, dc) = q.at(x0, py);
                assert_eq!(
                    (c, dc),
                    (want.map(|w| w.0), want.map(|w| w.1)),
                    "plane {plane}"
                );
            }
        }
    }

    #[test]
    fn f32_conversions_are_the_language_casts() {
        let edges = [
            0.0f32,
            -0.0,
            0.5,
            -0.99,
            1.0,
            -1.0,
            8388607.5,
            16777216.0,
            -16777217.0,
            2147483648.0,
            // 2^63 and the float just below it, both signs.
            9_223_372_036_854_775_808.0,
            -9_223_372_036_854_775_808.0,
            f32::from_bits(0x5eff_ffff),
            f32::from_bits(0xdeff_ffff),
            1e30,
            -1e30,
            f32::MAX,
            f32::MIN,
            f32::MIN_POSITIVE,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        for x in edges {
            assert_eq!(f32_to_i64(x), x as i64, "{x}");
        }
        // Every exponent, with significands spread over their range.
        let mut b = 0u32;
        loop {
            let x = f32::from_bits(b);
            assert_eq!(f32_to_i64(x), x as i64, "{b:#x}");
            match b.checked_add(4093) {
                Some(n) => b = n,
                None => break,
            }
        }
        let mut v = 1i64;
        for _ in 0..63 {
            for d in [-1, 0, 1] {
                for s in [v + d, -(v + d)] {
                    assert_eq!(<f32 as SetupFloat>::of(s).to_bits(), (s as f32).to_bits());
                }
            }
            v = v.wrapping_mul(2);
        }
    }

    #[test]
    fn alpha_weight_is_the_rounded_quotient() {
        for a in 0..=255u8 {
            let exact = ((a as i64) << 24) as f64 / 255.0;
            assert_eq!(alpha_weight(a) as i64, exact.round() as i64, "{a}");
        }
        assert_eq!(alpha_weight(255), 1 << 24);
        assert_eq!(alpha_weight(0), 0);
    }
}
